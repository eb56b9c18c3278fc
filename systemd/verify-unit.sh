#!/bin/sh
# systemd-analyze verify on the unit, with ExecStart pointed at the given robocald binary.
set -eu
unit=$1 binary=$2
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
sed "s#/usr/sbin/robocald#$binary#" "$unit" >"$dir/robocald.service"
systemd-analyze verify "$dir/robocald.service"
echo "systemd-analyze verify: ok"
