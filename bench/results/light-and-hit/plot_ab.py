"""Plot of ab.csv (ratio.py's output): each run's rays/s over Embree's raw rate, before (old)
and after (new), per scene and thread count.
    /usr/bin/python3 plot_ab.py ab.csv ab.png [OLD_LABEL [TITLE]] (defaults: this folder's)"""
import csv, sys
import matplotlib
matplotlib.use('Agg')
import matplotlib.pyplot as plt

old_label = sys.argv[3] if len(sys.argv) > 3 else 'git 222dac6'
rows = list(csv.DictReader(r for r in open(sys.argv[1]) if r.strip() and not r.startswith('#')))
panels = [(s, t) for s in ('cornell-box', 'displaced-sphere') for t in ('1', '2')]
fig, axes = plt.subplots(1, 4, figsize=(13, 3.6), sharey=True)
for ax, (scene, threads) in zip(axes, panels):
    for x, build in enumerate(('old', 'new')):
        v = [float(r['over_raw']) for r in rows
             if r['scene'] == scene and r['threads'] == threads and r['build'] == build]
        ax.plot([x + (i % 3 - 1) * 0.08 for i in range(len(v))], v, 'o', alpha=0.6)
        ax.hlines(sorted(v)[len(v) // 2], x - 0.25, x + 0.25, color='k')
    goal = 0.7 if scene == 'cornell-box' else 0.8
    ax.axhline(goal, ls='--', color='grey')
    ax.set_xticks([0, 1], [old_label, 'after'])
    ax.set_title(f'{scene}, {threads} thread(s)', fontsize=9)
axes[0].set_ylabel("rays/s over Embree's raw rate\n(box: incoherent, mesh: sorted)")
title = sys.argv[4] if len(sys.argv) > 4 else 'light samples and hit records for less'
fig.suptitle(f'path: {title} (dashed: goal)', fontsize=10)
fig.tight_layout()
fig.savefig(sys.argv[2], dpi=110)
