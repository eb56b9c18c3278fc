#!/usr/bin/env bash
# Builds and runs the streaming latency and fan-out benchmark (docs/reliability.md, section 1):
# robocal-cellsim streams the bar at 200 readings/s into a fresh robocald, and 1, 16 and 64
# watchers on loopback (plus a client that never reads) measure each reading's latency. Builds
# robocald, robocal-cellsim and robocal-bench-stream only, in build-stream/ (or
# $ROBOCAL_BENCH_STREAM_BUILD_DIR), RelWithDebInfo. Arguments go to robocal-bench-stream (e.g.
# --duration-s 10, --watchers 64, --json). About 3 minutes with the defaults.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=${ROBOCAL_BENCH_STREAM_BUILD_DIR:-$root/build-stream}
jobs=${ROBOCAL_JOBS:-2}

launcher=()
command -v ccache >/dev/null && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DROBOCAL_BUILD_BENCH=ON \
  "${launcher[@]}" >/dev/null
cmake --build "$build" --target robocal-bench-stream -j "$jobs"
echo "bench-stream: $(nproc) CPUs, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2- | sed 's/^ //'),"\
     "$(uname -r), load average $(cut -d' ' -f1-3 /proc/loadavg)" >&2
exec "$build/bench/robocal-bench-stream" "$@"
