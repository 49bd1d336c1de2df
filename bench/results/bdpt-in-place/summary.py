# Summary of ab-*.csv: per round, the new plugin's time over the old one's, and each build's BDPT rays/s over the
# path tracer's of the same round (median [min, max]). Usage: python3 summary.py ab-2-threads.csv ab-1-thread.csv
import csv, statistics, sys
for f in sys.argv[1:]:
    rows = list(csv.DictReader(open(f)))
    by = {}
    for r in rows: by[(r['round'], r['build'])] = float(r['mrays'])
    rounds = sorted({r['round'] for r in rows}, key=int)
    sp = [by[(k,'old')]/by[(k,'new')] for k in rounds]  # time new/old = rate old/new
    ro = [by[(k,'old')]/by[(k,'path')] for k in rounds]
    rn = [by[(k,'new')]/by[(k,'path')] for k in rounds]
    m = statistics.median
    print(f"{f}: time new/old {m(sp):.3f} [{min(sp):.3f},{max(sp):.3f}]  bdpt/path old {m(ro):.3f} [{min(ro):.3f},{max(ro):.3f}]  new {m(rn):.3f} [{min(rn):.3f},{max(rn):.3f}]")
