#!/usr/bin/env bash
# Peak memory of splatting (issue 11): scenes/cornell-box at 256x256 with a 1024-bin cube
# (768 MiB), rendered at 2 threads by transient_light (every vertex a splat) and, as the
# yardstick, transient_path, each RUNS times interleaved; peak RSS minus the same render with a
# 1-bin film (program, libraries, scene), over the cube's size (render + write).
#   bench/run_splat_memory.sh [RUNS]      default 3; about 2 minutes on 2 cores once built
# Results: bench/results/splat_memory.csv, splat_memory.png, splat_memory_run.log.
set -euo pipefail

source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
bench_build  # everything: the CLI and its plugins
runs=${1:-3}
log="$results/splat_memory_run.log"
bench_log_header "$log"

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
scene="$root/scenes/cornell-box/scene.xml"
cube_kib=$((256 * 256 * 1024 * 3 * 4 / 1024))
csv="$results/splat_memory.csv"
echo "integrator,run,bins,peak_kib,seconds" > "$csv"
for run in $(seq 1 "$runs"); do
    for integrator in transient_path transient_light; do
        for bins in 1 1024; do
            /usr/bin/time -f "%M %e" -o "$work/time.txt" "$build/bin/femto" render \
                "$scene" -D integrator=$integrator -D res=256 -D spp=8 -D bins=$bins --threads 2 -q \
                -o "$work/out"
            read -r peak seconds < "$work/time.txt"
            echo "$integrator,$run,$bins,$peak,$seconds" | tee -a "$csv"
        done
    done
done
echo "load average after the benchmark: $(cat /proc/loadavg)" | tee -a "$log"
/usr/bin/python3 - "$csv" "$cube_kib" "$results/splat_memory.png" <<'PY' | tee -a "$log"
import csv, statistics, sys
import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt
rows = list(csv.DictReader(open(sys.argv[1])))
cube = float(sys.argv[2])
ratios = {}
for integ in ("transient_path", "transient_light"):
    base = statistics.median(float(r["peak_kib"]) for r in rows if r["integrator"] == integ and r["bins"] == "1")
    peaks = [float(r["peak_kib"]) for r in rows if r["integrator"] == integ and r["bins"] == "1024"]
    ratios[integ] = [(p - base) / cube for p in peaks]
    print(f"{integ}: (peak - 1-bin baseline) / cube = median {statistics.median(ratios[integ]):.3f} "
          f"over {len(peaks)} runs (baseline {base / 1024:.0f} MiB, cube {cube / 1024:.0f} MiB)")
plt.figure(figsize=(5, 3.5))
plt.boxplot(list(ratios.values()), labels=list(ratios.keys()))
plt.axhline(1.5, color="r", ls="--", label="budget 1.5x")
plt.ylabel("(peak RSS - baseline) / cube")
plt.title("cornell-box 256x256x1024, 2 threads")
plt.legend()
plt.tight_layout()
plt.savefig(sys.argv[3], dpi=120)
PY
