"""Ratios of ab.sh's runs: each run's rays/s over Embree's raw rate measured just before it
(incoherent for the Cornell box, sorted for the mesh, as issue 17's goals name them), and NEW
over OLD rays/s paired by thread count, round, scene and seed.
    python3 ratio.py OUT > OUT/ab.csv"""
import csv, glob, os, re, statistics, sys

out_dir = sys.argv[1]
yardstick = {'cornell-box': 'incoherent', 'displaced-sphere': 'sorted'}
rows = []
for d in sorted(glob.glob(os.path.join(out_dir, '*-t*-r*'))):
    if not os.path.isdir(d):
        continue
    build, threads, rnd = re.match(r'(\w+)-t(\d+)-r(\d+)$', os.path.basename(d)).groups()
    raw = {(x['scene'], x['seed'], x['kind']): float(x['rays']) / float(x['seconds'])
           for x in csv.DictReader(open(os.path.join(d, 'raw_rays.csv')))}
    for x in csv.DictReader(open(os.path.join(d, 'results.csv'))):
        rate = float(x['rays']) / float(x['seconds'])
        ref = raw[(x['scene'], x['seed'], yardstick[x['scene']])]
        rows.append((int(threads), int(rnd), build, x['scene'], x['seed'], rate, rate / ref))

w = csv.writer(sys.stdout)
w.writerow(['threads', 'round', 'build', 'scene', 'seed', 'rays_per_s', 'over_raw'])
w.writerows(rows)
for t in sorted({r[0] for r in rows}):
    for scene in yardstick:
        sel = [r for r in rows if r[0] == t and r[3] == scene]
        if not sel:
            continue
        for b in ('old', 'new'):
            v = [r[6] for r in sel if r[2] == b]
            print(f'# {scene}, {t} thread(s), {b}: over raw {yardstick[scene]} median '
                  f'{statistics.median(v):.3f} [{min(v):.3f}, {max(v):.3f}] n={len(v)}',
                  file=sys.stderr)
        pairs = []
        for key in {(r[1], r[4]) for r in sel}:
            o = [r[5] for r in sel if (r[1], r[4]) == key and r[2] == 'old']
            n = [r[5] for r in sel if (r[1], r[4]) == key and r[2] == 'new']
            if o and n:
                pairs.append(n[0] / o[0])
        print(f'# {scene}, {t} thread(s): new/old rays/s paired median '
              f'{statistics.median(pairs):.3f} [{min(pairs):.3f}, {max(pairs):.3f}] '
              f'n={len(pairs)}', file=sys.stderr)
