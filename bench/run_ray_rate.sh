#!/usr/bin/env bash
# Ray throughput of the bidirectional integrators against the path tracer (issue 11: BDPT's
# rays/s >= 0.8x transient_path's on the same scene and threads). Each scene is rendered by
# transient_path, transient_bdpt and transient_light, interleaved, RUNS rounds, at 2 threads;
# the rate is the one `femto render` reports (rays traced, closest-hit and shadow, over the
# render time: no loading or writing). Ratios are taken within a round (the same load), and
# the table gives their median and range.
#   bench/run_ray_rate.sh [RUNS]      default 7; about 3 minutes on 2 cores once built
# Results: bench/results/ray_rate.csv, ray_rate.png, ray_rate_run.log.
set -euo pipefail

source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
bench_build  # everything: the CLI and its plugins
runs=${1:-7}
log="$results/ray_rate_run.log"
bench_log_header "$log"

work=$(mktemp -d)
trap 'rm -rf "$work"; remove_scene_copies' EXIT
integrators=(transient_path transient_bdpt transient_light)
csv="$results/ray_rate.csv"
echo "scene,integrator,run,seconds,mrays_per_s" > "$csv"
for run in $(seq 1 "$runs"); do
    for entry in "${ray_rate_scenes[@]}"; do
        scene=${entry%%|*}
        read -r -a defines <<< "${entry#*|}"
        for integrator in "${integrators[@]}"; do
            line=$(ray_rate_render "$build/bin/femto" "$scene" "$integrator" 2 "$work/out" \
                "${defines[@]}")
            read -r seconds rate <<< "$line"
            echo "$scene,$integrator,$run,$seconds,$rate" | tee -a "$csv"
        done
    done
done
echo "load average after the benchmark: $(cat /proc/loadavg)" | tee -a "$log"
/usr/bin/python3 - "$csv" "$results/ray_rate.png" <<'PY' | tee -a "$log"
import csv, statistics, sys
from collections import defaultdict
import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt
rows = list(csv.DictReader(open(sys.argv[1])))
rate = {(r["scene"], r["integrator"], r["run"]): float(r["mrays_per_s"]) for r in rows}
scenes = list(dict.fromkeys(r["scene"] for r in rows))
runs = sorted({r["run"] for r in rows}, key=int)
print("| scene | transient_path M rays/s | transient_bdpt M rays/s | BDPT / path, median [range] "
      "| transient_light M rays/s | light / path, median [range] |")
print("|---|---|---|---|---|---|")
ratios = defaultdict(list)
for s in scenes:
    cells = []
    for integ in ("transient_bdpt", "transient_light"):
        per_run = [rate[(s, integ, k)] / rate[(s, "transient_path", k)] for k in runs]
        ratios[(s, integ)] = per_run
        cells.append((statistics.median(rate[(s, integ, k)] for k in runs),
                      statistics.median(per_run), min(per_run), max(per_run)))
    path = statistics.median(rate[(s, "transient_path", k)] for k in runs)
    (b, rb, lo_b, hi_b), (l, rl, lo_l, hi_l) = cells
    print(f"| {s} | {path:.2f} | {b:.2f} | {rb:.2f} [{lo_b:.2f}, {hi_b:.2f}] | {l:.2f} | "
          f"{rl:.2f} [{lo_l:.2f}, {hi_l:.2f}] |")
fig, ax = plt.subplots(figsize=(6, 3.2))
for i, s in enumerate(scenes):
    for j, integ in enumerate(("transient_bdpt", "transient_light")):
        ys = ratios[(s, integ)]
        ax.plot([i + 0.15 * (2 * j - 1)] * len(ys), ys, "o", ms=4,
                color=("black", "tab:orange")[j], label=integ if i == 0 else None)
ax.axhline(0.8, color="tab:red", lw=1, ls="--", label="goal for BDPT (0.8)")
ax.set_xticks(range(len(scenes)), scenes)
ax.set_ylabel("rays/s over transient_path's")
ax.legend(fontsize=7)
ax.grid(True, alpha=0.3)
fig.tight_layout()
fig.savefig(sys.argv[2], dpi=110)
PY
echo
echo "results in $results: ray_rate.csv, ray_rate.png, ray_rate_run.log"
