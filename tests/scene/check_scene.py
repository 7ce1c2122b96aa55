#!/usr/bin/env python3
"""Runs a scene through `simit run` and checks what it wrote (a ctest; stdlib only).

check_scene.py SIMIT SCENE OUTDIR FRAMES [--baseline EXE MESH] [--baseline-arg A]... [--rtol R]
               [--energy-rtol ER] [--energy-atol EA]

Runs SCENE for FRAMES frames into OUTDIR, then checks: the .pvd lists frames 0..FRAMES, every
.vtu it names exists, has the mesh's point count and only finite point coordinates; the
last frame's points equal the --final-csv positions. With --baseline, runs EXE --csv FILE
MESH FRAMES (a hand-written baseline) and compares its final positions with simit's to
relative tolerance R (|a - b| <= R * max|b| per coordinate); each --baseline-arg is passed
to EXE before its other arguments (e.g. --cg-tol 1e-24). It also compares the total energy
of every frame: the baseline prints it on its frame lines ("frame N: ..., energy E") and
simit writes the program's `energy` statistic to the scene's [output] csv; they must agree
to |a - b| <= ER * |b| + EA (defaults 1e-9 and 0). A scene without an [output] csv has no
energies to compare: the check says so and leaves them out. EA is for totals that are a near
cancellation (the falling cloth's kinetic and gravitational energy), where |b| measures the
cancellation rather than the size of the terms that were rounded.
"""
import csv
import math
import os
import re
import struct
import subprocess
import sys
import tomllib


def fail(msg):
    print("FAIL: " + msg)
    sys.exit(1)


def read_vtu_points(path):
    data = open(path, "rb").read()
    head_end = data.index(b"<AppendedData")
    header = data[:head_end].decode()
    if 'header_type="UInt64"' not in header:
        fail(path + ": expected header_type UInt64")
    n = int(re.search(r'NumberOfPoints="(\d+)"', header).group(1))
    m = re.search(r'<Points>\s*<DataArray type="Float64"[^>]*offset="(\d+)"', header)
    if not m:
        fail(path + ": no Float64 Points array")
    start = data.index(b"_", head_end) + 1 + int(m.group(1))
    (nbytes,) = struct.unpack_from("<Q", data, start)
    if nbytes != 24 * n:
        fail("%s: Points has %d bytes, expected %d" % (path, nbytes, 24 * n))
    values = struct.unpack_from("<%dd" % (3 * n), data, start + 8)
    return [values[3 * i:3 * i + 3] for i in range(n)]


def read_csv(path):
    rows = [line.strip() for line in open(path) if line.strip()]
    if rows[0] != "x,y,z":
        fail(path + ": expected the header x,y,z")
    return [tuple(float(v) for v in r.split(",")) for r in rows[1:]]


def stats_csv_name(scene):
    with open(scene, "rb") as f:
        return tomllib.load(f).get("output", {}).get("csv")


def simit_energies(scene, outdir):
    """The energy column of the per-frame statistics CSV that SCENE's [output] csv names."""
    with open(os.path.join(outdir, stats_csv_name(scene))) as f:
        rows = list(csv.DictReader(f))
    if rows and "energy" not in rows[0]:
        fail("%s has no energy column" % name)
    return [float(r["energy"]) for r in rows]


FRAME_ENERGY = re.compile(r"^frame (\d+): .*, energy (\S+)$")


def baseline_energies(stdout):
    """The energies of the baseline's frame lines, in frame order."""
    found = [m for m in map(FRAME_ENERGY.match, stdout.splitlines()) if m]
    if [int(m.group(1)) for m in found] != list(range(1, len(found) + 1)):
        fail("the baseline's frame lines are not frames 1, 2, ... in order")
    return [float(m.group(2)) for m in found]


def compare_energies(simit_e, base_e, frames, rtol, atol):
    if len(simit_e) != frames or len(base_e) != frames:
        fail("energies of %d frames expected: simit wrote %d, the baseline printed %d"
             % (frames, len(simit_e), len(base_e)))
    worst_abs = worst_rel = 0.0
    for k, (a, b) in enumerate(zip(simit_e, base_e)):
        bound = rtol * abs(b) + atol
        if not abs(a - b) <= bound:
            fail("frame %d: simit's energy %.17g, the baseline's %.17g (|a - b| = %.3e > %.3e)"
                 % (k + 1, a, b, abs(a - b), bound))
        worst_abs = max(worst_abs, abs(a - b))
        worst_rel = max(worst_rel, abs(a - b) / abs(b) if b else 0.0)
    print("energy over %d frames: max |simit - baseline| = %.3e, relative %.3e "
          "(tolerance %.1e relative + %.1e)" % (frames, worst_abs, worst_rel, rtol, atol))


def main():
    args = sys.argv[1:]
    baseline = None
    rtol = 1e-9
    if "--baseline" in args:
        i = args.index("--baseline")
        baseline = (args[i + 1], args[i + 2])
        del args[i:i + 3]
    baseline_args = []
    while "--baseline-arg" in args:
        i = args.index("--baseline-arg")
        baseline_args.append(args[i + 1])
        del args[i:i + 2]
    if "--rtol" in args:
        i = args.index("--rtol")
        rtol = float(args[i + 1])
        del args[i:i + 2]
    energy_rtol, energy_atol = 1e-9, 0.0
    if "--energy-rtol" in args:
        i = args.index("--energy-rtol")
        energy_rtol = float(args[i + 1])
        del args[i:i + 2]
    if "--energy-atol" in args:
        i = args.index("--energy-atol")
        energy_atol = float(args[i + 1])
        del args[i:i + 2]
    simit, scene, outdir, frames = args[0], args[1], args[2], int(args[3])
    os.makedirs(outdir, exist_ok=True)
    final_csv = os.path.join(outdir, "final.csv")
    cmd = [simit, "run", "--frames", str(frames), "--output", outdir, "--final-csv", final_csv, scene]
    print(" ".join(cmd), flush=True)
    if subprocess.call(cmd) != 0:
        fail("simit run failed")
    pvds = [f for f in os.listdir(outdir) if f.endswith(".pvd")]
    if len(pvds) != 1:
        fail("expected one .pvd in %s, found %s" % (outdir, pvds))
    files = re.findall(r'file="([^"]+)"', open(os.path.join(outdir, pvds[0])).read())
    if len(files) != frames + 1:
        fail("the .pvd lists %d frames, expected %d" % (len(files), frames + 1))
    points = None
    for f in files:
        points = read_vtu_points(os.path.join(outdir, f))
        bad = [p for p in points if not all(math.isfinite(c) for c in p)]
        if bad:
            fail("%s: %d non-finite points" % (f, len(bad)))
    final = read_csv(final_csv)
    if final != [tuple(p) for p in points]:
        fail("--final-csv differs from the last frame's points")
    print("ok: %d frames of %d points, all finite" % (len(files), len(points)))
    if baseline:
        exe, mesh = baseline
        base_csv = os.path.join(outdir, "baseline.csv")
        cmd = [exe] + baseline_args + ["--csv", base_csv, mesh, str(frames)]
        print(" ".join(cmd), flush=True)
        run = subprocess.run(cmd, stdout=subprocess.PIPE, text=True)
        print(run.stdout, end="", flush=True)
        if run.returncode != 0:
            fail("the baseline failed")
        ref = read_csv(base_csv)
        if len(ref) != len(final):
            fail("baseline has %d points, simit %d" % (len(ref), len(final)))
        scale = max(abs(c) for p in ref for c in p)
        worst = max(abs(a - b) for p, q in zip(final, ref) for a, b in zip(p, q)) / scale
        print("max |simit - baseline| / max|baseline| = %.3e (tolerance %.1e)" % (worst, rtol))
        if not worst <= rtol:
            fail("simit and the baseline differ")
        if not stats_csv_name(scene):
            print("energy: not compared, %s writes no statistics ([output] csv)" % scene)
            return
        compare_energies(simit_energies(scene, outdir), baseline_energies(run.stdout), frames,
                         energy_rtol, energy_atol)


main()
