#!/usr/bin/env bash
# Builds and runs the solver benchmark (docs/performance.md) in build-bench/ (or
# $ROBOCAL_BENCH_BUILD_DIR). Installs libceres-dev from Debian 12 when it is missing so that the
# run includes the Ceres comparison; if that cannot be installed the benchmark runs without it.
# Arguments go to robocal-bench-solver (e.g. --quick, --repeats 11); extra cmake arguments in
# $ROBOCAL_BENCH_CMAKE_ARGS (e.g. -DROBOCAL_SKIP_MODULES="planner;drivers;proto;daemon").
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=${ROBOCAL_BENCH_BUILD_DIR:-$root/build-bench}

if ! dpkg-query -W -f='${Status}' libceres-dev 2>/dev/null | grep -q "install ok installed"; then
  echo "bench: installing libceres-dev (for the Ceres comparison)"
  sudo_cmd=()
  [ "$(id -u)" -eq 0 ] || sudo_cmd=(sudo)
  if ! { "${sudo_cmd[@]}" apt-get update -qq &&
         DEBIAN_FRONTEND=noninteractive "${sudo_cmd[@]}" apt-get install -y -qq \
           --no-install-recommends libceres-dev; }; then
    echo "bench: could not install libceres-dev; running without the Ceres comparison" >&2
  fi
fi

# shellcheck disable=SC2086  # ROBOCAL_BENCH_CMAKE_ARGS is a list of arguments
cmake -S "$root" -B "$build" -DROBOCAL_BUILD_BENCH=ON -DCMAKE_BUILD_TYPE=Release \
  ${ROBOCAL_BENCH_CMAKE_ARGS:-} >/dev/null
cmake --build "$build" --target robocal-bench-solver -j "$(nproc)"
echo "bench: $(nproc) CPUs, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2- | sed 's/^ //'),"\
     "load average $(cut -d' ' -f1-3 /proc/loadavg)"
exec "$build/bench/robocal-bench-solver" "$@"
