#!/usr/bin/python3
"""Plots femto_bench_transient's results.

    /usr/bin/python3 bench/plot_transient.py [RESULTS_DIR]

Writes RESULTS_DIR/transient_throughput.png (samples/s per variant and thread count, with the
transient/steady ratio, next to peak memory against the cube's size) and
RESULTS_DIR/transient_error.png (relative MSE against render time, log-log, one line per
label, with a slope -1 guide).
"""
import csv
import os
import statistics
import sys
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def rows(path):
    if not os.path.exists(path):
        return []
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def plot_throughput(results):
    runs = rows(os.path.join(results, "transient_throughput.csv"))
    mem = rows(os.path.join(results, "transient_memory_summary.csv"))
    if not runs and not mem:
        return None
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2), gridspec_kw={"width_ratios": [3, 2]})
    ax = axes[0]
    if runs:
        variants = list(dict.fromkeys(r["variant"] for r in runs))
        threads = sorted({int(r["threads"]) for r in runs})
        per = defaultdict(list)
        for r in runs:
            per[(r["variant"], int(r["threads"]))].append(float(r["samples_per_s"]) * 1e-6)
        width = 0.8 / len(variants)
        colors = {"steady": "#4c72b0", "tpath_hdr": "#8172b2", "transient": "#dd8452"}
        for i, v in enumerate(variants):
            xs = [t + (i - (len(variants) - 1) / 2) * width for t in range(len(threads))]
            meds = [statistics.median(per[(v, t)]) for t in threads]
            ax.bar(xs, meds, width, label=v, color=colors.get(v))
            for x, t in zip(xs, threads):  # every run as a dot
                ax.plot([x] * len(per[(v, t)]), per[(v, t)], "k.", ms=3)
            for x, t, m in zip(xs, threads, meds):
                base = statistics.median(per[("steady", t)])
                ax.annotate(f"{m / base:.2f}x", (x, m), ha="center", va="bottom", fontsize=8)
        ax.set_xticks(range(len(threads)))
        ax.set_xticklabels([f"{t} thread{'s' if t > 1 else ''}" for t in threads])
        r0 = runs[0]
        bins = max(int(r["bins"]) for r in runs)
        ax.set_title(f"Cornell box {r0['res']}², {r0['spp']} spp, max_depth {r0['max_depth']}; "
                     f"transient = {bins} bins", fontsize=10)
        ax.set_ylabel("M camera samples / s (median; dots = runs)")
        ax.legend(fontsize=8, loc="upper left")
    ax = axes[1]
    if mem:
        m = mem[0]
        cube = float(m["cube_mib"])
        base = float(m["baseline_peak_mib"])
        labels = ["baseline\n(1-bin film)", "render", "render\n+ write"]
        vals = [base, float(m["render_peak_mib"]), float(m["write_peak_mib"])]
        ax.bar(labels, vals, color=["#999999", "#dd8452", "#c44e52"])
        ax.axhline(base + cube, color="k", ls=":", lw=1, label=f"baseline + cube ({cube:.0f} MiB)")
        ax.axhline(base + 1.25 * cube, color="r", ls="--", lw=1, label="baseline + 1.25 x cube")
        for i, v in enumerate(vals[1:], 1):
            ax.annotate(f"{(v - base) / cube:.2f}x cube", (i, v), ha="center", va="bottom",
                        fontsize=8)
        ax.set_ylabel("peak RSS (MiB)")
        ax.set_title("256x256x1024 RGB transient render, 1 spp", fontsize=10)
        ax.legend(fontsize=7, loc="upper left")
    fig.tight_layout()
    out = os.path.join(results, "transient_throughput.png")
    fig.savefig(out, dpi=110)
    return out


def plot_error(results):
    runs = rows(os.path.join(results, "transient_error.csv"))
    if not runs:
        return None
    per = defaultdict(lambda: defaultdict(lambda: ([], [])))
    for r in runs:
        key = f"{r['label']} ({r['integrator']}, {r['tfilter']})"
        s, e = per[key][int(r["spp"])]
        s.append(float(r["seconds"]))
        e.append(float(r["relmse"]))
    fig, ax = plt.subplots(figsize=(6.5, 4.5))
    lo_t, hi_e = None, None
    for key, by_spp in per.items():
        spps = sorted(by_spp)
        ts = [statistics.median(by_spp[s][0]) for s in spps]
        es = [statistics.median(by_spp[s][1]) for s in spps]
        ax.loglog(ts, es, "o-", label=key)
        for s in spps:
            ax.plot(by_spp[s][0], by_spp[s][1], ".", color="0.6", ms=3)
        for t, e, s in zip(ts, es, spps):
            ax.annotate(f"{s}", (t, e), textcoords="offset points", xytext=(4, 3), fontsize=7)
        if lo_t is None:
            lo_t, hi_e, hi_t = ts[0], es[0], ts[-1]
    if lo_t:
        ax.loglog([lo_t, hi_t], [hi_e, hi_e * lo_t / hi_t], "k--", lw=1, label="slope -1")
    ax.set_xlabel("render time (s, median of seeds)")
    ax.set_ylabel("relMSE = Σ(x − ref)² / Σ ref²")
    ax.set_title("Cornell box cube: error against time (labels = spp)", fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    out = os.path.join(results, "transient_error.png")
    fig.savefig(out, dpi=110)
    return out


def main():
    results = sys.argv[1] if len(sys.argv) > 1 else os.path.join(
        os.path.dirname(os.path.abspath(__file__)), "results")
    for out in (plot_throughput(results), plot_error(results)):
        if out:
            print("wrote", out)


if __name__ == "__main__":
    main()
