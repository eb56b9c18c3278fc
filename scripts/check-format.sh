#!/usr/bin/env bash
# Fails when a tracked C++ file (*.cpp, *.hpp) differs from what clang-format makes of it with the
# repository's .clang-format. Fast (a few seconds): CI runs it first. Fix with
#   git ls-files '*.cpp' '*.hpp' | xargs clang-format -i
set -euo pipefail
cd "$(dirname "$0")/.."
if ! command -v "${CLANG_FORMAT:-clang-format}" >/dev/null; then
  echo "check-format: ${CLANG_FORMAT:-clang-format} not found (Debian: apt install clang-format)" >&2
  exit 2
fi
if git ls-files -z '*.cpp' '*.hpp' | xargs -0 "${CLANG_FORMAT:-clang-format}" --dry-run --Werror; then
  echo "check-format: every tracked *.cpp and *.hpp is clang-formatted"
else
  echo "check-format: the files above are not clang-formatted; fix with" >&2
  echo "  git ls-files '*.cpp' '*.hpp' | xargs clang-format -i" >&2
  exit 1
fi
