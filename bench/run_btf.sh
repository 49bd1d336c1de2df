#!/usr/bin/env bash
# Prefiltered BTF rendering against multisampling on scenes/btf-sphere (issue 16 §4, thesis
# ch. 3, Experiment 1): RMSE and SSIM against a 4096-spp reference at five texel-to-pixel
# ratios, equal-error speed-ups, the hierarchy's build time and size, and the bound on any
# prefiltering's speed-up (--bound).
#   bench/run_btf.sh [--quick]       about 20 minutes on 2 cores once built (BTF B: 40; --quick: 4)
#   bench/run_btf.sh --res R --ref-spp N --runs K --max-spp M   other settings
#   bench/run_btf.sh --btf b         BTF B (V-grooves, made at bench time) instead of BTF A
# Results: bench/results/btf/ (BTF A) or bench/results/btf-b/ (BTF B): btf_runs.csv,
# btf_speedup.csv, btf_build.csv, btf_cost.csv, btf_bound.csv, btf.png, btf_run.log.
set -euo pipefail

source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
bench_build  # the CLI and its plugins
"$root/scripts/deps.sh"  # python3-skimage for the SSIM
btf=a
for ((i = 0; i + 1 < $#; i++)); do
    a=("$@"); if [[ ${a[i]} == --btf ]]; then btf=${a[i + 1]}; fi
done
out="$results/btf"
if [[ $btf == b ]]; then out="$results/btf-b"; fi
mkdir -p "$out"
log="$out/btf_run.log"
bench_log_header "$log"
/usr/bin/python3 "$root/bench/btf.py" "$build/bin/femto" "$out" "$@" 2>&1 | tee -a "$log"
# The time per sample of each mode at 64 spp (femto prints times to 0.01 s, which the 1-spp
# renders at the far distances reach), then the speed-ups again with it.
res=128
for ((i = 0; i + 1 < $#; i++)); do
    a=("$@"); if [[ ${a[i]} == --res ]]; then res=${a[i + 1]}; fi
done
if [[ " $* " == *" --quick "* ]]; then res=32; fi
echo "time per sample (--cost):" | tee -a "$log"
/usr/bin/python3 "$root/bench/btf.py" "$build/bin/femto" "$out" --cost --btf "$btf" --res "$res" 2>&1 | tee -a "$log"
# The speed-up no prefiltering can exceed at 1 spp (btf_bound.csv; bench/README.md).
echo "bound (--bound):" | tee -a "$log"
bound_args=(--btf "$btf" --res "$res")
if [[ " $* " == *" --quick "* ]]; then bound_args+=(--ref-spp 256 --runs 1); fi
/usr/bin/python3 "$root/bench/btf.py" "$build/bin/femto" "$out" --bound "${bound_args[@]}" 2>&1 | tee -a "$log"
echo "load average after the benchmark: $(cat /proc/loadavg)" | tee -a "$log"
