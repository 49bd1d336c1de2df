#!/usr/bin/env bash
# Installs what is missing, builds femto and renders the demo scene into out/.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/deps.sh
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release -DFEMTO_TESTS=OFF > /dev/null
cmake --build build -j "$(nproc)"
mkdir -p out
build/bin/femto render scenes/cornell-box/scene.xml -o out/cornell-box "$@"
echo "Pictures: $(pwd)/out/cornell-box.png (preview) and $(pwd)/out/cornell-box.exr (linear HDR)"
