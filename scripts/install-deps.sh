#!/usr/bin/env bash
# Installs the Debian packages piezobench needs, and only those that are missing.
# Idempotent: `dpkg -s` decides; apt-get runs only when something is absent.
# Nothing is downloaded at configure or build time; this script is the only
# place the project reaches a package registry.
#   scripts/install-deps.sh        what the build and `make test` need (gcc)
#   scripts/install-deps.sh fuzz   that, plus the libFuzzer toolchain of `make fuzz`
set -euo pipefail

PACKAGES=(
  build-essential cmake pkg-config
  libeigen3-dev libspectra-dev libfftw3-dev
  libhdf5-dev hdf5-tools
  libusb-1.0-0-dev libcomedi-dev
  libglfw3-dev libimgui-dev libstb-dev libgl-dev libcairo2-dev
  libcli11-dev nlohmann-json3-dev libtomlplusplus-dev libssl-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  xvfb xauth libgl1-mesa-dri
  python3-numpy python3-h5py python3-pyvisa python3-pyvisa-py
  qemu-user
)
# (qemu-user: the test that a build for x86-64-v3 refuses an older CPU with a
# message runs the program on an emulated one: tests/cli/CMakeLists.txt.)
# `make fuzz` only: clang, its compiler-rt (Debian 12 ships libFuzzer and the
# sanitizer runtimes for clang 14 in libclang-rt-14-dev) and llvm (for
# /usr/bin/llvm-symbolizer: symbolized sanitizer reports).
FUZZ_PACKAGES=(clang libclang-rt-14-dev llvm)
if [ "${1:-}" = fuzz ]; then PACKAGES+=("${FUZZ_PACKAGES[@]}"); fi

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
