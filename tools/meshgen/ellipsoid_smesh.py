#!/usr/bin/env python3
"""Writes a closed ellipsoid surface as a TetGen .smesh file: an icosahedron subdivided
LEVEL times, projected onto the unit sphere and scaled to the semi-axes (mm).
Deterministic (no randomness). Usage: ellipsoid_smesh.py OUT.smesh A B C LEVEL"""
import math
import sys


def icosphere(level):
    t = (1 + math.sqrt(5)) / 2
    verts = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t),
             (0, -1, -t), (0, 1, -t), (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    faces = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4),
             (11, 10, 2), (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8),
             (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    verts = [unit(v) for v in verts]
    for _ in range(level):
        middle = {}

        def mid(i, j):
            key = (min(i, j), max(i, j))
            if key not in middle:
                a, b = verts[i], verts[j]
                verts.append(unit(((a[0] + b[0]) / 2, (a[1] + b[1]) / 2, (a[2] + b[2]) / 2)))
                middle[key] = len(verts) - 1
            return middle[key]

        refined = []
        for a, b, c in faces:
            ab, bc, ca = mid(a, b), mid(b, c), mid(c, a)
            refined += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        faces = refined
    return verts, faces


def unit(v):
    n = math.sqrt(v[0] ** 2 + v[1] ** 2 + v[2] ** 2)
    return (v[0] / n, v[1] / n, v[2] / n)


def main():
    if len(sys.argv) != 6:
        sys.exit(__doc__)
    out, a, b, c, level = sys.argv[1], float(sys.argv[2]), float(sys.argv[3]), float(sys.argv[4]), int(sys.argv[5])
    verts, faces = icosphere(level)
    with open(out, "w") as f:
        f.write(f"{len(verts)} 3 0 0\n")
        for i, (x, y, z) in enumerate(verts):
            f.write(f"{i + 1} {a * x:.17g} {b * y:.17g} {c * z:.17g}\n")
        f.write(f"{len(faces)} 0\n")
        for p, q, r in faces:
            f.write(f"3 {p + 1} {q + 1} {r + 1}\n")
        f.write("0\n0\n")


main()
