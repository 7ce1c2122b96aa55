#!/usr/bin/python3
"""Refines a TetGen tet mesh by regular 1:8 subdivision, for meshes larger than the repository's.

Usage: /usr/bin/python3 bench/refine_tets.py BASE OUT_DIR [--times N]

Reads BASE.node and BASE.ele (TetGen: 0- or 1-based indices, as the files say; '#' comments)
and writes OUT_DIR/NAME.node and OUT_DIR/NAME.ele (NAME: BASE's file name) with each tet cut
into 8: a new vertex at every edge midpoint, shared by the tets around the edge. With
--times N it refines N times (the dragon's 160,606 tets: 1,284,848 at 1, 10,278,784 at 2).
Prints the tet counts and the volumes' sums before and after: regular subdivision keeps both
the volume and each tet's orientation, so the sums must agree to rounding.

Vertex attributes of a midpoint are the mean of its edge's two ends, its boundary marker 0;
a child tet keeps its parent's attributes. Needs numpy (Debian's python3-numpy).
"""

import argparse
import os
import sys
import time

try:
    import numpy as np
except ImportError:  # the interpreter on PATH may not be the one with numpy
    sys.exit("refine_tets.py needs numpy: run it with an interpreter that has it "
             "(e.g. Debian's /usr/bin/python3 with python3-numpy)")

# The 6 edges of a tet as pairs of its corners, in the order the midpoints are numbered.
EDGES = np.array([(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)])
# The 8 children over the local numbering 0..3 = corners, 4..9 = midpoints of EDGES
# (4: 01, 5: 02, 6: 03, 7: 12, 8: 13, 9: 23). Four corner tets keep the parent's orientation;
# the inner octahedron is cut along the diagonal 02-13 into the four tets around it, whose
# orientation is fixed afterwards by signed volume.
CHILDREN = np.array([
    (0, 4, 5, 6), (4, 1, 7, 8), (5, 7, 2, 9), (6, 8, 9, 3),
    (5, 8, 4, 7), (5, 8, 7, 9), (5, 8, 9, 6), (5, 8, 6, 4),
])


class MeshError(Exception):
    pass


def read_records(path, width):
    """The header's numbers and the records (a 2-D float array) of a TetGen file, whose
    records have width(header) numbers each."""
    try:
        with open(path) as f:
            lines = f.read().splitlines()
    except OSError as e:
        raise MeshError(f"{path}: {e.strerror}")
    lines = [ln.split('#', 1)[0] for ln in lines]
    lines = [ln for ln in lines if ln.strip()]
    if not lines:
        raise MeshError(f"{path}: no header")
    try:
        header = [int(t) for t in lines[0].split()]
        body = np.array(" ".join(lines[1:]).split(), dtype=np.float64)
    except ValueError as e:
        raise MeshError(f"{path}: not a number ({e})")
    if len(header) < 2 or header[0] <= 0:
        raise MeshError(f"{path}: the header must give a positive count and a dimension")
    count, w = header[0], width(header)
    if body.size != count * w:
        raise MeshError(f"{path}: {body.size} numbers after the header, where its {count} "
                        f"records of {w} numbers make {count * w}")
    return header, body.reshape(count, w)


def read_mesh(base):
    nh, nodes = read_records(base + ".node", lambda h: 4 + sum(h[2:4]))
    if nh[1] != 3:
        raise MeshError(f"{base}.node: the header must say dimension 3")
    attrs = nh[2] if len(nh) > 2 else 0
    first = int(nodes[0, 0])
    if first not in (0, 1) or not np.array_equal(nodes[:, 0], first + np.arange(len(nodes))):
        raise MeshError(f"{base}.node: vertex indices must count up from 0 or 1")
    eh, eles = read_records(base + ".ele", lambda h: 1 + h[1] + sum(h[2:3]))
    if eh[1] != 4:
        raise MeshError(f"{base}.ele: only 4-vertex tets are refined (the header says {eh[1]})")
    tets = eles[:, 1:5].astype(np.int64) - first
    if tets.min() < 0 or tets.max() >= len(nodes):
        raise MeshError(f"{base}.ele: a vertex index outside the .node file's")
    return {
        "first": first,
        "points": nodes[:, 1:4],
        "vattrs": nodes[:, 4:4 + attrs],
        "markers": nodes[:, 4 + attrs:],  # 0 or 1 column
        "tets": tets,
        "tattrs": eles[:, 5:],
    }


def signed_volumes(points, tets):
    a, b, c, d = (points[tets[:, k]] for k in range(4))
    return np.einsum("ij,ij->i", np.cross(b - a, c - a), d - a) / 6.0


def refine(mesh):
    """The mesh with every tet cut into 8 (a new dict of the same fields)."""
    points, tets = mesh["points"], mesh["tets"]
    n = len(points)
    # Every tet's 6 edges as (low, high) keys; np.unique numbers each edge once, so that the
    # tets around an edge share its midpoint.
    ends = np.sort(tets[:, EDGES], axis=2)  # (tets, 6, 2)
    keys = ends[:, :, 0] * n + ends[:, :, 1]
    unique, inverse = np.unique(keys.ravel(), return_inverse=True)
    lo, hi = unique // n, unique % n
    mid = n + inverse.reshape(-1, 6)
    local = np.concatenate([tets, mid], axis=1)  # (tets, 10): corners then midpoints
    children = local[:, CHILDREN].reshape(-1, 4)
    new_points = np.concatenate([points, 0.5 * (points[lo] + points[hi])])
    # The octahedron's children do not all come out with the parent's orientation: swap two
    # vertices of those whose signed volume's sign differs from the parent's.
    parent_sign = np.repeat(np.sign(signed_volumes(points, tets)), 8)
    flip = np.sign(signed_volumes(new_points, children)) != parent_sign
    children[flip, 2], children[flip, 3] = children[flip, 3], children[flip, 2].copy()
    vattrs, markers = mesh["vattrs"], mesh["markers"]
    return {
        "first": mesh["first"],
        "points": new_points,
        "vattrs": np.concatenate([vattrs, 0.5 * (vattrs[lo] + vattrs[hi])]),
        "markers": np.concatenate([markers, np.zeros((len(unique), markers.shape[1]))]),
        "tets": children,
        "tattrs": np.repeat(mesh["tattrs"], 8, axis=0),
    }


def write_rows(f, ints, floats, int_cols, chunk=200_000):
    """Writes rows of `int_cols` integers then float columns, fast: one % per chunk of rows."""
    width = floats.shape[1]
    row = " ".join(["%d"] * int_cols + ["%.17g"] * width) + "\n"
    for start in range(0, len(ints), chunk):
        i = ints[start:start + chunk]
        x = floats[start:start + chunk]
        cols = [i[:, k].astype(object) for k in range(int_cols)] + [x[:, k] for k in range(width)]
        flat = np.empty(len(i) * len(cols), dtype=object)
        for k, c in enumerate(cols):
            flat[k::len(cols)] = c
        f.write((row * len(i)) % tuple(flat.tolist()))


def write_mesh(mesh, base):
    first = mesh["first"]
    npts = len(mesh["points"])
    with open(base + ".node", "w") as f:
        f.write(f"{npts}  3  {mesh['vattrs'].shape[1]}  {mesh['markers'].shape[1]}\n")
        floats = np.concatenate([mesh["points"], mesh["vattrs"], mesh["markers"]], axis=1)
        write_rows(f, (first + np.arange(npts)).reshape(-1, 1), floats, 1)
    ntets = len(mesh["tets"])
    with open(base + ".ele", "w") as f:
        f.write(f"{ntets}  4  {mesh['tattrs'].shape[1]}\n")
        ints = np.concatenate([(first + np.arange(ntets)).reshape(-1, 1), first + mesh["tets"]],
                              axis=1)
        write_rows(f, ints, mesh["tattrs"], 5)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("base", help="the input mesh without extension (BASE.node, BASE.ele)")
    ap.add_argument("out_dir", help="the folder to write NAME.node and NAME.ele into")
    ap.add_argument("--times", type=int, default=1, help="refinements (default 1)")
    args = ap.parse_args()
    if args.times < 1:
        ap.error("--times must be at least 1")
    try:
        t0 = time.perf_counter()
        mesh = read_mesh(args.base)
        vol = np.abs(signed_volumes(mesh["points"], mesh["tets"])).sum()
        print(f"input:  {len(mesh['points']):,} vertices, {len(mesh['tets']):,} tets, "
              f"volume {vol:.15g}")
        for k in range(args.times):
            mesh = refine(mesh)
            v = np.abs(signed_volumes(mesh["points"], mesh["tets"])).sum()
            print(f"refined x{k + 1}: {len(mesh['points']):,} vertices, {len(mesh['tets']):,} "
                  f"tets, volume {v:.15g} (relative difference {abs(v - vol) / vol:.1e})")
        os.makedirs(args.out_dir, exist_ok=True)
        out = os.path.join(args.out_dir, os.path.basename(args.base))
        write_mesh(mesh, out)
        print(f"wrote {out}.node, {out}.ele in {time.perf_counter() - t0:.1f} s")
    except MeshError as e:
        sys.exit(f"refine_tets.py: {e}")


if __name__ == "__main__":
    main()
