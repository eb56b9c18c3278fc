#!/bin/sh
# systemd-analyze verify on the unit, with ExecStart pointed at the given robocald binary.
set -eu
unit=$1 binary=$2
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
sed "s#/usr/sbin/robocald#$binary#" "$unit" >"$dir/robocald.service"
systemd-analyze verify "$dir/robocald.service"
echo "systemd-analyze verify: ok"
# The hardening must not regress: exposure 1.3 today (docs/security.md); fail above 1.5.
if ! systemd-analyze security --offline=true --threshold=15 "$dir/robocald.service" >"$dir/security"; then
  tail -1 "$dir/security"
  echo "systemd-analyze security: the unit's exposure rose above 1.5" >&2
  exit 1
fi
tail -1 "$dir/security"
