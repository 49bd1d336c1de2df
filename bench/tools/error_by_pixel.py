#!/usr/bin/env python3
"""Where a cube's error is: the share of its relMSE that each pixel carries.

    bench/tools/error_by_pixel.py REFERENCE_MEAN.npy [--variance REFERENCE_VARIANCE.npy] RENDER.npy...

REFERENCE_MEAN and REFERENCE_VARIANCE are what `femto bench` keeps in
OUT/cache/reference-SCENE-HASH-{mean,variance}.npy; each RENDER is a `femto render --npy` cube
of the same shape [H, W, T, C]. For each render: its relMSE (docs/bench.md: the reference's
variance taken out per voxel when given), the share of it in the 1, 5, 20 and 100 pixels that
carry most, and those pixels with their share and reference energy. A cube's L2 error is often
a few bright pixels; this says which, so that an integrator's gain elsewhere is not hidden.
"""
import argparse
import sys

import numpy as np


def main():
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("reference", help="the reference cube's mean (.npy)")
    parser.add_argument("renders", nargs="+", help="cubes to measure (.npy)")
    parser.add_argument("--variance", help="the reference's per-voxel variance (.npy)")
    args = parser.parse_args()
    ref = np.load(args.reference).astype(np.float64)
    renders = args.renders
    var = np.zeros_like(ref)
    if args.variance:
        var = np.load(args.variance).astype(np.float64)
        if var.shape != ref.shape:
            sys.exit(f"{args.variance}: shape {var.shape}, the reference's is {ref.shape}")
    norm = (ref ** 2).sum()
    energy = ref.sum(axis=(2, 3))
    print(f"reference {ref.shape}, its own noise (relMSE) {var.sum() / norm:.3g}")
    for path in renders:
        x = np.load(path).astype(np.float64)
        if x.shape != ref.shape:
            sys.exit(f"{path}: shape {x.shape}, the reference's is {ref.shape}")
        err = (x - ref) ** 2 - var
        total = err.sum()
        per_pixel = err.sum(axis=(2, 3)).ravel()
        order = np.argsort(per_pixel)[::-1]
        share = np.cumsum(per_pixel[order]) / total
        width = ref.shape[1]
        print(f"{path}: relMSE {total / norm:.4g}; share in the top 1 / 5 / 20 / 100 pixels: "
              + " / ".join(f"{share[min(n, len(share)) - 1]:.2f}" for n in (1, 5, 20, 100)))
        for i in order[:8]:
            y, xx = divmod(int(i), width)
            print(f"    pixel (x {xx}, y {y}): {per_pixel[i] / total:.3f} of the error, "
                  f"reference energy {energy[y, xx]:.3g}")


if __name__ == "__main__":
    main()
