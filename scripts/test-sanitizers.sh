#!/usr/bin/env bash
# The whole test suite again, built with AddressSanitizer and UndefinedBehaviorSanitizer
# (robocald and robocal-cellsim included, so the end-to-end tests run sanitized too).
# Every process writes its sanitizer reports under $reports, so a report from a child daemon
# or cellsim (even one at its exit, after the test's last check) fails the script too.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
"$root/scripts/setup.sh"
export ROBOCAL_BUILD_DIR=${ROBOCAL_ASAN_BUILD_DIR:-$root/build-asan}
# -O1, as the sanitizers' documentation suggests: faster to build than -O2 and still fast to run.
"$root/scripts/build.sh" -DROBOCAL_SANITIZE=address \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 ${ROBOCAL_DEBUG_FLAGS:--g} -DNDEBUG"
reports=$ROBOCAL_BUILD_DIR/sanitizer-reports
rm -rf "$reports"
mkdir -p "$reports"
export ASAN_OPTIONS="log_path=$reports/asan ${ASAN_OPTIONS:-}"
export UBSAN_OPTIONS="log_path=$reports/ubsan print_stacktrace=1 ${UBSAN_OPTIONS:-}"
cd "$ROBOCAL_BUILD_DIR"
status=0
# One test more than the cores: sanitized processes use far more of the CPU than plain ones, and
# the end-to-end tests keep time (ROBOCAL_TEST_JOBS sets another number).
ctest --output-on-failure -j "${ROBOCAL_TEST_JOBS:-$(($(nproc) + 1))}" --timeout 900 || status=$?
if compgen -G "$reports/*" >/dev/null; then
  echo "Sanitizer reports:"
  for f in "$reports"/*; do
    echo "== $f"
    head -60 "$f"
  done
  status=1
fi
exit $status
