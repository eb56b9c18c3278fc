#!/usr/bin/env bash
# The README's test command: installs what is missing, builds, and runs the whole test suite.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
"$root/scripts/setup.sh"
"$root/scripts/build.sh"
cd "${ROBOCAL_BUILD_DIR:-$root/build}"
# Three tests a core: the end-to-end tests mostly wait on the simulated cell's motion (the whole
# plain suite used about 60 s of CPU in 470 s at two tests a core; 171 s at three). ROBOCAL_TEST_JOBS
# sets another number.
ctest --output-on-failure -j "${ROBOCAL_TEST_JOBS:-$((3 * $(nproc)))}" --timeout 600
