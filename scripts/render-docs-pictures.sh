#!/usr/bin/env bash
# Renders every scene in scenes/ and writes the pictures shown in docs/scenes.md and the
# README into docs/images/. Usage: scripts/render-docs-pictures.sh [BUILD_DIR]
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
femto="$build/bin/femto"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
mkdir -p docs/images
for dir in scenes/*/; do
  name=$(basename "$dir")
  start=$(date +%s.%N)
  "$femto" render "$dir/scene.xml" -o "$tmp/$name" -q
  # The wall-clock time at defaults, for the table in scenes/README.md.
  awk -v name="$name" -v start="$start" -v end="$(date +%s.%N)" -v load="$(cut -d' ' -f1 /proc/loadavg)" \
    'BEGIN { printf "%s: %.1f s (load average %s)\n", name, end - start, load }'
  cp "$tmp/$name.png" "docs/images/$name.png"
  if [ -f "$tmp/$name.exr" ] && "$femto" viz peak-time "$tmp/$name.exr" -o "docs/images/$name-peak-time.png" 2>/dev/null; then
    :
  fi
done
# A strip of the demo's frames for the README.
"$femto" viz frames "$tmp/cornell-box.exr" -o "$tmp/frames" > /dev/null
echo "wrote docs/images/"
