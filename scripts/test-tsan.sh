#!/usr/bin/env bash
# The threaded parts again under ThreadSanitizer: robocald (client loop, run thread, solver
# workers), robocal-cellsim and the drivers' async core, with the daemon and driver tests
# (end-to-end runs, kill -9 and resume, faults, protocol abuse) run against them.
# A race anywhere, in a test or in a child daemon/cellsim, fails the script: every process
# writes its reports under $reports, which must stay empty.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
"$root/scripts/setup.sh"
build=${ROBOCAL_TSAN_BUILD_DIR:-$root/build-tsan}
# -O1, as ThreadSanitizer's documentation suggests: a third less compile time than -O2.
cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DROBOCAL_SANITIZE=thread \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 ${ROBOCAL_DEBUG_FLAGS:--g} -DNDEBUG" \
  -DCMAKE_CXX_FLAGS=-Wno-tsan >/dev/null
cmake --build "$build" -j "$(nproc)" --target test_daemon test_drivers robocald robocal-cellsim robocal
reports=$build/tsan-reports
rm -rf "$reports"
mkdir -p "$reports"
export TSAN_OPTIONS="log_path=$reports/tsan second_deadlock_stack=1 ${TSAN_OPTIONS:-}"
cd "$build"
status=0
ctest --output-on-failure -j "$(nproc)" --timeout 900 -R '^(daemon|drivers):' || status=$?
if compgen -G "$reports/tsan*" >/dev/null; then
  echo "ThreadSanitizer reports:"
  for f in "$reports"/tsan*; do
    echo "== $f"
    head -60 "$f"
  done
  status=1
fi
exit $status
