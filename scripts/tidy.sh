#!/usr/bin/env bash
# clang-tidy with the repository's .clang-tidy over the C++ sources (not a CI gate: a full run
# takes long on 2 cores). Needs build/compile_commands.json (scripts/build.sh makes it; the top
# CMakeLists.txt sets CMAKE_EXPORT_COMPILE_COMMANDS). Usage:
#   scripts/tidy.sh                      # every source file of the build (slow)
#   scripts/tidy.sh drivers/src/val.cpp  # these files only
# $ROBOCAL_BUILD_DIR picks another build folder; $JOBS the parallel runs (default: nproc).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=${ROBOCAL_BUILD_DIR:-$root/build}
cd "$root"
if [ ! -f "$build/compile_commands.json" ]; then
  echo "tidy: $build/compile_commands.json missing: run scripts/build.sh first" >&2
  exit 2
fi
if [ $# -gt 0 ]; then
  status=0
  for f in "$@"; do clang-tidy -p "$build" --quiet "$f" || status=1; done
  exit $status
fi
# The project's sources only: not the tests (Catch2's macros), fuzz harnesses or generated files.
run-clang-tidy -quiet -p "$build" -j "${JOBS:-$(nproc)}" \
  '^'"$root"'/(kinematics|solver|formats|planner|drivers|proto|daemon|sim|cli)/'
