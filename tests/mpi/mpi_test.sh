#!/usr/bin/env bash
# One case of distributed rendering (docs/distributed.md):
#   mpi_test.sh CASE FEMTO_BINARY COMPARE_BINARY SOURCE_DIR WORK_DIR
# Renders under `mpirun -np N` must equal the single-process render of the same seed and spp to
# float rounding (relative 1e-6), and repeat bit for bit with the same process count. Skips
# (exit 77) where femto was built without MPI or mpirun is missing.
set -uo pipefail
case_name=$1 femto=$2 compare=$3 src=$4 work=$5
rm -rf "$work" && mkdir -p "$work" && cd "$work" || exit 1
fail() { echo "FAIL [$case_name]: $*" >&2; exit 1; }
skip() { echo "SKIP [$case_name]: $*"; exit 77; }
[ -x "$femto" ] || fail "no femto program at $femto"
command -v mpirun > /dev/null || skip "mpirun not found (Debian: openmpi-bin)"
"$femto" --version | grep -q "distributed rendering: yes" || skip "femto was built without MPI"
# CI runs as root, which Open MPI refuses unless told; oversubscribe: 3 processes on 2 cores.
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
cornell="$src/scenes/cornell-box/scene.xml"
films="$src/bench/experiments/scenes/cornell-films.xml"

# render NP OUT SCENE ARGS...: NP = 0 renders in one process, without mpirun.
render() {
  local np=$1 out=$2 scene=$3; shift 3
  if [ "$np" -eq 0 ]; then
    "$femto" render "$scene" -o "$out" -q --threads 1 --seed 7 "$@" 2> "$out.log"
  else
    mpirun -np "$np" "$femto" render "$scene" -o "$out" -q --threads 1 --seed 7 "$@" 2> "$out.log"
  fi || { cat "$out.log" >&2; fail "render (np $np) failed: $*"; }
}
same() {  # same A B REL
  "$compare" "$1" "$2" "$3" || fail "$1 and $2 differ beyond $3"
}
exr_attr() { iinfo -v "$1" | sed -n "s/^ *$2: *\"\{0,1\}\([^\"]*\)\"\{0,1\}$/\1/p"; }
# Starts an MPI render of many samples in the background (pid in $job), waits for its passes.
# 32 passes of 1/32 of the samples (default 40000: ~1.5 s per pass here).
start_long_render() {
  mpirun -np 2 "$femto" render "$cornell" -o out/long --threads 1 -D res=32 -D spp=${1:-40000} \
    -D bins=64 > long.log 2>&1 &
  job=$!
  for _ in $(seq 300); do grep -q "passes done" long.log && return; sleep 0.1; done
  cat long.log >&2; fail "the render never reported a pass"
}

case "$case_name" in
path_np2|path_np3)
  np=${case_name#path_np}
  render 0 one "$films" -D integrator=path -D film=hdrfilm -D res=48 -D spp=24
  render "$np" many "$films" -D integrator=path -D film=hdrfilm -D res=48 -D spp=24
  same one.exr many.exr 1e-6
  [ "$(exr_attr many.exr femto:processes)" = "$np" ] || fail "femto:processes is not $np"
  [ "$(exr_attr many.exr femto:samples)" = 24 ] || fail "femto:samples is not 24";;
histogram_np2|histogram_np3|kernel_np2|kernel_np3)
  tfilter=${case_name%_np*} np=${case_name##*_np}
  args=(-D integrator=transient_path -D tfilter=$tfilter -D res=32 -D spp=16 -D bins=64 --npy)
  render 0 one "$cornell" "${args[@]}"
  render "$np" many "$cornell" "${args[@]}"
  same one.npy many.npy 1e-6
  same one_steady.exr many_steady.exr 1e-6;;
light_np2)
  args=(-D integrator=transient_light -D res=32 -D spp=8 -D bins=64 --npy)
  render 0 one "$cornell" "${args[@]}"
  render 2 many "$cornell" "${args[@]}"
  same one.npy many.npy 1e-6;;
streak_np2)  # a streak film (two recorded rows) over a lit plane with a kernel filter
  cat > streak.xml <<'XML'
<scene version="3.0.0">
  <integrator type="transient_path"/>
  <sensor type="perspective">
    <float name="fov" value="60"/>
    <transform name="to_world"><lookat origin="0,-3,4" target="0,0,0" up="0,0,1"/></transform>
    <sampler type="independent"><integer name="sample_count" value="16"/></sampler>
    <film type="streak">
      <integer name="width" value="32"/><integer name="height" value="24"/>
      <string name="rows" value="5, 12"/>
      <float name="start" value="6"/><float name="bin_width" value="0.1"/><integer name="bins" value="40"/>
      <tfilter type="kernel"/>
    </film>
  </sensor>
  <shape type="rectangle"><transform name="to_world"><scale value="3"/></transform></shape>
  <emitter type="point"><point name="position" x="0" y="0" z="2"/><rgb name="intensity" value="5"/></emitter>
</scene>
XML
  render 0 one streak.xml
  render 2 many streak.xml
  for row in 0005 0012; do same one_row$row.exr many_row$row.exr 1e-6; done;;
ppm_np2|beams_np3)  # photon passes: each pass (photon map and camera samples) in one process
  integrator=transient_${case_name%_np*} np=${case_name##*_np}
  args=(-D integrator=$integrator -D res=32 -D spp=8 -D bins=40 --npy)
  render 0 one "$src/scenes/laser-caustic/scene.xml" "${args[@]}"
  render "$np" many "$src/scenes/laser-caustic/scene.xml" "${args[@]}"
  same one.npy many.npy 1e-6;;
bdpt_images_np2)  # an integrator's own images (transient_bdpt's strategy images) are combined
  cp -r "$src/scenes/cornell-box" scene
  sed -i 's|<integer name="max_depth" value="$max_depth"/>|&<boolean name="strategy_images" value="true"/>|' scene/scene.xml
  grep -q strategy_images scene/scene.xml || fail "could not turn strategy images on"
  args=(-D integrator=transient_bdpt -D max_depth=3 -D res=24 -D spp=8 -D bins=32 --npy)
  render 0 one scene/scene.xml "${args[@]}"
  render 2 many scene/scene.xml "${args[@]}"
  same one.npy many.npy 1e-6
  for image in one_bdpt_s*_t*.exr; do same "$image" "many${image#one}" 1e-6; done;;
repeat_np2)
  args=(-D integrator=transient_path -D tfilter=kernel -D res=32 -D spp=16 -D bins=64 --npy)
  render 2 first "$cornell" "${args[@]}"
  render 2 second "$cornell" "${args[@]}"
  same first.npy second.npy 0;;
sigint)  # SIGINT to every process of the job: each finishes its pass, rank 0 writes
  start_long_render
  pkill -INT -f "^$femto render $cornell -o out/long"  # the processes, not mpirun
  wait $job; code=$?
  [ "$code" -eq 130 ] || { cat long.log >&2; fail "exit code $code after SIGINT, expected 130"; }
  grep -q "every process finishes its pass" long.log || { cat long.log >&2; fail "no message"; }
  [ -s out/long.exr ] || { cat long.log >&2; fail "no partial output"; }
  [ "$(exr_attr out/long.exr femto:interrupted)" = true ] || fail "not marked interrupted"
  n=$(exr_attr out/long.exr femto:samples)
  # 32 passes of 1250 samples (16 per process), stopped after a round: whole rounds only.
  [ "$n" -gt 0 ] && [ "$n" -lt 40000 ] && [ $((n % 2500)) -eq 0 ] || fail "samples attribute $n";;
usr1)  # SIGUSR1 to mpirun, which forwards it to every process
  start_long_render
  kill -USR1 $job
  wait $job; code=$?
  [ "$code" -eq 138 ] || { cat long.log >&2; fail "exit code $code after SIGUSR1, expected 138"; }
  [ "$(exr_attr out/long.exr femto:interrupted)" = true ] || fail "not marked interrupted";;
ctrl_c)  # Ctrl-C on mpirun, with Open MPI's grace before SIGKILL raised (docs/distributed.md)
  export OMPI_MCA_odls_base_sigkill_timeout=10  # SIGTERM 10 s after Ctrl-C, SIGKILL 10 s later
  start_long_render 120000  # passes of ~4 s: longer than Open MPI's default grace of 1 s
  kill -INT $job
  wait $job; code=$?
  echo "mpirun exited $code"
  [ -s out/long.exr ] || { cat long.log >&2; fail "no partial output after Ctrl-C on mpirun"; }
  [ "$(exr_attr out/long.exr femto:interrupted)" = true ] || fail "not marked interrupted";;
dead_process)  # a rendering process killed outright: the job fails (exit 1), nothing is written
  start_long_render
  # The newest match is a rendering process (each is the child of the process mpirun started).
  pkill -KILL -n -f "^$femto render $cornell -o out/long"
  wait $job; code=$?
  [ "$code" -eq 1 ] || { cat long.log >&2; fail "exit code $code after a process died, expected 1"; }
  grep -q "femto: error: process [01] of the MPI job (pid [0-9]*) died (Killed, signal 9)" long.log ||
    { cat long.log >&2; fail "no message naming the process"; }
  ! ls out 2>/dev/null | grep -q . || fail "outputs written: $(ls out)";;
scene_error)  # every process meets the same error: exit code 2, reported once
  echo '<scene version="3.0.0"><integrator type="nope"/></scene>' > bad.xml
  mpirun -np 2 "$femto" render bad.xml -o out/bad > stdout.txt 2> stderr.txt; code=$?
  [ "$code" -eq 2 ] || { cat stderr.txt >&2; fail "exit code $code, expected 2"; }
  [ "$(grep -c 'femto.*error' stderr.txt)" -eq 1 ] || { cat stderr.txt >&2; fail "not reported once"; }
  grep -q 'bad.xml:1' stderr.txt || { cat stderr.txt >&2; fail "no location"; };;
bench_np3)  # a distributed study: 3 workers take the runs, all 3 render the reference
  experiment="$src/bench/experiments/fog-point-connections.xml"
  "$femto" bench "$experiment" -o one -q || fail "single-process study failed"
  mpirun -np 3 "$femto" bench "$experiment" -o many --runs-per-machine 3 2> many.log ||
    { cat many.log >&2; fail "distributed study failed"; }
  grep -q "with 3 processes" many.log || fail "the reference was not rendered by 3 processes"
  grep -q "(worker 1)" many.log && grep -q "(worker 2)" many.log || fail "runs not shared"
  [ "$(wc -l < many/results.csv)" = 19 ] && [ "$(wc -l < many/frames.csv)" = "$(wc -l < one/frames.csv)" ] ||
    fail "results.csv or frames.csv incomplete"
  [ -s many/report.md ] && [ -s many/plot.svg ] || fail "report missing"
  [ "$(grep -o "the runs went to 3 workers.*: .*\. The machine above" many/report.md | grep -o ' cores, load average' | wc -l)" = 3 ] ||
    { cat many/report.md >&2; fail "the report does not describe the 3 workers"; }
  # The same runs (scene..samples) with the same errors (relmse..relmse_raw) to 1e-6.
  grep -v '^scene,' one/results.csv | sort > a.csv; grep -v '^scene,' many/results.csv | sort > b.csv
  paste -d, a.csv b.csv | awk -F, -v n="$(head -1 one/results.csv | tr ',' '\n' | wc -l)" '
    { for (i = 1; i <= 6; ++i) if ($i != $(i + n)) { print "run differs: " $0; bad = 1 }
             for (i = 11; i <= 15; ++i) { a = $i; b = $(i + n); d = a - b; if (d < 0) d = -d
               s = (a < 0 ? -a : a); if (d > 1e-6 * s) { print "error differs: " $0; bad = 1 } } }
    END { exit bad }' || fail "the distributed study measured other errors"
  mpirun -np 3 "$femto" bench "$experiment" -o many --runs-per-machine 3 -q || fail "resume failed"
  [ "$(wc -l < many/results.csv)" = 19 ] || fail "resuming added rows";;
*) fail "unknown case";;
esac
echo "PASS [$case_name]"
