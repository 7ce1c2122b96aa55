#!/usr/bin/env python3
"""Writes the hard-case suite's small TetGen meshes into tests/hard/data/.

bar.node/.ele: a 0.02 x 0.1 x 0.02 bar (y up) of 2 x 10 x 2 cubes, six tets per cube (the
Kuhn subdivision, conforming across cubes): 99 vertices, 240 tets. sliver.node/.ele: the same
bar with the vertex layer at y = 0.05 raised by 0.99 of a cell, so that the 24 tets between
it and the next layer are 1e-4 m thick and 1e-2 m wide: four nearly coplanar corners without
a short edge among the pairs that straddle the layer (slivers, caps and wedges), volume about
1/100 of a regular tet's. Tets follow TetGen's orientation (det [x0-x3, x1-x3, x2-x3] < 0).
"""
import itertools
import os

HERE = os.path.dirname(os.path.abspath(__file__))


def det3(a, b, c):
    return (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
            + a[2] * (b[0] * c[1] - b[1] * c[0]))


def bar(nx=2, ny=10, nz=2, size=(0.02, 0.1, 0.02), lift_layer=None, lift=0.0):
    idx = {}
    pts = []
    for j in range(ny + 1):
        for k in range(nz + 1):
            for i in range(nx + 1):
                y = size[1] * j / ny
                if j == lift_layer:
                    y += lift * size[1] / ny
                idx[i, j, k] = len(pts)
                pts.append((size[0] * i / nx, y, size[2] * k / nz))
    tets = []
    for i, j, k in itertools.product(range(nx), range(ny), range(nz)):
        for perm in itertools.permutations(range(3)):
            c = [0, 0, 0]
            path = [tuple(c)]
            for axis in perm:
                c[axis] = 1
                path.append(tuple(c))
            t = [idx[i + a, j + b, k + d] for a, b, d in path]
            p = [pts[n] for n in t]
            e = [[p[m][r] - p[3][r] for r in range(3)] for m in range(3)]
            if det3(*e) > 0:
                t[0], t[1] = t[1], t[0]
            tets.append(t)
    return pts, tets


def write(name, pts, tets):
    with open(os.path.join(HERE, "data", name + ".node"), "w") as f:
        f.write("%d  3  0  0\n" % len(pts))
        for n, p in enumerate(pts):
            f.write("%d  %.17g  %.17g  %.17g\n" % (n, *p))
    with open(os.path.join(HERE, "data", name + ".ele"), "w") as f:
        f.write("%d  4  0\n" % len(tets))
        for n, t in enumerate(tets):
            f.write("%d  %d  %d  %d  %d\n" % (n, *t))


if __name__ == "__main__":
    os.makedirs(os.path.join(HERE, "data"), exist_ok=True)
    write("bar", *bar())
    write("sliver", *bar(lift_layer=5, lift=0.99))
