import csv, glob, os, statistics, sys, re
base = sys.argv[1]
rows = []
for d in sorted(glob.glob(os.path.join(base, '*-t*-r*'))):
    if not os.path.isdir(d): continue
    m = re.match(r'(\w+)-t(\d)-r(\d+)', os.path.basename(d))
    v, t, r = m.group(1), int(m.group(2)), int(m.group(3))
    raw = {}
    for x in csv.DictReader(open(os.path.join(d, 'raw_rays.csv'))):
        if x['kind'] == 'incoherent': raw[x['seed']] = float(x['rays']) / float(x['seconds'])
    for x in csv.DictReader(open(os.path.join(d, 'results.csv'))):
        rate = float(x['rays']) / float(x['seconds'])
        rows.append((t, r, v, x['seed'], rate, rate / raw[x['seed']]))
out = csv.writer(sys.stdout)
out.writerow(['threads', 'round', 'build', 'seed', 'rays_per_s', 'over_raw_incoherent'])
for row in rows: out.writerow(row)
print()
for t in sorted({r[0] for r in rows}):
    for v in ('old', 'new'):
        rr = [r[5] for r in rows if r[0] == t and r[2] == v]
        print(f'# threads {t} {v}: over raw median {statistics.median(rr):.3f} [{min(rr):.3f}, {max(rr):.3f}] n={len(rr)}')
    pairs = []
    for rd in sorted({r[1] for r in rows if r[0] == t}):
        for s in sorted({r[3] for r in rows}):
            o = [r[4] for r in rows if r[0] == t and r[1] == rd and r[3] == s and r[2] == 'old']
            n = [r[4] for r in rows if r[0] == t and r[1] == rd and r[3] == s and r[2] == 'new']
            if o and n: pairs.append(n[0] / o[0])
    print(f'# threads {t}: new/old rays/s, same round and seed: median {statistics.median(pairs):.3f} [{min(pairs):.3f}, {max(pairs):.3f}] n={len(pairs)}')
