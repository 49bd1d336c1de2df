#!/usr/bin/python3
"""Plots femto_bench_ceiling's results.

    /usr/bin/python3 bench/plot_ceiling.py RESULTS.csv

Writes RESULTS.png beside it: nanoseconds per ray of each variant (median bar, every round as a
point), with the times per ray that 1.0x and 0.7x Embree's raw incoherent rate allow.
"""
import csv
import os
import statistics
import sys
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main(path):
    with open(path, newline="") as f:
        header = f.readline().lstrip("# ").strip()
        rows = list(csv.DictReader(f))
    ns = defaultdict(list)
    for r in rows:
        ns[r["variant"]].append(1e9 / float(r["rays_per_s"]))
    variants = list(dict.fromkeys(r["variant"] for r in rows))
    raw = statistics.median(ns["raw incoherent"])
    fig, ax = plt.subplots(figsize=(9, 4.5))
    for i, v in enumerate(variants):
        ax.barh(i, statistics.median(ns[v]), color="#8fb3d9" if v != "femto path" else "#d98f8f")
        ax.plot(ns[v], [i] * len(ns[v]), "k.", markersize=3)
        ax.text(max(ns[v]) + 3, i, f"{statistics.median(ns[v]):.0f} ns", va="center")
    ax.axvline(raw, color="k", linewidth=1)
    ax.axvline(raw / 0.7, color="g", linestyle="--", linewidth=1)
    ax.text(raw, len(variants) - 0.4, " raw rate", fontsize=8)
    ax.text(raw / 0.7, len(variants) - 0.4, " 0.7x raw (issue 17)", fontsize=8, color="g")
    ax.set_yticks(range(len(variants)))
    ax.set_yticklabels(variants)
    ax.invert_yaxis()
    ax.set_xlabel("wall-clock nanoseconds per ray (camera, bounce and shadow rays)")
    ax.set_title(header[:110], fontsize=7)
    fig.tight_layout()
    out = os.path.splitext(path)[0] + ".png"
    fig.savefig(out, dpi=110)
    print("wrote", out)


if __name__ == "__main__":
    main(sys.argv[1])
