#!/usr/bin/env bash
# What a femto process costs besides rendering: the wall time of `femto --version`, of a 16x16,
# 1-sample render of scenes/cornell-box (loading, a few milliseconds of rendering, writing),
# of a 1-sample render into a large cube (the Cornell box at 256x256 x 1024 bins, 805 MB:
# setting the film up and writing it dominate), and of `femto viz peak-time` reading that cube
# back, for two builds side by side:
#
#     bench/run_startup.sh BUILD_A BUILD_B [ROUNDS]
#
# BUILD_A and BUILD_B are build folders (each with bin/femto and its plugins; the same folder
# twice is an A/A run). Each round runs the four commands with both builds, the builds' order
# alternating from round to round. ROUNDS default 15 (about 5 minutes). Also prints how many
# shared libraries each build's femto loads (ldd). Results: bench/results/startup.csv (`round,
# build,command,seconds`), startup.png, startup_run.log.
set -euo pipefail

source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
if [[ $# -lt 2 ]]; then
    sed -n '2,14p' "$0"
    exit 2
fi
builds=("$1" "$2")
rounds=${3:-15}
for b in "${builds[@]}"; do
    [[ -x "$b/bin/femto" ]] || { echo "run_startup.sh: no $b/bin/femto" >&2; exit 2; }
done
log="$results/startup_run.log"
bench_log_header "$log"
names=(A B)
for i in 0 1; do
    echo "build ${names[$i]}: ${builds[$i]} ($(ldd "${builds[$i]}/bin/femto" | wc -l) shared libraries)" |
        tee -a "$log"
done

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
csv="$results/startup.csv"
echo "round,build,command,seconds" > "$csv"
seconds_of() {  # runs the command, prints its wall time in seconds
    local t0 t1
    t0=$(date +%s%N)
    "$@" > /dev/null
    t1=$(date +%s%N)
    awk -v ns=$((t1 - t0)) 'BEGIN { printf "%.4f\n", ns / 1e9 }'
}
for round in $(seq 1 "$rounds"); do
    order=(0 1)
    ((round % 2 == 0)) && order=(1 0)
    for i in "${order[@]}"; do
        femto="${builds[$i]}/bin/femto" name=${names[$i]}
        echo "$round,$name,version,$(seconds_of "$femto" --version)" >> "$csv"
        echo "$round,$name,render,$(seconds_of "$femto" render "$root/scenes/cornell-box/scene.xml" \
            -D res=16 --spp 1 -q -o "$work/out")" >> "$csv"
        echo "$round,$name,cube,$(seconds_of "$femto" render \
            "$root/bench/experiments/scenes/cornell-films.xml" -D res=256 --spp 1 -q \
            -o "$work/cube")" >> "$csv"
        echo "$round,$name,viz,$(seconds_of "$femto" viz peak-time "$work/cube.exr" \
            -o "$work/peak.png")" >> "$csv"
    done
done
echo "load average after the benchmark: $(cat /proc/loadavg)" | tee -a "$log"
/usr/bin/python3 - "$csv" "$results/startup.png" <<'PY' | tee -a "$log"
import csv, statistics, sys
import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt
rows = list(csv.DictReader(open(sys.argv[1])))
sec = {}
for r in rows:
    sec.setdefault((r["build"], r["command"]), []).append(float(r["seconds"]))
commands = ["version", "render", "cube", "viz"]
print("| command | A: s, median [range] | B: s, median [range] | B / A (medians) |")
print("|---|---|---|---|")
fig, ax = plt.subplots(figsize=(7, 3))
for i, c in enumerate(commands):
    a, b = sec[("A", c)], sec[("B", c)]
    print(f"| {c} | {statistics.median(a):.3f} [{min(a):.3f}, {max(a):.3f}] | "
          f"{statistics.median(b):.3f} [{min(b):.3f}, {max(b):.3f}] | "
          f"{statistics.median(b) / statistics.median(a):.3f} |")
    ax.plot([i - 0.1] * len(a), a, "o", ms=4, color="tab:gray", label="A" if i == 0 else None)
    ax.plot([i + 0.1] * len(b), b, "o", ms=4, color="tab:blue", label="B" if i == 0 else None)
ax.set_xticks(range(len(commands)),
              ["femto --version", "16x16 1-spp\nrender", "256x256x1024\n1-spp render",
               "viz peak-time\nof that cube"])
ax.set_xlim(-0.5, len(commands) - 0.5)
ax.set_ylim(bottom=0)
ax.set_ylabel("wall time per process (s)")
ax.legend(fontsize=7)
ax.grid(True, alpha=0.3)
fig.tight_layout()
fig.savefig(sys.argv[2], dpi=110)
PY
echo
echo "results in $results: startup.csv, startup.png, startup_run.log"
