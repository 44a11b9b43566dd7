#!/usr/bin/env bash
# Installs the Debian packages crumple needs, only those missing. Needs root (apt-get).
set -euo pipefail
pkgs=(build-essential cmake g++ libeigen3-dev libtbb-dev libbenchmark-dev libbenchmark-tools
      libgtest-dev libtinyobjloader-dev libcli11-dev nlohmann-json3-dev libbullet-dev
      clang-14 libfuzzer-14-dev python3-matplotlib python3-scipy python3-numpy python3-pil python3-tk xvfb xauth)
missing=()
for p in "${pkgs[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "install_deps: installing ${missing[*]}"
  SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  $SUDO apt-get update -q
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -q --no-install-recommends "${missing[@]}"
fi
