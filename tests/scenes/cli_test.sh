#!/usr/bin/env bash
# One end-to-end case of the femto CLI: cli_test.sh CASE FEMTO_BINARY SOURCE_DIR WORK_DIR
set -uo pipefail
case_name=$1 femto=$2 src=$3 work=$4
rm -rf "$work" && mkdir -p "$work" && cd "$work" || exit 1
scene="$src/scenes/cornell-box/scene.xml"
compat="$src/../shared/compat-scenes"

fail() { echo "FAIL [$case_name]: $*" >&2; exit 1; }
# expect_exit CODE PATTERN -- command...: runs it, checks the exit code and that stderr matches.
expect_exit() {
  local code=$1 pattern=$2; shift 3
  "$@" > stdout.txt 2> stderr.txt
  local got=$?
  [ "$got" -eq "$code" ] || { cat stderr.txt >&2; fail "exit code $got, expected $code: $*"; }
  grep -Eq -- "$pattern" stderr.txt || { cat stderr.txt >&2; fail "stderr does not match /$pattern/"; }
}
exr_attr() { iinfo -v "$1" | sed -n "s/^ *$2: *\"\{0,1\}\([^\"]*\)\"\{0,1\}$/\1/p"; }
no_temp_files() { ! ls -A "$1" | grep -q '\.tmp'; }

case "$case_name" in
version)
  "$femto" --version | grep -Eq '^femto [0-9]+\.[0-9]+\.[0-9]+$' || fail "bad --version";;
plugins_list)
  "$femto" plugins > list.txt || fail "exit code"
  for k in integrator sensor film rfilter sampler shape bsdf emitter texture; do
    grep -q "^$k:" list.txt || fail "kind $k missing"; done
  grep -q "  path " list.txt || fail "path integrator missing";;
plugins_schema)
  "$femto" plugins roughconductor > s.txt || fail "exit code"
  grep -q "alpha" s.txt && grep -q "distribution" s.txt || fail "schema incomplete";;
plugins_unknown)
  expect_exit 2 'no plugin named "nosuch"' -- "$femto" plugins nosuch;;
plugin_docs_fresh)
  "$femto" plugins --markdown > plugins.md || fail "exit code"
  diff -u "$src/docs/plugins.md" plugins.md > diff.txt ||
    { head -40 diff.txt >&2; fail "docs/plugins.md is stale: run scripts/gen-plugin-docs.sh"; };;
render_demo)
  "$femto" render "$scene" -o out/demo -D spp=4 -D res=64 -q || fail "render failed"
  [ -s out/demo.exr ] && [ -s out/demo.png ] || fail "outputs missing"
  [ "$(exr_attr out/demo.exr femto:samples)" = 4 ] || fail "samples attribute"
  [ "$(exr_attr out/demo.exr femto:integrator)" = transient_path ] || fail "integrator attribute"
  [ "$(exr_attr out/demo.exr femto:bins)" = 256 ] || fail "bins attribute"
  [ -s out/demo_steady.exr ] || fail "steady image missing"
  no_temp_files out || fail "temporary files left";;
bad_xml)
  printf '<scene version="3.0.0">\n  <shape type="rectangle">\n</scene>\n' > bad.xml
  expect_exit 2 'bad\.xml:3:[0-9]+: malformed XML' -- "$femto" render bad.xml -o out/x -q
  [ ! -e out/x.exr ] || fail "output written";;
unknown_plugin)
  printf '<scene version="3.0.0">\n<sensor type="perspective"/>\n<shape type="spehre"/>\n</scene>\n' > u.xml
  expect_exit 2 'u\.xml:3:1: unknown <shape> plugin "spehre" \(did you mean "sphere"\?\)' -- "$femto" render u.xml -o out/u -q;;
missing_scene)
  expect_exit 2 'does not exist' -- "$femto" render nothere.xml -q;;
missing_mesh)
  printf '<scene version="3.0.0">\n<sensor type="perspective"/>\n<shape type="obj">\n<string name="filename" value="gone.obj"/>\n</shape>\n</scene>\n' > m.xml
  expect_exit 2 'm\.xml:4:1: .*gone\.obj' -- "$femto" render m.xml -o out/m -q;;
unwritable_output)
  touch afile
  expect_exit 2 'cannot create the output folder' -- "$femto" render "$scene" -o afile/sub/x -q
  mkdir ro && chmod 555 ro
  if [ "$(id -u)" -ne 0 ]; then
    expect_exit 2 'not writable' -- "$femto" render "$scene" -o ro/x -q
  fi
  ls -A ro | grep -q . && fail "something was written";
  true;;
bad_spp)
  expect_exit 2 'spp' -- "$femto" render "$scene" --spp 0 -q
  expect_exit 2 'spp' -- "$femto" render "$scene" --spp -3 -q
  expect_exit 2 'spp' -- "$femto" render "$scene" --spp abc -q
  expect_exit 2 'sample_count' -- "$femto" render "$scene" -D spp=0 -o out/s -q;;
bad_threads)
  expect_exit 2 'threads' -- "$femto" render "$scene" --threads 0 -q;;
bad_define)
  expect_exit 2 'expected name=value' -- "$femto" render "$scene" -D novalue -q
  expect_exit 2 'width must be in' -- "$femto" render "$scene" -D res=-1 -o out/d -q
  expect_exit 2 'scene\.xml:[0-9]+:[0-9]+: integer "width": "nan" is not an integer' -- "$femto" render "$scene" -D res=nan -o out/d -q;;
sigint_partial)
  "$femto" render "$scene" -o out/int -D spp=100000 -D res=64 -q 2> err.txt &
  pid=$!
  # Wait until femto has installed its SIGINT handler (bit 2 of SigCgt), then let it render.
  for _ in $(seq 600); do
    cgt=$(sed -n 's/^SigCgt:\t//p' /proc/$pid/status 2>/dev/null) || break
    [ -n "$cgt" ] && (( (0x$cgt >> 1) & 1 )) && break
    sleep 0.1
  done
  sleep 1
  kill -INT $pid
  wait $pid; code=$?
  [ "$code" -eq 130 ] || { cat err.txt >&2; fail "exit code $code after SIGINT, expected 130"; }
  [ -s out/int.exr ] && [ -s out/int.png ] || fail "partial outputs missing"
  [ "$(exr_attr out/int.exr femto:interrupted)" = true ] || fail "not marked interrupted"
  n=$(exr_attr out/int.exr femto:samples)
  [ "$n" -gt 0 ] && [ "$n" -lt 100000 ] || fail "samples attribute $n"
  no_temp_files out || fail "temporary files left";;
compat_cbox)
  expect_exit 0 'focus_distance' -- "$femto" render "$compat/mitsuba06-cbox/mts1-cbox-rgb.xml" -o out/cbox --lenient -D spp=4 -D res=64 -q
  # The only parameter femto ignores in this file is the sensor's focusDistance.
  [ "$(grep -c '^warning' stderr.txt)" -eq 1 ] || { cat stderr.txt >&2; fail "unexpected warnings"; }
  [ -s out/cbox.exr ] || fail "no output"
  expect_exit 2 'has no parameter "focus_distance"' -- "$femto" render "$compat/mitsuba06-cbox/mts1-cbox-rgb.xml" -o out/strict -q;;
compat_veach)
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
*) fail "unknown case";;
esac
echo "PASS [$case_name]"
