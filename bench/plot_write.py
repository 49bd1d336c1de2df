#!/usr/bin/python3
"""Plots femto_bench_write's results.

    /usr/bin/python3 bench/plot_write.py [RESULTS_DIR]

Writes RESULTS_DIR/write.png: left, the median wall seconds of writing the 256x256x256 cube per
variant (bars, file size in MiB on each) with the every-round points; right, (peak RSS -
baseline) / cube size of render and of render + write against the number of bins of a 16x16
film (and the 256x256x256 case), with the 1.25 budget.
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


def plot_speed(ax, runs):
    per = defaultdict(list)
    size = {}
    for r in runs:
        per[r["variant"]].append(float(r["wall_seconds"]))
        size[r["variant"]] = int(r["bytes"]) / 2**20
    names = list(dict.fromkeys(r["variant"] for r in runs))
    medians = [statistics.median(per[n]) for n in names]
    colours = ["tab:grey" if n == "baseline" else "tab:blue" if n.startswith("exr") else "tab:green"
               for n in names]
    ax.barh(names, medians, color=colours)
    for i, n in enumerate(names):
        ax.plot(per[n], [i] * len(per[n]), "k.", ms=3)
        ax.text(medians[i], i, f" {size[n]:.0f} MiB", va="center", fontsize=7)
    ax.axvline(2.0, color="tab:red", ls="--", lw=1, label="2 s goal")
    ax.invert_yaxis()
    ax.set_xlabel("wall seconds (median; dots: every round)")
    ax.set_title("writing a 256×256×256 cube")
    ax.legend(fontsize=8)


def plot_memory(ax, mem):
    small = [r for r in mem if r["res"] == "16"]
    bins = [int(r["bins"]) for r in small]
    ax.plot(bins, [float(r["render_ratio"]) for r in small], "o-", label="render (16×16 film)")
    ax.plot(bins, [float(r["write_ratio"]) for r in small], "s-", label="render + write (16×16)")
    for r in mem:
        if r["res"] == "256":
            ax.plot([int(r["bins"])], [float(r["write_ratio"])], "r*", ms=10,
                    label="render + write (256×256)")
    ax.axhline(1.25, color="tab:red", ls="--", lw=1, label="1.25 budget")
    ax.set_xscale("log", base=2)
    ax.set_xlabel("bins")
    ax.set_ylabel("(peak RSS − 1-bin baseline) / cube")
    ax.set_title("peak memory")
    ax.legend(fontsize=8)


def main():
    results = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), "results")
    runs = rows(os.path.join(results, "write_speed.csv"))
    mem = rows(os.path.join(results, "write_memory.csv"))
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.5), gridspec_kw={"width_ratios": [3, 2]})
    if runs:
        plot_speed(axes[0], runs)
    if mem:
        plot_memory(axes[1], mem)
    fig.tight_layout()
    out = os.path.join(results, "write.png")
    fig.savefig(out, dpi=110)
    print("wrote", out)


if __name__ == "__main__":
    main()
