#!/usr/bin/env bash
# Installs femto into a temporary prefix, builds tests/plugin_sdk against the installed SDK
# and renders a scene naming the plugin, found through FEMTO_PLUGIN_PATH; the installed femto
# also reads a PNG texture (its OpenImageIO module, installed beside libfemto_io).
# Usage: run_sdk_test.sh BUILD_DIR SOURCE_DIR WORK_DIR
set -euo pipefail
build=$1 src=$2 work=$3
rm -rf "$work" && mkdir -p "$work"
cmake --install "$build" --prefix "$work/install" > "$work/install.log"
# The installed binaries look for femto's libraries inside the installation only.
checked=$(bash "$src/tests/check_runpath.sh" "$work/install" "$work/install"/bin/* \
  "$work/install"/lib*/*.so* "$work/install"/lib*/femto/plugins/*.so) ||
  { echo "FAIL: $checked"; exit 1; }
[ "$checked" -gt 10 ] || { echo "FAIL: only $checked installed binaries have a RUNPATH"; exit 1; }
cmake -S "$src/tests/plugin_sdk" -B "$work/sdk-build" -G Ninja -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_PREFIX_PATH="$work/install" > "$work/configure.log"
cmake --build "$work/sdk-build" > "$work/build.log"
[ -f "$work/sdk-build/ao.so" ] || { echo "FAIL: ao.so was not built"; exit 1; }
export FEMTO_PLUGIN_PATH="$work/sdk-build"
# The installed conformance matrix on the out-of-tree mini_path integrator.
"$work/sdk-build/conformance" --gtest_brief=1 > "$work/conformance.log" 2>&1 ||
  { cat "$work/conformance.log"; echo "FAIL: mini_path fails the conformance matrix"; exit 1; }
grep -q "PASSED" "$work/conformance.log" || { cat "$work/conformance.log"; echo "FAIL: no conformance test ran"; exit 1; }
femto="$work/install/bin/femto"
"$femto" plugins ao | grep -q "Ambient occlusion" || { echo "FAIL: femto plugins does not list ao"; exit 1; }
"$femto" render "$src/tests/plugin_sdk/scene.xml" -o "$work/ao" -q
stats=$(oiiotool "$work/ao.exr" --printstats)
min=$(echo "$stats" | sed -n 's/.*Stats Min: *\([0-9.e+-]*\).*/\1/p' | head -1)
max=$(echo "$stats" | sed -n 's/.*Stats Max: *\([0-9.e+-]*\).*/\1/p' | head -1)
echo "AO min $min max $max"
# Unoccluded plane far from the sphere: exactly 1. Near the contact: clearly occluded. The
# sphere's top sees the open sky (1) as well.
awk -v a="$min" -v b="$max" 'BEGIN { exit !(b == 1 && a < 0.6) }' || { echo "FAIL: AO range [$min, $max]"; exit 1; }
# The installed libfemto_io finds its OpenImageIO module beside it: a PNG texture needs it.
cat > "$work/texture.xml" <<XML
<scene version="3.0.0">
  <sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/></film></sensor>
  <shape type="rectangle"><bsdf type="diffuse">
    <texture type="bitmap" name="reflectance"><string name="filename" value="$work/ao.png"/></texture>
  </bsdf></shape>
  <emitter type="constant"/>
</scene>
XML
LD_DEBUG=files "$femto" render "$work/texture.xml" -o "$work/texture" -q 2> "$work/texture-ld.txt" ||
  { grep -v '^ *[0-9]*:' "$work/texture-ld.txt"; echo "FAIL: the installed femto cannot read a PNG texture"; exit 1; }
grep -q "file=$work/install/lib[^ ]*/libfemto_oiio.so" "$work/texture-ld.txt" ||
  { echo "FAIL: the OpenImageIO module was not loaded from the installation"; exit 1; }
# Without the plugin path the type is unknown: a clean error, exit 2.
set +e
FEMTO_PLUGIN_PATH= "$femto" render "$src/tests/plugin_sdk/scene.xml" -o "$work/none" -q 2> "$work/err.txt"
code=$?
set -e
[ $code -eq 2 ] && grep -q 'unknown <integrator> plugin "ao"' "$work/err.txt" || { cat "$work/err.txt"; echo "FAIL: expected exit 2"; exit 1; }
echo PASS
