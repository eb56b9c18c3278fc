#!/usr/bin/env bash
# The whole test suite again, built with AddressSanitizer and UndefinedBehaviorSanitizer
# (robocald and robocal-cellsim included, so the end-to-end tests run sanitized too).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
"$root/scripts/setup.sh"
export ROBOCAL_BUILD_DIR=${ROBOCAL_ASAN_BUILD_DIR:-$root/build-asan}
"$root/scripts/build.sh" -DROBOCAL_SANITIZE=address
cd "$ROBOCAL_BUILD_DIR"
ctest --output-on-failure -j "$(nproc)" --timeout 900
