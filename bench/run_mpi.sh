#!/usr/bin/env bash
# Distributed rendering (issue 18, docs/distributed.md): strong scaling of one render on this
# machine and what the processes exchange.
#   bench/run_mpi.sh [RUNS]      default 5; about 6 minutes on 2 cores once built
# 1. Scaling: the Cornell box by `path` into hdrfilm (128x128, 256 spp) and by
#    `transient_path` into a 1024-bin transient film (128x128, 64 spp), as 1 process x 1 thread,
#    1 process x 2 threads and 2 processes x 1 thread (mpirun), RUNS times interleaved; wall
#    time of the whole command (start, load, render, combine, write) and femto's own render
#    time; speedups of the medians against 1 x 1.
# 2. Volume and memory: a 256x256 film of 1024 bins (768 MiB cube) at 2 processes: the bytes
#    combined, how long it took, and rank 0's peak memory beside a single process's (each
#    minus the same render into a 1-bin film: program, libraries, scene).
# Results: bench/results/mpi/{scaling.csv,memory.csv,scaling.png,run.log}.
set -euo pipefail

source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
bench_build
runs=${1:-5}
out="$results/mpi"
mkdir -p "$out"
log="$out/run.log"
bench_log_header "$log"
command -v mpirun >/dev/null || { echo "mpirun not found (scripts/deps.sh installs it)"; exit 1; }
"$build/bin/femto" --version | tee -a "$log"
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
femto="$build/bin/femto"
films="$root/bench/experiments/scenes/cornell-films.xml"
cornell="$root/scenes/cornell-box/scene.xml"

# run CONFIG SCENE_ARGS...: CONFIG is PROCESSES x THREADS; prints "wall render combine_s mib".
run() {
    local procs=${1%x*} threads=${1#*x}
    shift
    local start end
    start=$(date +%s.%N)
    if [[ $procs -eq 1 ]]; then
        "$femto" render "$@" --threads "$threads" -o "$work/img" 2> "$work/err.txt"
    else
        mpirun -np "$procs" --bind-to none "$femto" render "$@" --threads "$threads" \
            -o "$work/img" 2> "$work/err.txt"
    fi
    end=$(date +%s.%N)
    local render combine mib
    render=$(sed -n 's/.* spp in \([0-9.]*\) s .*/\1/p' "$work/err.txt")
    combine=$(sed -n 's/.*MiB from each) in \([0-9.]*\) s.*/\1/p' "$work/err.txt")
    mib=$(sed -n 's/.*processes (\([0-9.]*\) MiB from each.*/\1/p' "$work/err.txt")
    echo "$(echo "$end - $start" | bc) $render ${combine:-0} ${mib:-0}"
}

csv="$out/scaling.csv"
echo "workload,config,run,wall_s,render_s,combine_s,combined_mib_per_process" > "$csv"
declare -A workloads=(
    [path-hdrfilm]="$films -D integrator=path -D film=hdrfilm -D res=128 -D spp=256"
    [transient-1024]="$cornell -D integrator=transient_path -D res=128 -D spp=64 -D bins=1024"
)
for run_index in $(seq 1 "$runs"); do
    for workload in path-hdrfilm transient-1024; do
        for config in 1x1 1x2 2x1; do
            # shellcheck disable=SC2086  # the workload's arguments split on purpose
            read -r wall render combine mib <<< "$(run $config ${workloads[$workload]})"
            echo "$workload,$config,$run_index,$wall,$render,$combine,$mib" | tee -a "$csv"
        done
    done
done

mem="$out/memory.csv"
echo "config,bins,peak_kib,combine_s,combined_mib_per_process" > "$mem"
for bins in 1 1024; do
    args=("$cornell" -D integrator=transient_path -D res=256 -D spp=4 -D bins=$bins)
    /usr/bin/time -f "%M" -o "$work/time.single" "$femto" render "${args[@]}" --threads 2 \
        -o "$work/mem" 2> /dev/null
    echo "1x2,$bins,$(cat "$work/time.single"),0,0" | tee -a "$mem"
    mpirun -np 2 --bind-to none bash -c '/usr/bin/time -f "%M" -o "$0.$OMPI_COMM_WORLD_RANK" "$@"' \
        "$work/time.rank" "$femto" render "${args[@]}" --threads 1 -o "$work/mem" 2> "$work/err.txt"
    combine=$(sed -n 's/.*MiB from each) in \([0-9.]*\) s.*/\1/p' "$work/err.txt")
    mib=$(sed -n 's/.*processes (\([0-9.]*\) MiB from each.*/\1/p' "$work/err.txt")
    echo "2x1 rank 0,$bins,$(cat "$work/time.rank.0"),$combine,$mib" | tee -a "$mem"
done
echo "load average after the benchmark: $(cat /proc/loadavg)" | tee -a "$log"

/usr/bin/python3 - "$csv" "$mem" "$out/scaling.png" <<'PY' | tee -a "$log"
import csv, statistics, sys
import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt

rows = list(csv.DictReader(open(sys.argv[1])))
configs = ["1x1", "1x2", "2x1"]
fig, axes = plt.subplots(1, 2, figsize=(10, 4))
for ax, workload in zip(axes, ["path-hdrfilm", "transient-1024"]):
    med = {}
    for c in configs:
        sel = [r for r in rows if r["workload"] == workload and r["config"] == c]
        med[c] = {k: statistics.median(float(r[k]) for r in sel)
                  for k in ("wall_s", "render_s", "combine_s")}
    print(f"{workload} ({len(sel)} runs each; medians; speedup against 1 process x 1 thread)")
    print("  processes x threads |  wall s | speedup | render s | speedup | combine s")
    for c in configs:
        m = med[c]
        print(f"  {c:>19} | {m['wall_s']:7.2f} | {med['1x1']['wall_s'] / m['wall_s']:6.2f}x"
              f" | {m['render_s']:8.2f} | {med['1x1']['render_s'] / m['render_s']:6.2f}x"
              f" | {m['combine_s']:9.2f}")
    x = range(len(configs))
    ax.bar([i - 0.2 for i in x], [med["1x1"]["wall_s"] / med[c]["wall_s"] for c in configs],
           0.4, label="whole command")
    ax.bar([i + 0.2 for i in x], [med["1x1"]["render_s"] / med[c]["render_s"] for c in configs],
           0.4, label="render only")
    ax.set_xticks(list(x), configs)
    ax.set_xlabel("processes x threads")
    ax.axhline(2, color="gray", lw=0.5, ls="--")
    ax.set_ylabel("speedup vs 1 x 1")
    ax.set_title(workload)
    ax.legend()
fig.tight_layout()
fig.savefig(sys.argv[3], dpi=100)

mem = list(csv.DictReader(open(sys.argv[2])))
peak = {(r["config"], r["bins"]): float(r["peak_kib"]) for r in mem}
cube_kib = 256 * 256 * 1024 * 3 * 4 / 1024
print(f"memory: 256x256x1024 cube = {cube_kib / 1024:.0f} MiB")
for config in ("1x2", "2x1 rank 0"):
    extra = peak[(config, "1024")] - peak[(config, "1")]
    print(f"  {config:>10}: peak {peak[(config, '1024')] / 1024:.0f} MiB, minus the 1-bin render "
          f"{extra / 1024:.0f} MiB = {extra / cube_kib:.2f} x the cube")
for r in mem:
    if r["config"].startswith("2x1") and r["bins"] == "1024":
        print(f"  combined {r['combined_mib_per_process']} MiB from the other process in "
              f"{r['combine_s']} s; per pass the processes exchange one int each (the stop vote)")
PY
