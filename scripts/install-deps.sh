#!/usr/bin/env bash
# Installs the Debian packages piezobench needs, and only those that are missing.
# Idempotent: `dpkg -s` decides; apt-get runs only when something is absent.
# Nothing is downloaded at configure or build time; this script is the only
# place the project reaches a package registry.
set -euo pipefail

PACKAGES=(
  build-essential cmake pkg-config
  libeigen3-dev libspectra-dev libfftw3-dev
  libhdf5-dev hdf5-tools
  libusb-1.0-0-dev
  libglfw3-dev libimgui-dev libstb-dev libgl-dev
  libcli11-dev nlohmann-json3-dev libtomlplusplus-dev libssl-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  xvfb xauth libgl1-mesa-dri
  python3-numpy python3-h5py
)

missing=()
for p in "${PACKAGES[@]}"; do
  if ! dpkg -s "$p" >/dev/null 2>&1; then missing+=("$p"); fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#PACKAGES[@]} packages present"
  exit 0
fi

echo "install-deps: installing ${missing[*]}"
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
