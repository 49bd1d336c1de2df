#!/usr/bin/env bash
# Builds femto with the benchmarks, runs femto_bench_media (the time-sampling strategies of
# ch. 5.6 against steady sampling on scenes/fog-object: Fig. 5.8-5.10 and every strategy
# combination against wall clock) and plots the results.
#   bench/run_media.sh [femto_bench_media options...]     e.g. --seeds 5
# Results: bench/results/media_*.{csv,txt,md,png}, media_run.log. About 13 minutes on the
# 2-core machine once built; the first run adds ~5 minutes of references (then cached as
# ref_media_*.npy).
set -euo pipefail

source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
bench_build femto_bench_media

log="$results/media_run.log"
bench_log_header "$log"
"$build/bin/femto_bench_media" --out "$results" "$@" 2>&1 | tee -a "$log"
echo "load average after the benchmark: $(cat /proc/loadavg)" | tee -a "$log"

# Debian's Python has matplotlib (a pyenv python3 on PATH may not).
/usr/bin/python3 "$root/bench/plot_media.py" "$results" | tee -a "$log"

echo
echo "results in $results:"
echo "  media_error.csv     every render: time and the error measures"
echo "  media_frames.csv    per frame error, pixel (a) profile and sample counts (first seed)"
echo "  media_ratio.csv     equal-error sample and time ratios of the time strategies"
echo "  media_combos.csv    every strategy combination: median error, time, efficiency"
echo "  media_tables.md     the tables quoted in bench/README.md"
echo "  media_error.png, media_profiles.png, media_error_time.png, media_single.png,"
echo "  media_combos.png, media_meta.txt, media_run.log"
