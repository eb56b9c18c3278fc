#!/usr/bin/env bash
# The crash-state explorer's full form (issue 21 item 6; docs/reliability.md, "Crash states"): a
# short run through robocald and robocal-cellsim is recorded (every durable file operation of its
# data folder), then robocald is started on every state a power cut may leave, and each
# interrupted run resumed to its end, checked (tests/daemon/test_crash_states.cpp; the plain test
# suite tries eight of them). Prints how many states were tried. About 9 s a state.
#   scripts/crash-states.sh            (installs and builds what it needs first)
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
"$root/scripts/setup.sh"
"$root/scripts/build.sh"
build=${ROBOCAL_BUILD_DIR:-$root/build}
ROBOCAL_CRASH_STATES=all ROBOCAL_BIN="$build/cli" "$build/tests/test_daemon" "[crash]" \
  2> >(grep -v '^\[20' >&2)
