#!/usr/bin/env bash
# Installs the Debian 12 packages vdbmatch needs to build, test and inspect its outputs.
# Safe to run repeatedly; skips apt when everything is already installed.
set -euo pipefail
PACKAGES=(
  build-essential cmake pkg-config
  libopenvdb-dev libtbb-dev libeigen3-dev libopenimageio-dev libboost-iostreams-dev
  libgtest-dev libbenchmark-dev nlohmann-json3-dev libcli11-dev
  libopenvdb-tools python3-openvdb python3-numpy openimageio-tools clang-format time
  python3-dev pybind11-dev python3-pytest python3-tqdm python3-matplotlib
)
missing=()
for p in "${PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#PACKAGES[@]} packages present"
  exit 0
fi
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
echo "install-deps: installing ${missing[*]}"
$SUDO apt-get update -qq
DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq "${missing[@]}"
