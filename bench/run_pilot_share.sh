#!/usr/bin/env bash
# The kernel filter's pilot share of a 16-spp render (issue 17: halved). The Cornell box at
# 128x128, 256 bins of 0.05, `transient_path`, 16 spp, all threads (default 2), rendered in
# every round with: the histogram; the kernel with a fixed bandwidth (no pilot: the kernel's own
# cost); the kernel with its 64-spp pilot as a separate pass (pilot_in_image false); and with
# the pilot as the image's first samples (the default). The order rotates from round to round.
# Pilot share = 1 - (the fixed-bandwidth kernel's time / the variant's time), per round: what
# the render spends beyond the kernel's own splatting. For the separate pilot, femto also
# reports the pilot pass's own time; its share of the render is printed beside.
#   bench/run_pilot_share.sh [RUNS] [THREADS]     defaults 9 and 2; about 2 minutes on 2 cores
# Results: bench/results/pilot-share.csv, pilot-share.png, pilot-share_run.log.
set -euo pipefail

source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
bench_build
runs=${1:-9}
threads=${2:-2}
log="$results/pilot-share_run.log"
bench_log_header "$log"
echo "cores used: $threads of $(nproc)" | tee -a "$log"

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
variants=(
    "histogram|-D tfilter=histogram"
    "kernel-fixed-bandwidth|-D tfilter=kernel-bandwidth"
    "pilot-separate|-D tfilter=kernel -D pilot_in_image=false"
    "pilot-in-image|-D tfilter=kernel -D pilot_in_image=true"
)
xml="$root/bench/experiments/scenes/cornell-films.xml"
csv="$results/pilot-share.csv"
echo "variant,run,seconds,pilot_seconds" > "$csv"
for run in $(seq 1 "$runs"); do
    for i in $(seq 0 $((${#variants[@]} - 1))); do
        IFS='|' read -r name defs <<< "${variants[$(((i + run) % ${#variants[@]}))]}"
        read -r -a defines <<< "$defs"
        out=$("$build/bin/femto" render "$xml" -D res=128 -D spp=16 -D bins=256 \
            -D bin_width=0.05 "${defines[@]}" --threads "$threads" --seed "$run" \
            -o "$work/out" 2>&1)
        # (the EXR header's render time has milliseconds; the terminal line rounds to 10 ms)
        seconds=$(oiiotool --info -v "$work/out.exr" | sed -n 's/.*femto:render_seconds: //p')
        pilot=$(echo "$out" | grep -o "pilot pass took [0-9.]* s" | grep -o "[0-9.]*" || echo 0)
        echo "$name,$run,$seconds,$pilot" | tee -a "$csv"
    done
done
echo "load average after the benchmark: $(cat /proc/loadavg)" | tee -a "$log"
/usr/bin/python3 - "$csv" "$results/pilot-share.png" <<'PY' | tee -a "$log"
import csv, statistics, sys
import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt
rows = list(csv.DictReader(open(sys.argv[1])))
sec = {(r["variant"], r["run"]): float(r["seconds"]) for r in rows}
pilot = {(r["variant"], r["run"]): float(r["pilot_seconds"]) for r in rows}
variants = list(dict.fromkeys(r["variant"] for r in rows))
runs = sorted({r["run"] for r in rows}, key=int)
base = "kernel-fixed-bandwidth"
print("| variant | render s (median) | share beyond the fixed-bandwidth kernel, median [range] "
      "| pilot pass's own share, median |")
print("|---|---|---|---|")
fig, ax = plt.subplots(figsize=(6, 3))
for i, v in enumerate(variants):
    share = [1 - sec[(base, k)] / sec[(v, k)] for k in runs]
    own = [pilot[(v, k)] / sec[(v, k)] for k in runs]
    print(f"| {v} | {statistics.median(sec[(v, k)] for k in runs):.3f} | "
          f"{statistics.median(share):.3f} [{min(share):.3f}, {max(share):.3f}] | "
          f"{statistics.median(own):.3f} |")
    ax.plot([i] * len(share), share, "o", ms=4, color="black")
ax.axhline(0, color="gray", lw=1)
ax.set_xticks(range(len(variants)), variants, fontsize=7)
ax.set_ylabel("1 - t(fixed bandwidth) / t(variant)")
ax.grid(True, alpha=0.3)
fig.tight_layout()
fig.savefig(sys.argv[2], dpi=110)
PY
