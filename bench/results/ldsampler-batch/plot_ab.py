#!/usr/bin/env python3
"""path-box-ab.png: each run's rays/s over Embree's raw incoherent rate, git 3da56d1's
ldsampler ("old") against the batched one ("new"), by thread count (path-box-ab.csv, from
rate_ratio.py); and BDPT / path rays/s per round on issue 11's box (bdpt-path-box-ab.csv)."""
import csv
import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt

rows = [r for r in csv.DictReader(open("path-box-ab.csv")) if r.get("threads", "").isdigit()]
fig, (a, b) = plt.subplots(1, 2, figsize=(9, 3.6))
for k, (t, v) in enumerate([(1, "old"), (1, "new"), (2, "old"), (2, "new")]):
    ys = [float(r["over_raw_incoherent"]) for r in rows if int(r["threads"]) == t and r["build"] == v]
    a.plot([k + (i - len(ys) / 2) * 0.02 for i in range(len(ys))], ys, "o", ms=4,
           color="tab:gray" if v == "old" else "tab:blue")
a.set_xticks(range(4), ["1 thread\nold", "1 thread\nnew", "2 threads\nold", "2 threads\nnew"])
a.axhline(0.7, color="tab:red", lw=1, ls="--", label="issue 17's goal")
a.set_ylabel("path rays/s over Embree raw incoherent")
a.legend(loc="lower right", fontsize=8)
a.set_title("Cornell box, 256x256, 8 spp", fontsize=9)
bd = list(csv.DictReader(open("bdpt-path-box-ab.csv")))
for v, c in (("old", "tab:gray"), ("hyb3", "tab:blue")):
    rs = sorted({r["round"] for r in bd})
    ratio = []
    for rd in rs:
        d = {r["integrator"]: float(r["mrays"]) for r in bd if r["round"] == rd and r["build"] == v}
        ratio.append(d["bdpt"] / d["path"])
    b.plot([int(x) for x in rs], ratio, "o-", color=c, label="old" if v == "old" else "new")
b.axhline(0.8, color="tab:red", lw=1, ls="--", label="issue 11's goal")
b.set_xlabel("round")
b.set_ylabel("BDPT / path rays/s")
b.set_title("issue 11's box, 64x64, 256 spp, 2 threads", fontsize=9)
b.legend(fontsize=8)
fig.tight_layout()
fig.savefig("path-box-ab.png", dpi=110)
