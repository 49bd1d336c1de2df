#!/usr/bin/env python3
"""Writes displaced_sphere.ply next to this script: a bumpy sphere of 4 R (R - 1) triangles
(R = 512 latitude rings: 1,046,528 triangles, 20 MB), the dense mesh of ray-rate.xml's
displaced-sphere scene. Too large to keep in the repository; generated in a few seconds.

    python3 bench/experiments/scenes/make_displaced_sphere.py [RINGS]
"""
import math
import struct
import sys
from pathlib import Path


def radius(theta, phi):
    # Every term vanishes at the poles, so the surface stays closed there.
    return (1.0 + 0.08 * math.sin(7 * theta) * math.sin(9 * phi)
            + 0.025 * math.sin(29 * theta) * math.sin(31 * phi + 2 * theta)
            + 0.006 * math.sin(97 * theta) * math.cos(101 * phi))


def main():
    rings = int(sys.argv[1]) if len(sys.argv) > 1 else 512
    if rings < 3:
        sys.exit("RINGS must be at least 3")
    nu, nv = 2 * rings, rings
    vertices = [(0.0, 1.0, 0.0)]  # the north pole at radius(0, 0) = 1
    for j in range(1, nv):
        theta = math.pi * j / nv
        for i in range(nu):
            phi = 2 * math.pi * i / nu
            r = radius(theta, phi)
            vertices.append((r * math.sin(theta) * math.cos(phi), r * math.cos(theta),
                             r * math.sin(theta) * math.sin(phi)))
    vertices.append((0.0, -1.0, 0.0))
    south = len(vertices) - 1

    def vid(i, j):  # ring j in [1, nv), counter-clockwise seen from outside
        return 1 + (j - 1) * nu + i % nu

    faces = [(0, vid(i + 1, 1), vid(i, 1)) for i in range(nu)]
    for j in range(1, nv - 1):
        for i in range(nu):
            a, b, c, d = vid(i, j), vid(i + 1, j), vid(i + 1, j + 1), vid(i, j + 1)
            faces += [(a, b, c), (a, c, d)]
    faces += [(vid(i, nv - 1), vid(i + 1, nv - 1), south) for i in range(nu)]

    out = Path(__file__).resolve().parent / "displaced_sphere.ply"
    header = ("ply\nformat binary_little_endian 1.0\n"
              f"comment femto bench: displaced sphere, {rings} rings\n"
              f"element vertex {len(vertices)}\nproperty float x\nproperty float y\n"
              f"property float z\nelement face {len(faces)}\n"
              "property list uchar int vertex_indices\nend_header\n")
    with open(out, "wb") as f:
        f.write(header.encode())
        f.write(b"".join(struct.pack("<3f", *v) for v in vertices))
        f.write(b"".join(struct.pack("<B3i", 3, *t) for t in faces))
    print(f"wrote {out}: {len(faces)} triangles")


if __name__ == "__main__":
    main()
