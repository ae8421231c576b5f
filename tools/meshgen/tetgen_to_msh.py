#!/usr/bin/env python3
"""Converts TetGen output (BASE.node, BASE.ele) to Gmsh MSH 2.2 ASCII with physical tag 1,
every tet positively oriented ((b - a) . ((c - a) x (d - a)) > 0, two nodes swapped where
TetGen's order is the other one). Usage: tetgen_to_msh.py BASE OUT.msh"""
import sys


def rows(path):
    with open(path) as f:
        for line in f:
            line = line.split("#", 1)[0].split()
            if line:
                yield line


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    base, out = sys.argv[1], sys.argv[2]
    node_rows = rows(base + ".node")
    count = int(next(node_rows)[0])
    nodes = {}
    for _ in range(count):
        r = next(node_rows)
        nodes[int(r[0])] = (float(r[1]), float(r[2]), float(r[3]))
    ele_rows = rows(base + ".ele")
    count = int(next(ele_rows)[0])
    tets = []
    for _ in range(count):
        t = [int(v) for v in next(ele_rows)[1:5]]
        a, b, c, d = (nodes[i] for i in t)
        u = [b[k] - a[k] for k in range(3)]
        v = [c[k] - a[k] for k in range(3)]
        w = [d[k] - a[k] for k in range(3)]
        det = (u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0])
               + u[2] * (v[0] * w[1] - v[1] * w[0]))
        if det < 0:
            t[2], t[3] = t[3], t[2]
        tets.append(t)
    # MSH numbers nodes from 1 in file order, whatever TetGen's first index was.
    order = {old: new for new, old in enumerate(sorted(nodes), start=1)}
    with open(out, "w") as f:
        f.write("$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n%d\n" % len(nodes))
        for old in sorted(nodes):
            x, y, z = nodes[old]
            f.write("%d %.17g %.17g %.17g\n" % (order[old], x, y, z))
        f.write("$EndNodes\n$Elements\n%d\n" % len(tets))
        for e, t in enumerate(tets, start=1):
            f.write("%d 4 2 1 1 %s\n" % (e, " ".join(str(order[i]) for i in t)))
        f.write("$EndElements\n")


main()
