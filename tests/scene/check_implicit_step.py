#!/usr/bin/env python3
"""An independent check of the elastic and heat examples (a ctest; stdlib only).

usage: check_implicit_step.py SIMIT SCENE OUTDIR FRAMES {heat|elastic} [SIMIT ARGS...]

Runs SCENE for FRAMES frames into OUTDIR (every frame written), then reads the last two
frames' .vtu files back and checks, with its own finite-element code (linear tets, lumped
masses, written here from the textbook formulas, not from the .sim programs), that the last
frame is the solution of that frame's backward-Euler equations:

heat     (M + dt K) T' = M T at every vertex that is not held, where K_ij = alpha W g_i.g_j
         summed over the tets (g_i the gradient of corner i's shape function); held vertices
         exactly at t_hot / t_cold; every temperature between t_cold and t_hot (the maximum
         principle); the heater's and the cooler's power in the statistics CSV equal to
         (K T') summed over the hot and (negated) the cold vertices.
elastic  M (v' - v) + h K (x' - X) = h M g at every vertex that is not pinned, with K the
         small-strain stiffness W (lambda g_i g_j' + mu g_j g_i' + mu (g_i.g_j) I) per block;
         x' = x + h v' everywhere; pinned vertices exactly at rest with zero velocity.

Each residual must be at most 1e-9 of the largest term of its equation. SIMIT ARGS (such as
--backend jit) are passed to `simit run`.
"""
import csv
import math
import os
import re
import shutil
import struct
import subprocess
import sys
import tomllib

TOL = 1e-9


def fail(msg):
    print("FAIL: " + msg)
    sys.exit(1)


def read_vtu(path):
    """Points, tets and point-data arrays of a .vtu written by simit (raw appended data)."""
    data = open(path, "rb").read()
    head_end = data.index(b"<AppendedData")
    header = data[:head_end].decode()
    base = data.index(b"_", head_end) + 1
    arrays = {}
    for m in re.finditer(r'<DataArray type="(\w+)" Name="([^"]+)"(?: NumberOfComponents="(\d+)")?'
                         r' format="appended" offset="(\d+)"', header):
        kind, name, comps, offset = m.group(1), m.group(2), int(m.group(3) or 1), int(m.group(4))
        fmt = {"Float64": "d", "Int32": "i", "Int64": "q", "UInt8": "B"}[kind]
        start = base + offset
        (nbytes,) = struct.unpack_from("<Q", data, start)
        n = nbytes // struct.calcsize(fmt)
        values = struct.unpack_from("<%d%s" % (n, fmt), data, start + 8)
        arrays[name] = [values[i:i + comps] for i in range(0, n, comps)] if comps > 1 else list(values)
    pts = arrays.pop("Points")
    conn = arrays.pop("connectivity")
    offsets = arrays.pop("offsets")
    types = arrays.pop("types")
    if any(t != 10 for t in types) or any(o != 4 * (i + 1) for i, o in enumerate(offsets)):
        fail(path + ": expected tetrahedra only")
    tets = [conn[4 * i:4 * i + 4] for i in range(len(offsets))]
    return pts, tets, arrays


def sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def gradients(X):
    """Volume and the four shape-function gradients of the tet with corners X[0..3]."""
    e1, e2, e3 = sub(X[0], X[3]), sub(X[1], X[3]), sub(X[2], X[3])
    det = dot(e1, cross(e2, e3))
    # Rows of the inverse of the matrix with columns e1, e2, e3.
    g = [tuple(c / det for c in cross(e2, e3)), tuple(c / det for c in cross(e3, e1)),
         tuple(c / det for c in cross(e1, e2))]
    g.append(tuple(-(g[0][k] + g[1][k] + g[2][k]) for k in range(3)))
    return abs(det) / 6.0, g


def run_scene(simit, scene, outdir, frames, extra):
    if os.path.exists(outdir):
        shutil.rmtree(outdir)
    cmd = [simit, "run", scene, "--frames", str(frames), "--output", outdir] + extra
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        fail("%s exited %d\n%s\n%s" % (" ".join(cmd), p.returncode, p.stdout, p.stderr))
    with open(scene, "rb") as f:
        conf = tomllib.load(f)
    out = conf["output"]
    last = os.path.join(outdir, "%s_%06d.vtu" % (out["name"], frames))
    prev = os.path.join(outdir, "%s_%06d.vtu" % (out["name"], frames - 1))
    with open(os.path.join(outdir, out["csv"])) as f:
        stats = list(csv.DictReader(f))
    return conf["tensors"], read_vtu(prev), read_vtu(last), stats[-1]


def check_residual(name, residual, scale):
    worst = max(abs(r) for r in residual)
    print("%s: max |residual| %.3g, largest term %.3g, ratio %.3g" % (name, worst, scale,
                                                                      worst / scale))
    if not worst <= TOL * scale:
        fail("%s: residual %.3g exceeds %.0e of %.3g" % (name, worst, TOL, scale))


def check_heat(tensors, prev, last, stats):
    alpha, dt = tensors["alpha"], tensors["dt"]
    t_hot, t_cold = tensors["t_hot"], tensors["t_cold"]
    _, tets, d0 = prev
    _, _, d1 = last
    X, hot, cold = d1["x"], d1["hot"], d1["cold"]
    T0, T1 = d0["T"], d1["T"]
    n = len(X)
    m = [0.0] * n
    KT = [0.0] * n     # K T' over all the tets
    size = [0.0] * n   # sum of |K_ij T'_j|: the scale of the conduction term
    for tet in tets:
        W, g = gradients([X[i] for i in tet])
        for a in range(4):
            m[tet[a]] += 0.25 * W
            for b in range(4):
                k = alpha * W * dot(g[a], g[b]) * T1[tet[b]]
                KT[tet[a]] += k
                size[tet[a]] += abs(k)
    for i in range(n):
        if hot[i] and T1[i] != t_hot or cold[i] and not hot[i] and T1[i] != t_cold:
            fail("held vertex %d is at %r" % (i, T1[i]))
    free = [i for i in range(n) if not (hot[i] or cold[i])]
    res = [m[i] * (T1[i] - T0[i]) + dt * KT[i] for i in free]
    scale = max(max(m[i] * max(abs(T1[i]), abs(T0[i])), dt * size[i]) for i in free)
    check_residual("heat equation", res, scale)
    lo, hi = min(T1), max(T1)
    print("temperatures in [%.17g, %.17g]" % (lo, hi))
    if lo < t_cold - TOL * (t_hot - t_cold) or hi > t_hot + TOL * (t_hot - t_cold):
        fail("the maximum principle fails: temperatures in [%r, %r]" % (lo, hi))
    heater = sum(KT[i] for i in range(n) if hot[i])
    cooler = -sum(KT[i] for i in range(n) if cold[i] and not hot[i])
    for name, mine in (("heater", heater), ("cooler", cooler)):
        theirs = float(stats[name])
        print("%s: %.17g (program) %.17g (check)" % (name, theirs, mine))
        if abs(theirs - mine) > TOL * max(abs(heater), abs(cooler)):
            fail("%s power %r, the check computes %r" % (name, theirs, mine))


def check_elastic(tensors, prev, last, stats):
    E, nu, rho, h = tensors["E"], tensors["nu"], tensors["density"], tensors["h"]
    mu = E / (2.0 * (1.0 + nu))
    lam = E * nu / ((1.0 + nu) * (1.0 - 2.0 * nu))
    grav = (0.0, -9.81, 0.0)
    x0, tets, d0 = prev
    x1, _, d1 = last
    X, pinned, v0, v1 = d1["X"], d1["pinned"], d0["v"], d1["v"]
    n = len(X)
    m = [0.0] * n
    Ku = [[0.0] * 3 for _ in range(n)]  # K (x' - X)
    size = [0.0] * n
    u = [sub(x1[i], X[i]) for i in range(n)]
    for tet in tets:
        W, g = gradients([X[i] for i in tet])
        for a in range(4):
            i = tet[a]
            m[i] += 0.25 * rho * W
            for b in range(4):
                uj = u[tet[b]]
                gu_b, gu_a, gg = dot(g[b], uj), dot(g[a], uj), dot(g[a], g[b])
                for k in range(3):
                    t = W * (lam * g[a][k] * gu_b + mu * g[b][k] * gu_a + mu * gg * uj[k])
                    Ku[i][k] += t
                    size[i] += abs(t)
    for i in range(n):
        if any(abs(x1[i][k] - (x0[i][k] + h * v1[i][k])) > 1e-15 * (1 + abs(x1[i][k]))
               for k in range(3)):
            fail("vertex %d: x' is not x + h v'" % i)
        if pinned[i] and (v1[i] != (0.0, 0.0, 0.0) or x1[i] != X[i]):
            fail("pinned vertex %d moved" % i)
    free = [i for i in range(n) if not pinned[i]]
    res = [m[i] * (v1[i][k] - v0[i][k]) + h * Ku[i][k] - h * m[i] * grav[k]
           for i in free for k in range(3)]
    scale = max(max(m[i] * max(abs(c) for c in v1[i] + v0[i]), h * size[i] / 3,
                    h * m[i] * 9.81) for i in free)
    check_residual("elastic equation", res, scale)


def main():
    if len(sys.argv) < 6 or sys.argv[5] not in ("heat", "elastic"):
        sys.exit(__doc__)
    simit, scene, outdir, frames, model = sys.argv[1:6]
    tensors, prev, last, stats = run_scene(simit, scene, outdir, int(frames), sys.argv[6:])
    (check_heat if model == "heat" else check_elastic)(tensors, prev, last, stats)
    print("%s: frame %s solves its backward-Euler equations" % (scene, frames))


if __name__ == "__main__":
    main()
