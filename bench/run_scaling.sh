#!/usr/bin/env bash
# Thread scaling of the path tracer (issue 17: >= 1.9x at 2 threads when both cores are free):
# `path` into an hdrfilm on the Cornell box (256x256, 16 spp) and on the 1M-triangle displaced
# sphere (256x256, 8 spp), each rendered at 1 thread and at all threads (default 2) in the same
# round, the order of the two alternating from round to round so that drift of the machine
# falls on both. Scaling = 1-thread time / N-thread time within a round (render time as
# `femto render` reports it: no loading or writing); the table gives its median and range.
#   bench/run_scaling.sh [RUNS] [THREADS]     defaults 7 and 2; about 4 minutes on 2 cores
# Needs the mesh: python3 bench/experiments/scenes/make_displaced_sphere.py
# Results: bench/results/scaling.csv, scaling.png, scaling_run.log.
set -euo pipefail

source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
bench_build  # everything: the CLI and its plugins
runs=${1:-7}
threads=${2:-2}
log="$results/scaling_run.log"
bench_log_header "$log"
echo "cores used: 1 and $threads of $(nproc)" | tee -a "$log"
mesh="$root/bench/experiments/scenes/displaced_sphere.ply"
if [[ ! -f "$mesh" ]]; then
    echo "missing $mesh: run python3 bench/experiments/scenes/make_displaced_sphere.py" >&2
    exit 2
fi

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
scenes=(
    "cornell-box|$root/bench/experiments/scenes/cornell-films.xml|-D film=hdrfilm -D res=256 -D spp=16"
    "displaced-sphere|$root/bench/experiments/scenes/displaced-sphere.xml|-D res=256 -D spp=8"
)
csv="$results/scaling.csv"
echo "scene,threads,run,seconds,mrays_per_s" > "$csv"
for run in $(seq 1 "$runs"); do
    order=(1 "$threads")
    ((run % 2 == 0)) && order=("$threads" 1)
    for entry in "${scenes[@]}"; do
        IFS='|' read -r scene xml defs <<< "$entry"
        read -r -a defines <<< "$defs"
        for n in "${order[@]}"; do
            line=$("$build/bin/femto" render "$xml" -D integrator=path "${defines[@]}" \
                --threads "$n" --seed "$run" -o "$work/out" 2>&1 | render_seconds_and_rate)
            read -r seconds rate <<< "$line"
            echo "$scene,$n,$run,$seconds,$rate" | tee -a "$csv"
        done
    done
done
echo "load average after the benchmark: $(cat /proc/loadavg)" | tee -a "$log"
/usr/bin/python3 - "$csv" "$results/scaling.png" "$threads" <<'PY' | tee -a "$log"
import csv, statistics, sys
import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt
rows = list(csv.DictReader(open(sys.argv[1])))
n = sys.argv[3]
sec = {(r["scene"], r["threads"], r["run"]): float(r["seconds"]) for r in rows}
scenes = list(dict.fromkeys(r["scene"] for r in rows))
runs = sorted({r["run"] for r in rows}, key=int)
print(f"| scene | 1 thread: s (median) | {n} threads: s (median) | scaling per round, median [range] |")
print("|---|---|---|---|")
fig, ax = plt.subplots(figsize=(5, 3))
for i, s in enumerate(scenes):
    per_run = [sec[(s, "1", k)] / sec[(s, n, k)] for k in runs]
    t1 = statistics.median(sec[(s, "1", k)] for k in runs)
    tn = statistics.median(sec[(s, n, k)] for k in runs)
    print(f"| {s} | {t1:.2f} | {tn:.2f} | {statistics.median(per_run):.3f} "
          f"[{min(per_run):.3f}, {max(per_run):.3f}] |")
    ax.plot([i] * len(per_run), per_run, "o", ms=4, color="black")
ax.axhline(1.9, color="tab:red", lw=1, ls="--", label="goal (1.9)")
ax.axhline(float(n), color="gray", lw=1, ls=":", label=f"ideal ({n})")
ax.set_xticks(range(len(scenes)), scenes)
ax.set_xlim(-0.5, len(scenes) - 0.5)
ax.set_ylabel(f"1-thread time / {n}-thread time")
ax.legend(fontsize=7)
ax.grid(True, alpha=0.3)
fig.tight_layout()
fig.savefig(sys.argv[2], dpi=110)
PY
echo
echo "results in $results: scaling.csv, scaling.png, scaling_run.log"
