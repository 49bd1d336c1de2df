#!/usr/bin/env bash
# One end-to-end case of the femto CLI: cli_test.sh CASE FEMTO_BINARY SOURCE_DIR WORK_DIR
set -uo pipefail
case_name=$1 femto=$2 src=$3 work=$4 shadow=${5:-}  # shadow: the test plugins named "path"
rm -rf "$work" && mkdir -p "$work" && cd "$work" || exit 1
scene="$src/scenes/cornell-box/scene.xml"
compat="$src/../shared/compat-scenes"

fail() { echo "FAIL [$case_name]: $*" >&2; exit 1; }
# The compat cases read real Mitsuba scenes kept beside the repository (CI has them); without
# the folder they skip (exit 77, ctest's SKIP_RETURN_CODE) and say what is missing.
need_compat() {
  [ -d "$compat" ] && return 0
  echo "SKIP [$case_name]: $compat not found (real Mitsuba scenes kept beside the repository)"
  exit 77
}
# expect_exit CODE PATTERN -- command...: runs it, checks the exit code and that stderr matches.
expect_exit() {
  local code=$1 pattern=$2; shift 3
  "$@" > stdout.txt 2> stderr.txt
  local got=$?
  [ "$got" -eq "$code" ] || { cat stderr.txt >&2; fail "exit code $got, expected $code: $*"; }
  grep -Eq -- "$pattern" stderr.txt || { cat stderr.txt >&2; fail "stderr does not match /$pattern/"; }
}
# "min max" of an image's first channel.
pixel_range() {
  oiiotool "$1" --printstats | sed -n 's/.*Stats Min: *\([0-9.e+-]*\).*/\1/p;s/.*Stats Max: *\([0-9.e+-]*\).*/\1/p' | head -2 | tr '\n' ' '
}
# Waits until process $1 has installed its SIGINT handler (bit 2 of SigCgt) or has ended.
wait_for_sigint_handler() {
  local cgt
  for _ in $(seq 600); do
    cgt=$(sed -n 's/^SigCgt:\t//p' /proc/$1/status 2>/dev/null) || return
    [ -n "$cgt" ] && (( (0x$cgt >> 1) & 1 )) && return
    sleep 0.1
  done
}
exr_attr() { iinfo -v "$1" | sed -n "s/^ *$2: *\"\{0,1\}\([^\"]*\)\"\{0,1\}$/\1/p"; }
# The mean of a PNG's 8-bit values over pixels and channels, rounded down.
png_mean() { iinfo --stats "$1" | awk '/Stats Avg/ { printf "%d", ($3 + $4 + $5) / 3 }'; }
no_temp_files() { ! ls -A "$1" | grep -q '\.tmp'; }
# A small streak-film scene (rows 5 and 12 of 32x24, 30 bins) on stdout.
streak_scene() {
  cat <<'XML'
<scene version="3.0.0">
  <integrator type="transient_path"/>
  <sensor type="orthographic">
    <transform name="to_world"><scale x="2" y="2"/><lookat origin="0,0,5" target="0,0,0" up="0,1,0"/></transform>
    <sampler type="independent"><integer name="sample_count" value="4"/></sampler>
    <film type="streak">
      <integer name="width" value="32"/><integer name="height" value="24"/>
      <string name="rows" value="5, 12"/>
      <float name="start" value="6.5"/><float name="bin_width" value="0.1"/><integer name="bins" value="30"/>
    </film>
  </sensor>
  <shape type="rectangle"><transform name="to_world"><scale value="3"/></transform></shape>
  <emitter type="point"><point name="position" x="0" y="0" z="2"/><rgb name="intensity" value="5"/></emitter>
</scene>
XML
}

case "$case_name" in
version)
  "$femto" --version > version.txt || fail "exit code"
  head -1 version.txt | grep -Eq '^femto [0-9]+\.[0-9]+\.[0-9]+$' || fail "bad --version"
  sed -n 2p version.txt | grep -Eq '^distributed rendering: (yes|no) \(' || fail "no MPI line";;
plugins_list)
  "$femto" plugins > list.txt || fail "exit code"
  for k in integrator sensor film rfilter sampler shape bsdf emitter texture; do
    grep -q "^$k:" list.txt || fail "kind $k missing"; done
  grep -q "  path " list.txt || fail "path integrator missing";;
plugins_schema)
  "$femto" plugins roughconductor > s.txt || fail "exit code"
  grep -q "alpha" s.txt && grep -q "distribution" s.txt || fail "schema incomplete";;
plugins_unknown)
  expect_exit 2 '^femto: error: no plugin named "nosuch" \(`femto plugins` lists them\)' -- "$femto" plugins nosuch
  expect_exit 2 '^femto: error: no plugin named "transient_pth"; did you mean "transient_path"\?' -- "$femto" plugins transient_pth;;
unknown_command)
  expect_exit 2 '^femto: error: unknown command "rendr"; did you mean "render"\? \(commands: render, plugins, viz, bench, btf\)$' -- "$femto" rendr x.xml
  expect_exit 2 '^femto: error: unknown command "scene\.xml" \(commands: render, plugins, viz, bench, btf\)$' -- "$femto" scene.xml
  expect_exit 2 '^femto: error: `femto` needs a command \(commands: render, plugins, viz, bench, btf\)$' -- "$femto"
  expect_exit 2 '^femto: error: unknown viz command "peaktime"; did you mean "peak-time"\? \(viz commands: frames, peak-time, rainbow, streak, unwarp\)$' -- "$femto" viz peaktime x.exr -o p.png
  expect_exit 2 '^femto: error: `femto viz` needs a viz command \(viz commands: frames, peak-time, rainbow, streak, unwarp\)$' -- "$femto" viz
  # Help still works without a command.
  "$femto" --help | grep -q 'Subcommands' || fail "femto --help"
  "$femto" viz --help | grep -q 'peak-time' || fail "femto viz --help";;
plugin_docs_fresh)
  "$femto" plugins --markdown > plugins.md || fail "exit code"
  diff -u "$src/docs/plugins.md" plugins.md > diff.txt ||
    { head -40 diff.txt >&2; fail "docs/plugins.md is stale: run scripts/gen-plugin-docs.sh"; };;
bench_example)
  # The shipped example study: 18 runs and their report; a second call resumes (no new rows).
  "$femto" bench "$src/bench/experiments/fog-point-connections.xml" -o out/b -q || fail "exit code"
  [ "$(wc -l < out/b/results.csv)" = 19 ] || fail "results.csv has $(wc -l < out/b/results.csv) lines"
  for f in report.md plot.svg frames.csv; do [ -s "out/b/$f" ] || fail "$f missing"; done
  grep -q '^| equiangular | 9 (9 fitted) | ' out/b/report.md || fail "report row"
  "$femto" bench "$src/bench/experiments/fog-point-connections.xml" -o out/b -q || fail "resume"
  [ "$(wc -l < out/b/results.csv)" = 19 ] || fail "resuming added rows";;
bench_sigint)
  # Ctrl-C stops a study after the run in progress, keeps the finished rows and says so; the
  # same command resumes it to the end.
  experiment="$src/bench/experiments/fog-point-connections.xml"
  "$femto" bench "$experiment" -o out/b 2> err.txt &
  pid=$!
  for _ in $(seq 600); do
    [ -f out/b/results.csv ] && [ "$(wc -l < out/b/results.csv)" -ge 3 ] && break
    sleep 0.1
  done
  [ -f out/b/results.csv ] && [ "$(wc -l < out/b/results.csv)" -ge 3 ] ||
    fail "no two runs recorded after 60 s"
  kill -INT $pid
  wait $pid; code=$?
  [ "$code" -eq 130 ] || { cat err.txt >&2; fail "exit code $code after SIGINT, expected 130"; }
  grep -q 'the study stops after the runs in progress and keeps every finished run' err.txt ||
    { cat err.txt >&2; fail "no message"; }
  rows=$(wc -l < out/b/results.csv)
  [ "$rows" -ge 3 ] && [ "$rows" -lt 19 ] || fail "results.csv has $rows lines after the stop"
  "$femto" bench "$experiment" -o out/b -q || fail "resume"
  [ "$(wc -l < out/b/results.csv)" = 19 ] || fail "the resumed study has $(wc -l < out/b/results.csv) lines";;
bench_experiments_load)
  # Every shipped experiment's (scene, variant) pairs load and pass their integrator's checks.
  # The displaced sphere's mesh is generated, not shipped: experiments that use it are skipped
  # (and say so) unless it has been made.
  mesh="$src/bench/experiments/scenes/displaced_sphere.ply"
  experiments=()
  for e in "$src"/bench/experiments/*.xml; do
    if grep -q 'displaced-sphere' "$e" && [ ! -e "$mesh" ]; then
      echo "not checked: $(basename "$e") (needs python3 bench/experiments/scenes/make_displaced_sphere.py)"
    else
      experiments+=("$e")
    fi
  done
  [ "${#experiments[@]}" -ge 20 ] || fail "only ${#experiments[@]} experiments to check"
  expect_exit 0 'pairs load and can render' -- "$femto" bench --check "${experiments[@]}"
  [ "$(grep -c 'pairs load and can render' stderr.txt)" -eq "${#experiments[@]}" ] ||
    fail "not every experiment was checked"
  expect_exit 2 'one experiment at a time' -- "$femto" bench "${experiments[0]}" "${experiments[1]}"
  # A variant that cannot render is named before anything renders or is written.
  cat > b.xml <<EOF
<experiment name="x">
<scene file="$src/scenes/cornell-box/scene.xml"><define name="res" value="16"/></scene>
<variant name="ok"/>
<variant name="broken">
<define name="integrator" value="transient_beams"/>
</variant>
<budgets spp="1"/>
<reference variant="ok" spp="4"/>
</experiment>
EOF
  expect_exit 2 'b\.xml:4:1: variant "broken" cannot render scene "cornell-box": .*no shape bounds a <medium>' -- "$femto" bench b.xml -o out/b
  [ ! -e out/b ] || fail "the study wrote before its check"
  expect_exit 2 'variant "broken" cannot render' -- "$femto" bench --check b.xml;;
bench_bad_input)
  printf '<experiment>\n<scenery/>\n</experiment>\n' > e.xml
  expect_exit 2 'e\.xml:2:1: unknown element <scenery> in <experiment>' -- "$femto" bench e.xml
  expect_exit 2 'experiment file "none\.xml" cannot be read' -- "$femto" bench none.xml
  # A folder where the study keeps a file of its own: refused before anything renders.
  printf '<experiment name="t">\n<scene file="%s"><define name="res" value="8"/><define name="bins" value="8"/></scene>\n<variant name="a"/>\n<budgets spp="1"/>\n</experiment>\n' "$scene" > ok.xml
  mkdir -p res/results.csv
  expect_exit 2 '^femto: error: "res/results\.csv" is not a file: the study writes its results\.csv there$' -- "$femto" bench ok.xml -o res -q
  [ -z "$(ls -A res/cache 2>/dev/null)" ] || fail "something was rendered"
  # --check finds a <pixel> outside the film and a reference file of another shape (a study
  # found them only after rendering its reference or its first run).
  sed 's|<budgets spp="1"/>|<budgets spp="1"/><reference variant="a" spp="2"/><pixel name="p" x="100" y="0"/>|' ok.xml > pixel.xml
  expect_exit 2 '^femto: error: pixel\.xml:4:[0-9]+: pixel \(100, 0\) is outside scene "[^"]*".s 8 x 8 film' -- "$femto" bench pixel.xml --check
  "$femto" render "$scene" -D res=4 -D bins=8 --spp 1 --npy -o small -q || fail "render failed"
  sed 's|<budgets spp="1"/>|<budgets spp="1"/><reference file="small.npy"/>|' ok.xml > ref.xml
  expect_exit 2 '^femto: error: ref\.xml:4:[0-9]+: reference "[^"]*small\.npy" is \[4, 4, 8\] \(H, W, T\), but scene "[^"]*" renders \[8, 8, 8\]' -- "$femto" bench ref.xml --check;;
render_demo)
  "$femto" render "$scene" -o out/demo -D spp=4 -D res=64 -q || fail "render failed"
  [ -s out/demo.exr ] && [ -s out/demo.png ] || fail "outputs missing"
  [ "$(exr_attr out/demo.exr femto:samples)" = 4 ] || fail "samples attribute"
  [ "$(exr_attr out/demo.exr femto:integrator)" = transient_path ] || fail "integrator attribute"
  [ "$(exr_attr out/demo.exr femto:bins)" = 256 ] || fail "bins attribute"
  for kind in nan infinite negative; do
    [ "$(exr_attr out/demo.exr femto:rejected_$kind)" = 0 ] || fail "rejected_$kind attribute"
  done
  [ -s out/demo_steady.exr ] || fail "steady image missing"
  no_temp_files out || fail "temporary files left";;
bad_xml)
  printf '<scene version="3.0.0">\n  <shape type="rectangle">\n</scene>\n' > bad.xml
  expect_exit 2 'bad\.xml:3:[0-9]+: malformed XML' -- "$femto" render bad.xml -o out/x -q
  [ ! -e out/x.exr ] || fail "output written";;
unknown_plugin)
  printf '<scene version="3.0.0">\n<sensor type="perspective"/>\n<shape type="spehre"/>\n</scene>\n' > u.xml
  expect_exit 2 'u\.xml:3:1: unknown <shape> plugin "spehre" \(did you mean "sphere"\?\)' -- "$femto" render u.xml -o out/u -q
  # An empty type is named as such, not "corrected" to a short name such as "hg".
  printf '<scene version="3.0.0">\n<sensor type="perspective"/>\n<shape type="sphere">\n<bsdf type=""/>\n</shape>\n</scene>\n' > e.xml
  expect_exit 2 'e\.xml:4:1: the <bsdf> type is empty' -- "$femto" render e.xml -o out/e -q
  ! grep -q 'did you mean' stderr.txt || fail "an empty type got a suggestion";;
missing_scene)
  expect_exit 2 'does not exist' -- "$femto" render nothere.xml -q;;
missing_mesh)
  printf '<scene version="3.0.0">\n<sensor type="perspective"/>\n<shape type="obj">\n<string name="filename" value="gone.obj"/>\n</shape>\n</scene>\n' > m.xml
  expect_exit 2 'm\.xml:4:1: .*gone\.obj' -- "$femto" render m.xml -o out/m -q
  # A link that cannot be followed is not "not found": the message says why it cannot be read.
  ln -s loop.obj loop.obj
  ln -s nowhere.obj dangling.obj
  sed 's/gone\.obj/loop.obj/' m.xml > loop.xml
  expect_exit 2 'loop\.xml:4:1: cannot open "loop\.obj": Too many levels of symbolic links' -- "$femto" render loop.xml -o out/m -q
  sed 's/gone\.obj/dangling.obj/' m.xml > dangling.xml
  expect_exit 2 'dangling\.xml:4:1: cannot open "dangling\.obj": it is a symbolic link to a file that does not exist' -- "$femto" render dangling.xml -o out/m -q;;
unwritable_output)
  touch afile
  expect_exit 2 'cannot create the output folder' -- "$femto" render "$scene" -o afile/sub/x -q
  mkdir ro && chmod 555 ro
  if [ "$(id -u)" -ne 0 ]; then
    expect_exit 2 'not writable' -- "$femto" render "$scene" -o ro/x -q
  fi
  ls -A ro | grep -q . && fail "something was written";
  true;;
bad_output_folder)
  # Output names that are folders are refused before rendering, with a message that says so.
  mkdir -p folder out/taken.exr
  expect_exit 2 '^femto: error: output "folder" is a folder: name a file in it' -- "$femto" render "$scene" -o folder -q
  expect_exit 2 '^femto: error: cannot write "out/taken\.exr": a folder has that name' -- "$femto" render "$scene" -o out/taken -q
  ls -A folder | grep -q . && fail "something was written";
  true;;
bad_far_scene)
  # A camera at 2e18 made Embree abort (exit 134); beyond 1e9 scene units femto refuses.
  sed -e 's|<lookat origin="0, 0, 3.9"|<translate x="2e18"/><lookat origin="0, 0, 3.9"|' \
      -e "s|filename=\"room.xml\"|filename=\"$(dirname "$scene")/room.xml\"|" "$scene" > far.xml
  expect_exit 2 'far\.xml:[0-9]+:[0-9]+: "perspective": to_world.s origin lies at \(-?2e\+18, 0, 3\.9\), beyond femto.s limit' -- "$femto" render far.xml -o out/far -q
  [ ! -e out/far.exr ] || fail "output written";;
bad_texture)
  # A corrupt PNG texture: one located line from femto, none from libpng.
  printf '\211PNG\r\n\032\n\0\0\0\015IHDR\0\0\0\002\0\0\0\002\010\002\0\0\0BAD!' > corrupt.png
  printf '<scene version="3.0.0">\n<sensor type="perspective"/>\n<shape type="rectangle"><bsdf type="diffuse">\n<texture type="bitmap" name="reflectance"><string name="filename" value="corrupt.png"/></texture></bsdf></shape>\n</scene>\n' > t.xml
  expect_exit 2 '^femto: error: t\.xml:4:[0-9]+: "bitmap": cannot read image "[^"]*corrupt\.png": ' -- "$femto" render t.xml -o out/t -q
  [ "$(wc -l < stderr.txt)" -eq 1 ] || { cat stderr.txt >&2; fail "more than one line on stderr"; };;
image_libraries)
  # A render that reads no image, or only EXR images, writes its EXR and PNG files without
  # OpenImageIO (whose ~260 libraries take ~0.4 s to load); a PNG texture loads it on demand
  # (LD_DEBUG: the loader names every library it opens).
  LD_DEBUG=files "$femto" render "$scene" -o out/plain -D spp=1 -D res=16 -q 2> plain.txt ||
    { cat plain.txt >&2; fail "render failed"; }
  [ -s out/plain.exr ] && [ -s out/plain.png ] || fail "outputs missing"
  grep -q 'file=libfemto_io' plain.txt || fail "LD_DEBUG printed nothing: cannot tell"
  ! grep -q 'libOpenImageIO' plain.txt || fail "OpenImageIO loaded by a render that reads no image"
  for texture in plain_steady.exr plain.png; do
    printf '<scene version="3.0.0">\n<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/></film></sensor>\n<shape type="rectangle"><bsdf type="diffuse">\n<texture type="bitmap" name="reflectance"><string name="filename" value="out/%s"/></texture></bsdf></shape>\n<emitter type="constant"/>\n</scene>\n' "$texture" > tex.xml
    LD_DEBUG=files "$femto" render tex.xml -o out/tex -q 2> tex.txt || { cat tex.txt >&2; fail "render with $texture failed"; }
    [ -s out/tex.png ] || fail "render with $texture: no PNG"
    if [ "$texture" = plain.png ]; then
      grep -q 'libOpenImageIO' tex.txt || fail "OpenImageIO not loaded for a PNG texture"
    else
      ! grep -q 'libOpenImageIO' tex.txt || fail "OpenImageIO loaded for an EXR texture"
    fi
  done
  # An EXR whose header OpenEXR refuses: OpenEXR's message (exit 2), OpenImageIO not loaded.
  head -c 60 out/plain_steady.exr > out/cut.exr
  sed 's|out/plain.png|out/cut.exr|' tex.xml > cut.xml
  LD_DEBUG=files "$femto" render cut.xml -o out/cut -q 2> cut.txt; code=$?
  [ "$code" -eq 2 ] || { cat cut.txt >&2; fail "a cut EXR texture: exit $code, expected 2"; }
  grep -q '^femto: error: cut\.xml:4:[0-9]*: "bitmap": cannot read image "[^"]*cut\.exr": ' cut.txt ||
    { grep -v '^ *[0-9]*:' cut.txt >&2; fail "a cut EXR texture: no located message"; }
  ! grep -q 'libOpenImageIO' cut.txt || fail "OpenImageIO loaded for an EXR OpenEXR refuses";;
bad_film_size)
  # A cube that fits the fixed limits but not the machine: refused when the scene loads, with
  # the film's location (not an allocation failure or the OOM killer), and nothing written.
  ram_kb=$(sed -n 's/^MemTotal: *\([0-9]*\) kB$/\1/p' /proc/meminfo)
  bins=$(( ram_kb * 1024 * 8 / 10 / (1024 * 1024 * 12) + 1 ))  # 4/5 of memory at 1024x1024
  if [ -z "$ram_kb" ] || [ $(( bins * 1024 * 1024 * 12 )) -gt $(( 1 << 36 )) ]; then
    echo "SKIP [$case_name]: this machine's memory is beyond the film's fixed 64 GiB limit"
    exit 77
  fi
  expect_exit 2 '^femto: error: .*cornell-box/scene\.xml:[0-9]+:[0-9]+: "transient": the cube and its AOVs would need [0-9.]+ GiB, more than 3/4 of (this machine.s memory|this process.s memory limit \(control group\)), [0-9.]+ GiB$' \
    -- "$femto" render "$scene" -D res=1024 -D bins=$bins -o out/huge -q
  # The streak film's rows likewise: 24 rows of 8192 pixels.
  rows=$(seq -s, 0 23)
  streak_scene | sed -e 's|value="32"/><integer name="height"|value="8192"/><integer name="height"|' \
    -e "s|value=\"5, 12\"|value=\"$rows\"|" -e "s|name=\"bins\" value=\"30\"|name=\"bins\" value=\"$((bins * 1024 * 1024 / (24 * 8192) + 1))\"|" > streak.xml
  expect_exit 2 '^femto: error: streak\.xml:[0-9]+:[0-9]+: "streak": the streak images and their copies would need [0-9.]+ GiB, more than 3/4 of (this machine.s memory|this process.s memory limit)' \
    -- "$femto" render streak.xml -o out/streak -q
  [ -z "$(ls -A out 2>/dev/null)" ] || fail "something was written";;
runpath)
  # No build-tree binary looks for libraries in the current folder (an empty RUNPATH entry:
  # CMake's padding for an in-place edit at install made them) or outside the build folder.
  command -v readelf >/dev/null || { echo "SKIP [$case_name]: readelf not found"; exit 77; }
  build_dir=$(dirname "$(dirname "$femto")")
  checked=$(bash "$src/tests/check_runpath.sh" "$build_dir" "$build_dir"/bin/* "$build_dir"/lib/*.so \
    "$build_dir"/plugins/*.so) || fail "$checked"
  [ "$checked" -gt 10 ] || fail "only $checked binaries with a RUNPATH found under $build_dir";;
bad_volume)
  # Media volumes: a missing .vol, a truncated one, an unknown volume type, a negative constant;
  # each one located line and exit code 2, no image written.
  head='<scene version="3.0.0">\n<sensor type="perspective"/>\n<shape type="cube"><bsdf type="null"/>\n<medium type="heterogeneous" name="interior">'
  printf "$head"'<volume name="sigma_t" type="gridvolume"><string name="filename" value="none.vol"/></volume></medium></shape>\n</scene>\n' > v1.xml
  expect_exit 2 '^femto: error: v1\.xml:4:[0-9]+: file "none\.vol" not found' -- "$femto" render v1.xml -o out/v1 -q
  printf 'VOL\003' > short.vol
  printf "$head"'<volume name="sigma_t" type="gridvolume"><string name="filename" value="short.vol"/></volume></medium></shape>\n</scene>\n' > v2.xml
  expect_exit 2 '^femto: error: v2\.xml:4:[0-9]+: "gridvolume": grid volume "[^"]*short\.vol": truncated header' -- "$femto" render v2.xml -o out/v2 -q
  printf "$head"'<volume name="sigma_t" type="voxels"/></medium></shape>\n</scene>\n' > v3.xml
  expect_exit 2 '^femto: error: v3\.xml:4:[0-9]+: unknown <volume> plugin "voxels"' -- "$femto" render v3.xml -o out/v3 -q
  printf "$head"'<volume name="sigma_t" type="constvolume"><float name="value" value="-2"/></volume></medium></shape>\n</scene>\n' > v4.xml
  expect_exit 2 '^femto: error: v4\.xml:4:[0-9]+: "constvolume": a constvolume.s value must be >= 0' -- "$femto" render v4.xml -o out/v4 -q
  [ "$(wc -l < stderr.txt)" -eq 1 ] || { cat stderr.txt >&2; fail "more than one line on stderr"; }
  [ ! -e out/v4.exr ] || fail "an output was written"
  # A medium so dense that a free flight rounds to no move: paths could never end (this hung).
  printf '<scene version="3.0.0">\n<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="4"/><integer name="height" value="4"/></film>\n<medium type="homogeneous"><float name="sigma_t" value="1e30"/><float name="albedo" value="1"/></medium></sensor>\n<shape type="sphere"/><emitter type="point"/>\n</scene>\n' > v5.xml
  expect_exit 2 '^femto: error: v5\.xml:3:[0-9]+: "homogeneous": its extinction reaches 1e\+30 per scene unit, a mean free path of 1e-30: below the spacing of positions where it lies \(1\.19209e-07, up to 1 scene units from the origin\)' -- timeout 60 "$femto" render v5.xml -o out/v5 -q
  [ ! -e out/v5.exr ] || fail "an output was written"
  # A dense medium inside a small sphere is judged where it lies, not by a vast floor far away.
  printf '<scene version="3.0.0">\n<sensor type="perspective"><transform name="to_world"><lookat origin="0, 0, 4" target="0, 0, 0" up="0, 1, 0"/></transform><film type="hdrfilm"><integer name="width" value="4"/><integer name="height" value="4"/></film></sensor>\n<shape type="sphere"><bsdf type="null"/><medium type="homogeneous" name="interior"><float name="sigma_t" value="2000"/><float name="albedo" value="0.5"/></medium></shape>\n<shape type="rectangle"><transform name="to_world"><scale value="10000"/><translate z="-2"/></transform></shape><emitter type="point"><point name="position" x="0" y="0" z="3"/></emitter>\n</scene>\n' > v7.xml
  timeout 60 "$femto" render v7.xml -o out/v7 -q 2> v7.txt || { cat v7.txt >&2; fail "a dense sphere beside a large floor was refused"; }
  sed 's/"1e30"/"1e20"\/><float name="scale" value="1e20"/' v5.xml > v6.xml
  expect_exit 2 '^femto: error: v6\.xml:3:[0-9]+: "homogeneous": sigma_t times scale is 1e\+40, beyond the float range' -- "$femto" render v6.xml -o out/v6 -q
  # A scale beyond the float range is fine on a zero coefficient (it was cast to float first).
  sed 's/"1e30"/"0"\/><float name="scale" value="1e39"/' v5.xml > v8.xml
  "$femto" render v8.xml -o out/v8 -q 2> v8.txt || { cat v8.txt >&2; fail "sigma_t 0 with scale 1e39 was refused"; };;
exr_truncated)
  # EXRs cut short after their headers, which declare 2^26 pixels (768 MiB as float): refused
  # before the image is allocated. The reader once allocated and decoded all of it (3 GB and
  # 10 s for 2^28 pixels) before failing; under this memory limit that ended in bad_alloc.
  command -v oiiotool >/dev/null || { echo "SKIP [$case_name]: oiiotool not found"; exit 77; }
  oiiotool --create 16384x4096 3 -d half --compression zip -o big.exr || fail "oiiotool --create"
  head -c 20000 big.exr > cut.exr
  printf '<scene version="3.0.0">\n<sensor type="perspective"/>\n<shape type="rectangle"><bsdf type="diffuse">\n<texture type="bitmap" name="reflectance"><string name="filename" value="cut.exr"/></texture></bsdf></shape>\n</scene>\n' > t.xml
  (ulimit -v 500000; expect_exit 2 '^femto: error: t\.xml:4:[0-9]+: "bitmap": cannot read image "cut\.exr": .*Early end of file' -- "$femto" render t.xml -o out/t -q) || exit 1
  oiiotool --create 16384x4096 3 -d half --compression zip --attrib femto:layout "streak image: rows are time bins" --attrib femto:row 0 -o streak.exr ||
    fail "oiiotool --create (streak)"
  head -c 20000 streak.exr > cut_streak.exr
  (ulimit -v 500000; expect_exit 2 '^femto: error: cannot read streak image "cut_streak\.exr": .*Early end of file' -- "$femto" viz unwarp cut_streak.exr -o out/u.exr --to world -q) || exit 1
  [ -z "$(ls -A out 2>/dev/null)" ] || fail "something was written";;
bad_spp)
  expect_exit 2 '^femto: error: --spp: expected a whole number from 1 to 4294967295, got "0"' -- "$femto" render "$scene" --spp 0 -q
  expect_exit 2 '^femto: error: --spp: expected a whole number .*got "-3"' -- "$femto" render "$scene" --spp -3 -q
  expect_exit 2 'spp' -- "$femto" render "$scene" --spp abc -q
  expect_exit 2 '^femto: error: --seed: expected a whole number from 0 to 18446744073709551615, got "-1"' -- "$femto" render "$scene" --seed -1 -q
  expect_exit 2 'sample_count' -- "$femto" render "$scene" -D spp=0 -o out/s -q;;
bad_threads)
  expect_exit 2 '^femto: error: --threads: expected a whole number from 1 to 4096, got "0"' -- "$femto" render "$scene" --threads 0 -q;;
output_extension)
  # -o name.exr names the outputs name.exr, name.png, ... (not name.exr.exr).
  "$femto" render "$scene" -o out/named.exr -D spp=1 -D res=8 -q || fail "render failed"
  [ -f out/named.exr ] && [ -f out/named.png ] || fail "expected out/named.exr and out/named.png"
  [ ! -e out/named.exr.exr ] || fail "wrote out/named.exr.exr";;
bad_define)
  expect_exit 2 'expected name=value' -- "$femto" render "$scene" -D novalue -q
  expect_exit 2 'width must be in' -- "$femto" render "$scene" -D res=-1 -o out/d -q
  expect_exit 2 'scene\.xml:[0-9]+:[0-9]+: integer "width": "nan" is not an integer' -- "$femto" render "$scene" -D res=nan -o out/d -q
  # A name given twice: neither value silently wins (the loser would never be checked).
  expect_exit 2 '^femto: error: -D res is given twice \("8" and "-1"\)$' -- "$femto" render "$scene" -D res=8 -D res=-1 -o out/d -q
  [ ! -e out/d.exr ] || fail "output written";;
unused_define)
  # A -D the scene does not use is a typo until proven otherwise: an error naming the scene's
  # parameters and the closest one; --lenient makes it a warning and renders.
  expect_exit 2 '^femto: error: -D sppp=4: .*scene\.xml has no parameter "sppp" \(did you mean "spp"\?\); its parameters \(<default> names and \$names\): bins, integrator, max_depth, res, sampler, spp, tfilter$' -- "$femto" render "$scene" -D sppp=4 -o out/u -q
  [ ! -e out/u.exr ] || fail "output written"
  expect_exit 0 '^warning: -D sppp=4: .* -- ignored \(--lenient\)$' -- "$femto" render "$scene" -D sppp=4 -D spp=1 -D res=8 -D bins=4 --lenient -o out/l -q
  [ -s out/l.exr ] || fail "--lenient did not render";;
bad_plugin_dir)
  touch afile
  expect_exit 2 '^femto: error: plugin folder "/nonexistent" \(--plugin-dir\) does not exist$' -- "$femto" render "$scene" --plugin-dir /nonexistent -o out/x -q
  expect_exit 2 '^femto: error: plugin folder "afile" \(--plugin-dir\) is not a folder' -- "$femto" render "$scene" --plugin-dir afile -o out/x -q
  expect_exit 2 '^femto: error: plugin folder "/nonexistent" \(--plugin-dir\) does not exist$' -- "$femto" plugins --plugin-dir /nonexistent
  [ ! -e out ] || fail "the render started";;
plugin_shadowing)
  # A type is found by its library's file name, <type>.so, on the search path: --plugin-dir
  # folders in the order given, femto's own plugins, then $FEMTO_PLUGIN_PATH. When several
  # libraries provide a type, the first is used and a warning names it and the ignored ones.
  # $shadow/a/path.so and $shadow/b/path.so are test plugins of type "path" (like the built-in
  # integrator) that render 0.25 and 0.75 everywhere.
  [ -f "$shadow/a/path.so" ] && [ -f "$shadow/b/path.so" ] || fail "test plugins missing in '$shadow'"
  "$femto" plugins path > builtin.txt 2>&1 || fail "femto plugins path"
  builtin=$(sed -n 's/^  (from \(.*\))$/\1/p' builtin.txt)
  [ -f "$builtin" ] && ! grep -q '^warning' builtin.txt || { cat builtin.txt >&2; fail "built-in path.so"; }
  printf '%s\n' '<scene version="3.0.0"><integrator type="path"/><sensor type="orthographic">' \
    '<sampler type="independent"><integer name="sample_count" value="1"/></sampler>' \
    '<film type="hdrfilm"><integer name="width" value="4"/><integer name="height" value="4"/><rfilter type="box"/></film>' \
    '</sensor><shape type="rectangle"/></scene>' > s.xml
  expect_shadow() {  # expect_shadow USED IGNORED...: the warning of the last command
    local ignored; ignored=$(IFS=,; echo "$*" | cut -d, -f2- | sed 's/,/, /g')
    grep -qF "warning: plugin type \"path\" is provided by $# libraries: using $1, ignoring $ignored (" stderr.txt ||
      { cat stderr.txt >&2; fail "no warning that $1 shadows $ignored"; }
  }
  # `femto plugins path` shows the library used; a --plugin-dir wins over the built-in plugin.
  expect_exit 0 'provided by 2 libraries' -- "$femto" plugins path --plugin-dir "$shadow/a"
  expect_shadow "$shadow/a/path.so" "$builtin"
  grep -q 'copy a' stdout.txt && grep -qF "(from $shadow/a/path.so)" stdout.txt || { cat stdout.txt >&2; fail "femto plugins path"; }
  expect_exit 0 'provided by 2 libraries' -- "$femto" render s.xml --plugin-dir "$shadow/a" -o out/a -q
  [ "$(pixel_range out/a.exr)" = "0.250000 0.250000 " ] || fail "rendered $(pixel_range out/a.exr), not copy a's 0.25"
  # Between two --plugin-dir folders the first given wins.
  expect_exit 0 'provided by 3 libraries' -- "$femto" render s.xml --plugin-dir "$shadow/b" --plugin-dir "$shadow/a" -o out/ba -q
  expect_shadow "$shadow/b/path.so" "$shadow/a/path.so" "$builtin"
  [ "$(pixel_range out/ba.exr)" = "0.750000 0.750000 " ] || fail "rendered $(pixel_range out/ba.exr), not copy b's 0.75"
  # $FEMTO_PLUGIN_PATH adds types; it does not replace a built-in one.
  expect_exit 0 'provided by 2 libraries' -- env FEMTO_PLUGIN_PATH="$shadow/a" "$femto" plugins path
  expect_shadow "$builtin" "$shadow/a/path.so"
  # Without a second library: no warning.
  "$femto" render s.xml -o out/builtin -q 2> stderr.txt && [ ! -s stderr.txt ] || { cat stderr.txt >&2; fail "built-in path"; }
  # A library is identified by its descriptor's type name, which must match its file name: a
  # copy of the built-in `direct` under the name path.so is refused.
  mkdir copy && cp "$(dirname "$builtin")/direct.so" copy/path.so
  expect_exit 2 '^femto: error: s\.xml:1:[0-9]+: plugin copy/path\.so declares the type "direct": a plugin library must be named after its type \(direct\.so\)$' -- "$femto" render s.xml --plugin-dir copy -o out/c -q;;
sigint_partial)
  "$femto" render "$scene" -o out/int -D spp=100000 -D res=64 -q 2> err.txt &
  pid=$!
  wait_for_sigint_handler $pid
  sleep 1
  kill -INT $pid
  wait $pid; code=$?
  [ "$code" -eq 130 ] || { cat err.txt >&2; fail "exit code $code after SIGINT, expected 130"; }
  [ -s out/int.exr ] && [ -s out/int.png ] || fail "partial outputs missing"
  [ "$(exr_attr out/int.exr femto:interrupted)" = true ] || fail "not marked interrupted"
  n=$(exr_attr out/int.exr femto:samples)
  [ "$n" -gt 0 ] && [ "$n" -lt 100000 ] || fail "samples attribute $n"
  no_temp_files out || fail "temporary files left";;
sigint_latency)
  # Ctrl-C takes effect within a few samples' work, not at the end of a pass: one pixel whose
  # pass holds 2^22 volumetric samples (~10 s), a kernel filter's separate 65536-spp pilot
  # pass, and a 4096-spp pilot that is the image's first samples (a pass of the image).
  sed 's|<tfilter type="$tfilter"/>|<tfilter type="kernel"><integer name="pilot_spp" value="$pilot_spp"/><boolean name="pilot_in_image" value="$in_image"/></tfilter>|' \
    "$scene" > "$src/scenes/cornell-box/.pilot-$$.xml"
  trap 'rm -f "$src/scenes/cornell-box/.pilot-$$.xml"' EXIT
  for run in fog pilot pilot_image; do
    if [ $run = fog ]; then
      "$femto" render "$src/scenes/fog-object/scene.xml" -o out/$run -D res=1 --spp 67108864 -q 2> err.txt &
    elif [ $run = pilot ]; then
      "$femto" render "$src/scenes/cornell-box/.pilot-$$.xml" -o out/$run -D res=32 \
        -D pilot_spp=65536 -D in_image=false -q 2> err.txt &
    else
      "$femto" render "$src/scenes/cornell-box/.pilot-$$.xml" -o out/$run -D res=32 \
        -D pilot_spp=4096 -D in_image=true --spp 65536 -q 2> err.txt &
    fi
    pid=$!
    wait_for_sigint_handler $pid
    sleep 2
    start=$(date +%s%N)
    kill -INT $pid
    wait $pid; code=$?
    ms=$(( ($(date +%s%N) - start) / 1000000 ))
    [ "$code" -eq 130 ] || { cat err.txt >&2; fail "$run: exit code $code, expected 130"; }
    # Generous for a loaded machine; before, these took 10 s to minutes.
    [ "$ms" -lt 5000 ] || fail "$run: Ctrl-C took $ms ms to take effect"
    [ "$(exr_attr out/$run.exr femto:interrupted)" = true ] || fail "$run: not marked interrupted"
  done;;
empty_window)
  # A window no light reaches: a warning with the times light did arrive (the Cornell box's
  # first light reaches the camera after ~5.8 units; one bin from 3.5 misses it).
  expect_exit 0 'no light arrived within the film.s time window \[3\.5, 3\.55\] \(camera time, scene units\): the light this render traced arrived between [0-9.]+ and [0-9.]+' \
    -- "$femto" render "$scene" -o out/empty -D bins=1 -D res=16 -D spp=2 -q
  earliest=$(sed -n 's/.*arrived between \([0-9.]*\) and.*/\1/p' stderr.txt)
  awk -v t="$earliest" 'BEGIN { exit !(t > 3.55 && t < 20) }' || fail "earliest arrival $earliest"
  # A window light does reach: no such warning.
  "$femto" render "$scene" -o out/full -D bins=64 -D res=16 -D spp=2 -q 2> err.txt || fail "render"
  ! grep -q 'no light arrived' err.txt || fail "warned about a window that light reaches";;
write_signals)
  # Ctrl-C twice and SIGTERM while the outputs are being written: femto explains, finishes
  # a complete set, leaves no temporary file and exits 130 (the first signal's code).
  "$femto" render "$scene" -o out/big -D spp=1 -D res=256 -D bins=512 --npy 2> err.txt &
  pid=$!
  for _ in $(seq 6000); do
    grep -q 'writing out/big' err.txt && break
    kill -0 $pid 2>/dev/null || break
    sleep 0.01
  done
  kill -INT $pid; sleep 0.05; kill -INT $pid; sleep 0.05; kill -TERM $pid
  wait $pid; code=$?
  [ "$code" -eq 130 ] || { cat err.txt >&2; fail "exit code $code, expected 130"; }
  grep -q 'still writing the outputs' err.txt || { cat err.txt >&2; fail "no explanation (did writing end before the signals?)"; }
  for f in big.exr big_steady.exr big.png big.npy; do [ -s "out/$f" ] || fail "$f missing"; done
  iinfo out/big.exr | grep -q '256 x 131072' || fail "the cube is not readable"
  [ "$(stat -c %s out/big.npy)" -eq $((128 + 256 * 256 * 512 * 12)) ] || fail "the .npy is incomplete"
  no_temp_files out || fail "temporary files left";;
full_disk)
  # A write that fails part-way (RLIMIT_FSIZE standing in for a full disk) keeps the previous
  # outputs, says which file and why, and leaves no temporary file.
  "$femto" render "$scene" -o out/x -D spp=1 -D res=32 -D bins=256 --npy -q || fail "first render"
  cp out/x.exr before.exr
  ( trap '' XFSZ; ulimit -f 1024; exec "$femto" render "$scene" -o out/x -D spp=2 -D res=32 \
      -D bins=256 --npy --seed 7 -q ) 2> stderr.txt; code=$?
  [ "$code" -eq 2 ] || { cat stderr.txt >&2; fail "exit code $code, expected 2"; }
  grep -Eq 'cannot write "out/x\.npy": File too large' stderr.txt || { cat stderr.txt >&2; fail "message"; }
  cmp -s out/x.exr before.exr || fail "the EXR was replaced by a new one beside an old .npy"
  no_temp_files out || fail "temporary files left";;
compat_cbox)
  need_compat
  # Strict: every parameter of the file is accepted (the sensor's focusDistance has no effect
  # on a pinhole camera, in Mitsuba as in femto), without a warning.
  "$femto" render "$compat/mitsuba06-cbox/mts1-cbox-rgb.xml" -o out/cbox -D spp=4 -D res=64 -q \
    2> stderr.txt || { cat stderr.txt >&2; fail "strict render failed"; }
  ! grep -q '^warning' stderr.txt || { cat stderr.txt >&2; fail "unexpected warnings"; }
  [ -s out/cbox.exr ] || fail "no output";;
compat_veach)
  need_compat
  expect_exit 0 'strict_normals' -- "$femto" render "$compat/veach-mis/scene.xml" -o out/veach --lenient --spp 4 -q
  # Ignored on purpose: the path integrator's strictNormals and the film's gamma (femto's
  # PNG goes through the OpenColorIO sRGB transform).
  [ "$(grep -c '^warning' stderr.txt)" -eq 2 ] && grep -q '"gamma"' stderr.txt || { cat stderr.txt >&2; fail "unexpected warnings"; }
  [ -s out/veach.exr ] || fail "no output";;
progress_tty)
  # On a terminal (a pseudo-terminal from script(1)) the progress line shows percent,
  # elapsed time, ETA and the sample rate; with --quiet or without a terminal it is absent.
  script -qec "'$femto' render '$scene' -o out/p -D spp=16 -D res=64" /dev/null > tty.txt 2>&1 ||
    { cat tty.txt >&2; fail "render on a pty failed"; }
  grep -q 'Rendering \[#*' tty.txt && grep -q '100.0%' tty.txt && grep -q 'ETA' tty.txt &&
    grep -q 'M samples/s' tty.txt || { cat tty.txt >&2; fail "no progress line on a terminal"; }
  script -qec "'$femto' render '$scene' -o out/q -D spp=16 -D res=64 --quiet" /dev/null > quiet.txt 2>&1
  ! grep -q 'Rendering' quiet.txt || fail "--quiet still shows progress"
  "$femto" render "$scene" -o out/r -D spp=4 -D res=32 2> piped.txt
  ! grep -q 'Rendering \[' piped.txt || fail "progress shown when stderr is not a terminal";;
viz_outputs)
  # `femto viz` on a small transient render: every subcommand writes its files.
  "$femto" render "$scene" -o out/cb -D spp=2 -D res=32 -D bins=24 -q --npy || fail "render failed"
  "$femto" viz frames out/cb.exr -o out/frames --gif --tone log -q || fail "frames"
  [ "$(ls out/frames/frame_*.png | wc -l)" -eq 24 ] && [ -s out/frames/frames.gif ] || fail "frames missing"
  iinfo -v out/frames/frames.gif | grep -q '24 subimages' || fail "GIF is not animated"
  "$femto" viz frames out/cb.npy -o out/nframes --mp4 -q 2> mp4.txt || fail "frames from .npy"
  if command -v ffmpeg > /dev/null; then [ -s out/nframes/frames.mp4 ] || fail "no MP4"
  else grep -q 'skipping the MP4' mp4.txt || fail "no MP4 skip message"; fi
  "$femto" viz peak-time out/cb.exr -o out/peak.png --exr out/peak.exr -q || fail "peak-time"
  [ -s out/peak.png ] && [ -s out/peak.exr ] || fail "peak-time outputs missing"
  "$femto" viz peak-time out/cb.npy --start 3.5 --bin-width 0.05 -o out/peakn.png --exr out/peakn.exr --isochrones 4 -q ||
    fail "peak-time from .npy"
  "$femto" viz rainbow out/cb.exr -o out/rainbow.png -q && [ -s out/rainbow.png ] || fail "rainbow"
  # The lamp in view does not set the default level, so the box is not near black (with a
  # window long enough for the walls' light), and --level (about the lamp's radiance) wins.
  "$femto" render "$scene" -o out/long -D spp=2 -D res=32 -D bins=128 -q || fail "render failed"
  for sub in rainbow peak-time; do
    "$femto" viz $sub out/long.exr -o out/$sub.png -q && "$femto" viz $sub out/long.exr -o out/$sub-lamp.png --level 20 -q ||
      fail "$sub"
    [ "$(png_mean out/$sub.png)" -gt 45 ] || fail "default $sub is dark: mean $(png_mean out/$sub.png)"
    [ "$(png_mean out/$sub-lamp.png)" -lt 30 ] || fail "$sub --level ignored: mean $(png_mean out/$sub-lamp.png)"
  done
  "$femto" viz streak out/cb.exr --row 16 -o out/streak.png --exr out/streak.exr -q || fail "streak"
  [ "$(iinfo out/streak.exr | sed -n 's/.*: *\([0-9]*\) x *\([0-9]*\),.*/\1x\2/p')" = 32x24 ] || fail "streak size"
  [ "$(exr_attr out/streak.exr femto:row)" = 16 ] || fail "streak row attribute"
  "$femto" viz unwarp out/cb.exr -o out/world.exr --to world -q || fail "unwarp to world"
  [ "$(exr_attr out/world.exr femto:time)" = world ] || fail "femto:time not updated"
  "$femto" viz unwarp out/world.exr -o out/camera.exr --to camera -q || fail "unwarp to camera"
  [ "$(exr_attr out/camera.exr femto:time)" = camera ] || fail "femto:time not camera"
  no_temp_files out && no_temp_files out/frames || fail "temporary files left";;
viz_bad_input)
  "$femto" render "$scene" -o out/cb -D spp=1 -D res=16 -D bins=8 -q --npy || fail "render failed"
  expect_exit 2 '"nothere\.exr" does not exist' -- "$femto" viz peak-time nothere.exr -o out/p.png
  # A link that cannot be followed exists: the message says why it cannot be read.
  ln -s loop.exr loop.exr
  expect_exit 2 'cannot open "loop\.exr": Too many levels of symbolic links' -- "$femto" viz frames loop.exr -o out/f
  expect_exit 2 'not a femto transient cube' -- "$femto" viz frames out/cb_steady.exr -o out/f
  expect_exit 2 'row 16 is out of range.*0 to 15' -- "$femto" viz streak out/cb.exr --row 16 -o out/s.png
  expect_exit 2 'no depth part' -- "$femto" viz unwarp out/cb.npy -o out/u.exr --to world
  expect_exit 2 'already in camera time' -- "$femto" viz unwarp out/cb.exr -o out/u.exr --to camera
  expect_exit 2 'need the cube.s time axis' -- "$femto" viz peak-time out/cb.npy -o out/p.png --exr out/p.exr
  expect_exit 2 'tone' -- "$femto" viz frames out/cb.exr -o out/f --tone gamma
  expect_exit 2 'level must be a positive number' -- "$femto" viz peak-time out/cb.exr -o out/p.png --level 0
  expect_exit 2 'must end in \.exr' -- "$femto" viz unwarp out/cb.exr -o out/u.png --to world
  expect_exit 2 'needs a viz command' -- "$femto" viz
  : > empty.npy
  expect_exit 2 '^femto: error: "empty\.npy" is not a \.npy file$' -- "$femto" viz frames empty.npy -o out/f
  expect_exit 2 '^femto: error: --exposure must be a finite number of stops, got nan$' -- "$femto" viz frames out/cb.exr -o out/f --exposure nan
  expect_exit 2 '^femto: error: --start must be a finite time, got inf$' -- "$femto" viz peak-time out/cb.exr -o out/p.png --start inf
  # A tiny bin width shifts pixels by more bins than 64-bit indices hold: a message, not overflow.
  "$femto" render "$scene" -o out/d -D spp=1 -D res=8 -D bins=8 -q || fail "render failed"
  expect_exit 2 'shift pixels by up to .* bins of width 1e-20: too many' -- "$femto" viz unwarp out/d.exr -o out/u.exr --to world --bin-width 1e-20
  # An output that is a folder: refused before anything is written (the PNG was written first).
  mkdir -p out/folder.exr
  expect_exit 2 '^femto: error: --exr "out/folder\.exr" is a folder: name a file$' -- "$femto" viz rainbow out/cb.exr -o out/r.png --exr out/folder.exr
  [ ! -e out/r.png ] || fail "the PNG was written although the EXR could not be"
  mkdir -p out/fr/frame_00005.png
  expect_exit 2 '"out/fr/frame_00005\.png" is a folder' -- "$femto" viz frames out/cb.exr -o out/fr
  [ "$(ls out/fr)" = frame_00005.png ] || fail "frames written before the folder in their way was found"
  # A FIFO (of either name) is refused at once, not read: opening it would block forever.
  mkfifo cube.npy cube.exr || fail "mkfifo"
  for f in cube.npy cube.exr; do
    expect_exit 2 "\"$f\": it is not a regular file" -- timeout 10 "$femto" viz peak-time $f -o out/p.png
  done
  [ ! -e out/u.exr ] && [ ! -e out/p.png ] && [ ! -e out/s.png ] || fail "output written"
  # A whole-number --start over a cube whose start is fractional (OpenEXR had refused to
  # replace the header's double with an int).
  "$femto" viz peak-time out/cb.exr -o out/p6.png --exr out/p6.exr --start 6 -q || fail "--start 6"
  [ "$(exr_attr out/p6.exr femto:start)" = 6 ] || fail "--start 6 not recorded";;
btf_synth)
  # femto btf synth writes each format, femto btf info reads it back, and a scene renders it.
  for f in bdi dfmf fmf; do
    "$femto" btf synth -o a.$f --format $f --width 8 --height 4 2>synth.txt || fail "synth $f"
    grep -q "^wrote a\.$f ($(echo $f | tr a-z A-Z) 8x4, 81 light x 81 view directions)" synth.txt || fail "synth message: $(cat synth.txt)"
    "$femto" btf info a.$f > info.txt || fail "info $f"
    grep -q "^texels: *8 x 4" info.txt && grep -q "^directions: *81 lights x 81 views" info.txt || fail "info $f: $(cat info.txt)"
  done
  "$femto" btf synth -o g.btf --kind vgroove --format dfmf --sampling ubo2014 --width 16 --height 2 2>/dev/null || fail "vgroove"
  grep -q "151 lights" <("$femto" btf info g.btf) || fail "vgroove info"
  printf '<scene version="3.0.0"><sensor type="perspective"><transform name="to_world"><lookat origin="0,0,4" target="0,0,0" up="0,1,0"/></transform><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/></film></sensor><emitter type="point"><point name="position" x="1" y="1" z="2"/></emitter><shape type="rectangle"><bsdf type="btf"><string name="filename" value="a.dfmf"/></bsdf></shape></scene>' > b.xml
  "$femto" render b.xml -o out/b --spp 4 -q || fail "render"
  read -r lo hi <<< "$(pixel_range out/b.exr)"
  awk -v h="$hi" 'BEGIN { exit !(h > 0) }' || fail "the BTF plane is black (range $lo $hi)";;
bad_btf)
  # Bad BTF files and options: located errors, exit code 2, nothing written.
  expect_exit 2 '^femto: error: cannot open "none\.btf": no such file' -- "$femto" btf info none.btf
  printf '!DFMF08FCR\001\002' > short.btf
  expect_exit 2 'BTF "short\.btf": meta data size: needs' -- "$femto" btf info short.btf
  printf '<scene version="3.0.0"><sensor type="perspective"/><shape type="rectangle"><bsdf type="btf"><string name="filename" value="short.btf"/></bsdf></shape></scene>' > s.xml
  expect_exit 2 '^femto: error: s\.xml:1:[0-9]+: "btf": BTF "[^"]*short\.btf": meta data size' -- "$femto" render s.xml -o out/s -q
  expect_exit 2 'color-model 11.*dfmf only' -- "$femto" btf synth -o x.btf --format bdi --color-model 11
  expect_exit 2 'width' -- "$femto" btf synth -o x.btf --width 0
  expect_exit 2 'vgroove is written as --format bdi or dfmf' -- "$femto" btf synth -o x.btf --kind vgroove --format fmf
  expect_exit 2 '^femto: error: --slope must be from 1 to 89 degrees, got nan$' -- "$femto" btf synth -o x.btf --kind vgroove --slope nan
  mkdir -p taken.btf
  expect_exit 2 '^femto: error: cannot write "taken\.btf": Is a directory$' -- "$femto" btf synth -o taken.btf --width 2 --height 2
  expect_exit 2 'needs a btf command|subcommand' -- "$femto" btf
  [ ! -e x.btf ] && [ ! -e out/s.exr ] || fail "output written";;
streak_film)
  streak_scene > streak.xml
  "$femto" render streak.xml -o out/st -q || fail "render failed"
  for r in 0005 0012; do
    [ -s out/st_row$r.exr ] && [ -s out/st_row$r.png ] || fail "row $r outputs missing"; done
  [ "$(exr_attr out/st_row0012.exr femto:row)" = 12 ] || fail "femto:row"
  [ "$(exr_attr out/st_row0012.exr femto:bins)" = 30 ] || fail "femto:bins"
  [ "$(iinfo out/st_row0005.exr | sed -n 's/.*: *\([0-9]*\) x *\([0-9]*\),.*/\1x\2/p')" = 32x30 ] || fail "streak size"
  sed 's/value="5, 12"/value="5, 24"/' streak.xml > bad.xml
  expect_exit 2 'bad\.xml:[0-9]+:[0-9]+: .*row 24 is outside the image' -- "$femto" render bad.xml -o out/b -q;;
viz_streak)
  # A streak image carries its row's depth (channel Z), so `femto viz unwarp` takes it and
  # writes a streak image back; the other subcommands refuse it.
  streak_scene > streak.xml
  "$femto" render streak.xml -o out/st -q || fail "render failed"
  oiiotool --info -v out/st_row0012.exr > info.txt 2>&1 || { cat info.txt >&2; fail "oiiotool cannot read the streak EXR"; }
  grep -q 'channel list: R, G, B, Z' info.txt || { cat info.txt >&2; fail "no channel Z"; }
  # Z holds each column's depth in every time row: the first and the last row agree.
  oiiotool out/st_row0012.exr --ch Z --cut 32x1+0+0 -o z_first.exr &&
    oiiotool out/st_row0012.exr --ch Z --cut 32x1+0+29 -o z_last.exr || fail "oiiotool --ch Z"
  idiff -fail 0 -warn 0 z_first.exr z_last.exr > idiff.txt || { cat idiff.txt >&2; fail "Z differs between time rows"; }
  iinfo out/st_row0012.png | grep -q '32 x  *30, 3 channel' || { iinfo out/st_row0012.png >&2; fail "PNG preview"; }
  "$femto" viz unwarp out/st_row0012.exr -o out/world.exr --to world -q || fail "unwarp to world"
  [ -s out/world.exr ] || fail "no unwarped streak image"
  [ "$(exr_attr out/world.exr femto:time)" = world ] || fail "femto:time not world"
  [ "$(exr_attr out/world.exr femto:row)" = 12 ] || fail "femto:row not kept"
  exr_attr out/world.exr femto:layout | grep -q '^streak image' || fail "femto:layout not kept"
  exr_attr out/world.exr femto:unwarped | grep -q 'camera -> world' || fail "femto:unwarped"
  iinfo -v out/world.exr | grep -q 'channel list: R, G, B, Z' || fail "unwarped image has no Z"
  [ "$(iinfo out/world.exr | sed -n 's/.*: *\([0-9]*\) x *\([0-9]*\),.*/\1/p')" = 32 ] || fail "unwarped width"
  "$femto" viz unwarp out/world.exr -o out/camera.exr --to camera -q || fail "unwarp to camera"
  [ "$(exr_attr out/camera.exr femto:time)" = camera ] || fail "femto:time not camera"
  expect_exit 2 'already in world time' -- "$femto" viz unwarp out/world.exr -o out/again.exr --to world
  expect_exit 2 'is a streak image \(the x-t image of row 12\).*`femto viz frames` needs a cube.*only unwarp' -- "$femto" viz frames out/st_row0012.exr -o out/f
  expect_exit 2 'is a streak image.*`femto viz peak-time`' -- "$femto" viz peak-time out/st_row0012.exr -o out/p.png
  expect_exit 2 'is a streak image.*`femto viz rainbow`' -- "$femto" viz rainbow out/st_row0012.exr -o out/r.png
  expect_exit 2 'is a streak image.*`femto viz streak`' -- "$femto" viz streak out/st_row0012.exr --row 0 -o out/s.png
  # A cube's slice (viz streak --exr) is a streak image too: with the depth of an OpenEXR
  # cube it can be unwarped; from a .npy (no depth) it has no channel Z.
  "$femto" render "$scene" -o out/cb -D spp=1 -D res=16 -D bins=8 -q --npy || fail "cube render failed"
  "$femto" viz streak out/cb.exr --row 5 -o out/slice.png --exr out/slice.exr -q || fail "viz streak"
  "$femto" viz unwarp out/slice.exr -o out/slice_world.exr --to world -q || fail "unwarp a slice"
  [ "$(exr_attr out/slice_world.exr femto:time)" = world ] || fail "slice femto:time"
  "$femto" viz streak out/cb.npy --row 5 -o out/nslice.png --exr out/nslice.exr -q || fail "viz streak .npy"
  expect_exit 2 'streak image has no channel Z' -- "$femto" viz unwarp out/nslice.exr -o out/nu.exr --to world
  [ ! -e out/f ] && [ ! -e out/p.png ] && [ ! -e out/r.png ] && [ ! -e out/s.png ] &&
    [ ! -e out/again.exr ] && [ ! -e out/nu.exr ] || fail "output written"
  no_temp_files out || fail "temporary files left";;
viz_mp4)
  # MP4 needs ffmpeg, which femto does not require: skipped (ctest SKIP) when it is missing.
  command -v ffmpeg > /dev/null || { echo "SKIP [$case_name]: no ffmpeg on PATH"; exit 77; }
  "$femto" render "$scene" -o out/m -D spp=2 -D res=32 -D bins=24 -q || fail "render failed"
  "$femto" viz frames out/m.exr -o out/frames --mp4 > log.txt 2>&1 || { cat log.txt >&2; fail "viz frames --mp4"; }
  [ -s out/frames/frames.mp4 ] || fail "no mp4"
  n=$(ffprobe -v error -select_streams v:0 -count_frames -show_entries stream=nb_read_frames -of csv=p=0 out/frames/frames.mp4)
  [ "$n" = 24 ] || fail "mp4 has $n frames, expected 24";;
*) fail "unknown case";;
esac
echo "PASS [$case_name]"
