#!/usr/bin/env python3
# Each run folder's median rays/s over Embree's raw incoherent and sorted rates (same scene and
# seed): bench/results/return-in-place/ray-rate/ratios.py FOLDER...
import csv,sys,statistics,glob
for d in sys.argv[1:]:
    raw={}
    for r in csv.DictReader(open(d+"/raw_rays.csv")):
        raw[(r["scene"],r["seed"],r["kind"])]=float(r["rays"])/float(r["seconds"])
    out=[]
    for r in csv.DictReader(open(d+"/results.csv")):
        rate=float(r["rays"])/float(r["seconds"])
        out.append((r["scene"], rate/raw[(r["scene"],r["seed"],"incoherent")], rate/raw[(r["scene"],r["seed"],"sorted")]))
    for sc in ("cornell-box","displaced-sphere"):
        inc=[o[1] for o in out if o[0]==sc]; so=[o[2] for o in out if o[0]==sc]
        print(d, sc, "vs incoherent %.3f  vs sorted %.3f"%(statistics.median(inc),statistics.median(so)))
