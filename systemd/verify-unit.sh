#!/bin/sh
# systemd-analyze verify on a unit made from robocald.service.in (the build's, or an installed
# one), with ExecStart pointed at the given robocald binary (the unit's own path may not exist
# yet), then its security exposure, which must not rise. The man page its Documentation= names
# is looked up in MAN_DIR (holding man8/robocald.8) when given and man is installed, else not
# checked.
# Usage: verify-unit.sh UNIT ROBOCALD [MAN_DIR]
set -eu
unit=$1 binary=$2 man_dir=${3:-}
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
grep -q '^ExecStart=[^ ]*/robocald ' "$unit" || { echo "$unit: no ExecStart=.../robocald" >&2; exit 1; }
sed "s#^ExecStart=[^ ]*/robocald #ExecStart=$binary #" "$unit" >"$dir/robocald.service"
if [ -n "$man_dir" ] && command -v man >/dev/null; then
  MANPATH=$man_dir systemd-analyze verify "$dir/robocald.service"
else
  systemd-analyze verify --man=no "$dir/robocald.service"
fi
echo "systemd-analyze verify: ok"
# The hardening must not regress: exposure 1.3 today (docs/security.md); fail above 1.5.
if ! systemd-analyze security --offline=true --threshold=15 "$dir/robocald.service" >"$dir/security"; then
  tail -1 "$dir/security"
  echo "systemd-analyze security: the unit's exposure rose above 1.5" >&2
  exit 1
fi
tail -1 "$dir/security"
