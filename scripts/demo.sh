#!/usr/bin/env bash
# Installs what is missing, builds femto, renders the demo scene (the transient Cornell box)
# into out/ and makes pictures of it: time-integrated preview, frames + animated GIF, and the
# peak-time image.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/deps.sh
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release -DFEMTO_TESTS=OFF > /dev/null
cmake --build build -j "$(nproc)"
mkdir -p out
build/bin/femto render scenes/cornell-box/scene.xml -o out/cornell-box "$@"
build/bin/femto viz frames out/cornell-box.exr -o out/cornell-box-frames --gif
build/bin/femto viz peak-time out/cornell-box.exr -o out/cornell-box-peak-time.png
cat <<MSG
Pictures in $(pwd)/out:
  cornell-box.png              time-integrated preview (cornell-box_steady.exr: linear HDR)
  cornell-box.exr              the x-y-t cube: the time bins' frames stacked, and depth
  cornell-box-frames/          one PNG per time bin and an animated GIF
  cornell-box-peak-time.png    when each pixel is brightest (thesis ch. 4.5)
MSG
