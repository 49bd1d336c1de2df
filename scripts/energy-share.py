#!/usr/bin/python3
"""Share of a render's energy held by its brightest pixels: a measure of speckle (a few
fireflies hold much of the energy when a scene is under-sampled).

    /usr/bin/python3 scripts/energy-share.py OUTBASE.npy [TOP_PERCENT]     (default 1)

Reads the cube `femto render --npy` writes (float32 [H, W, T, C]), integrates it over time
into the steady image, and prints the share of its total luminance held by the brightest
TOP_PERCENT of the pixels. A smooth image of a scene with no small bright features holds
little more than TOP_PERCENT there.
"""
import sys

import numpy as np


def main():
    if len(sys.argv) not in (2, 3):
        sys.exit(__doc__)
    top = float(sys.argv[2]) if len(sys.argv) == 3 else 1.0
    cube = np.load(sys.argv[1], mmap_mode="r")
    steady = cube.sum(axis=2, dtype=np.float64)
    lum = 0.2126 * steady[..., 0] + 0.7152 * steady[..., 1] + 0.0722 * steady[..., 2]
    values = np.sort(lum.ravel())[::-1]
    count = max(1, int(round(values.size * top / 100.0)))
    total = values.sum()
    share = values[:count].sum() / total if total > 0 else 0.0
    print(f"{sys.argv[1]}: the brightest {top:g} % of {values.size} pixels hold "
          f"{100.0 * share:.1f} % of the energy")


if __name__ == "__main__":
    main()
