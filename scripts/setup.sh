#!/usr/bin/env bash
# Installs what robocal needs to build and test, from Debian 12 packages, when it is missing.
set -euo pipefail
packages=(build-essential cmake pkg-config libeigen3-dev libboost-dev libboost-system-dev
          libserialport-dev libspdlog-dev nlohmann-json3-dev catch2 libsystemd-dev systemd
          liburdfdom-dev liburdfdom-tools python3-pykdl clang libclang-rt-14-dev clang-format jq ccache
          chromium chromium-driver fonts-dejavu-core python3-selenium python3-prometheus-client)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "setup: installing ${missing[*]}"
  sudo_cmd=()
  [ "$(id -u)" -eq 0 ] || sudo_cmd=(sudo)
  "${sudo_cmd[@]}" apt-get update -qq
  DEBIAN_FRONTEND=noninteractive "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi
