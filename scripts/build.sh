#!/usr/bin/env bash
# Configures and builds robocal into build/ (or $ROBOCAL_BUILD_DIR). Extra args go to cmake.
# ROBOCAL_DEBUG_FLAGS: the debug information of the default RelWithDebInfo build (default -g;
# .ci/run sets -g1, line tables only: a quarter less compile time, stack traces keep their lines).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=${ROBOCAL_BUILD_DIR:-$root/build}
cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE="${ROBOCAL_BUILD_TYPE:-RelWithDebInfo}" \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O2 ${ROBOCAL_DEBUG_FLAGS:--g} -DNDEBUG" "$@" >/dev/null
cmake --build "$build" -j "$(nproc)"
