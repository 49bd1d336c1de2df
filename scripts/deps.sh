#!/usr/bin/env bash
# Installs every Debian package femto needs to build, test and benchmark. Idempotent: does
# nothing when all packages are present.
set -euo pipefail
PACKAGES=(
  g++ cmake ninja-build pkg-config git
  libembree-dev libtbb-dev libpugixml-dev libfmt-dev libcli11-dev libtinyobjloader-dev
  libopenimageio-dev openimageio-tools libopenexr-dev libopencolorio-dev libpng-dev zlib1g-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  clang libclang-rt-14-dev
  libopenmpi-dev openmpi-bin
  python3 python3-numpy python3-scipy python3-matplotlib python3-skimage
  ffmpeg  # optional for users (`femto viz frames --mp4`); here so that cli.viz_mp4 runs
  qemu-user  # the samplers.simd_clone_on_* tests run ldsampler on emulated CPUs
)
missing=()
for p in "${PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  exit 0
fi
echo "deps.sh: installing ${missing[*]}" >&2
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
