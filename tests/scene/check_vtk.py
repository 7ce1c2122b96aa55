#!/usr/bin/env python3
"""VTK's own reader opens every frame `simit run` writes, with the right values (a ctest).

check_vtk.py SIMIT SOURCE_DIR OUTDIR

Runs the fem bunny (3 frames) and the cloth square (2 frames) scenes of SOURCE_DIR/examples
with --final-csv, parses each .pvd as XML (VTK 9.1's Python has no .pvd reader) and reads
every .vtu it lists with vtk.vtkXMLUnstructuredGridReader, failing on any message VTK
prints. Checks, against values computed here from the mesh files, the programs and the
scenes: point and cell counts, cell types and connectivity, each point/cell field with the
number of components its element declares, frame 0's points = the mesh, the last frame's
points = --final-csv (1e-12), `pinned` = the scene's pinning rule at the mesh coordinates,
pinned points at rest, `m` = the lumped masses (density x tet volume / 4, or density x
triangle area / 3) and their sum the total mass, and the fem `W` = the tet rest volumes.
Exits 77 (ctest's skip code here) when `import vtk` fails: Debian's python3-vtk9 is
installed by scripts/test.sh for the tests only.
"""
import math
import os
import re
import subprocess
import sys
import tomllib
import xml.etree.ElementTree as ET

try:
    import vtk
except ImportError as e:
    print("SKIP: cannot import vtk (%s) with %s; install Debian's python3-vtk9 "
          "(scripts/test.sh does)" % (e, sys.executable))
    sys.exit(77)

VTK_TRIANGLE, VTK_TETRA = 5, 10


def fail(msg):
    print("FAIL: " + msg)
    sys.exit(1)


def close(a, b, rtol):
    return abs(a - b) <= rtol * max(abs(a), abs(b), 1e-300)


# ---- what the test computes on its own ----

def read_numbers(path):
    for line in open(path):
        fields = line.split("#")[0].split()
        if fields:
            yield fields


def read_tetgen(node_path):
    """Points and tets of a TetGen BASE.node / BASE.ele pair (0-based indices, as shipped)."""
    lines = list(read_numbers(node_path))
    points = [tuple(float(v) for v in f[1:4]) for f in lines[1:int(lines[0][0]) + 1]]
    base = int(lines[1][0])
    lines = list(read_numbers(os.path.splitext(node_path)[0] + ".ele"))
    tets = [tuple(int(v) - base for v in f[1:5]) for f in lines[1:int(lines[0][0]) + 1]]
    return points, tets


def square_cloth(n):
    """The generated cloth of README.md: point i + n j at (i, 0, j) / (n - 1), 2 triangles a cell."""
    points = [(i / (n - 1), 0.0, j / (n - 1)) for j in range(n) for i in range(n)]
    tris = []
    for j in range(n - 1):
        for i in range(n - 1):
            p = i + n * j
            tris += [(p, p + 1, p + n + 1), (p, p + n + 1, p + n)]
    return points, tris


def sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def tet_rest_volume(pts, t):
    """-det[x0-x3 | x1-x3 | x2-x3] / 6: positive for TetGen's orientation (fem.sim's W)."""
    a, b, c = sub(pts[t[0]], pts[t[3]]), sub(pts[t[1]], pts[t[3]]), sub(pts[t[2]], pts[t[3]])
    det = (a[0] * (b[1] * c[2] - b[2] * c[1]) - b[0] * (a[1] * c[2] - a[2] * c[1])
           + c[0] * (a[1] * b[2] - a[2] * b[1]))
    return -det / 6.0


def triangle_area(pts, t):
    u, v = sub(pts[t[1]], pts[t[0]]), sub(pts[t[2]], pts[t[0]])
    n = (u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0])
    return 0.5 * math.sqrt(n[0] ** 2 + n[1] ** 2 + n[2] ** 2)


def program_facts(sim_path):
    """Components of each element field, and the program's `density`, read from its text."""
    text = open(sim_path).read()
    comps = {}
    for block in re.findall(r"^element \w+\n(.*?)^end", text, re.M | re.S):
        for name, ty in re.findall(r"^\s*(\w+)\s*:\s*([^;]+);", block, re.M):
            dims = re.match(r"\s*(?:vector|matrix)\[([\d,\s]+)\]", ty)
            comps[name] = math.prod(int(d) for d in dims.group(1).split(",")) if dims else 1
    density = float(re.search(r"^const density\s*=\s*([\d.eE+-]+);", text, re.M).group(1))
    return comps, density


def pinning_rule(expr, pts):
    """The scene's pinning expression at each point. The two rules used here ("y < 1e-4", and
    "z < 1e-9 and (x < 1e-9 or x > 1 - 1e-9)") read the same in Python."""
    code = compile(expr, "pinned", "eval")
    return [int(bool(eval(code, {"__builtins__": {}}, {"x": p[0], "y": p[1], "z": p[2]})))
            for p in pts]


# ---- what VTK reads ----

def read_vtu(path):
    """The grid VTK reads from `path`; fails on anything VTK would print (errors, warnings)."""
    messages = vtk.vtkStringOutputWindow()
    vtk.vtkOutputWindow.SetInstance(messages)
    reader = vtk.vtkXMLUnstructuredGridReader()
    reader.SetFileName(path)
    reader.Update()
    said = messages.GetOutput().strip()
    if said or reader.GetErrorCode() != 0:
        fail("%s: VTK's reader reports: %s (error code %d)" % (path, said, reader.GetErrorCode()))
    return reader.GetOutput()


def array_values(grid_data, name, count, comps, where):
    a = grid_data.GetArray(name)
    if a is None:
        fail("%s: no array '%s'" % (where, name))
    if a.GetNumberOfComponents() != comps or a.GetNumberOfTuples() != count:
        fail("%s: '%s' has %d x %d values, expected %d x %d" % (
            where, name, a.GetNumberOfTuples(), a.GetNumberOfComponents(), count, comps))
    return [a.GetTuple(i) for i in range(count)]


def read_pvd(path, frames, frame_time):
    root = ET.parse(path).getroot()
    if root.tag != "VTKFile" or root.get("type") != "Collection":
        fail(path + ": not a VTKFile of type Collection")
    sets = root.findall("./Collection/DataSet")
    if len(sets) != frames + 1:
        fail("%s lists %d frames, expected %d" % (path, len(sets), frames + 1))
    for k, d in enumerate(sets):
        if not close(float(d.get("timestep")), k * frame_time, 1e-15):
            fail("%s: frame %d at time %s, expected %g" % (path, k, d.get("timestep"), k * frame_time))
    return [os.path.join(os.path.dirname(path), d.get("file")) for d in sets]


def const_value(sim_path, name):
    """A `const NAME = number;` or a column-vector literal `[a, b, c]'` of the program."""
    m = re.search(r"^const %s\s*=\s*([^;%%]+);" % name, open(sim_path).read(), re.M)
    text = m.group(1).strip()
    if text.startswith("["):
        return [float(v) for v in text.strip("[]'").split(",")]
    return float(text)


def inverse3(a):
    det = (a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1])
           - a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0])
           + a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]))
    cof = [[a[(j + 1) % 3][(i + 1) % 3] * a[(j + 2) % 3][(i + 2) % 3]
            - a[(j + 1) % 3][(i + 2) % 3] * a[(j + 2) % 3][(i + 1) % 3] for j in range(3)]
           for i in range(3)]
    return [[cof[i][j] / det for j in range(3)] for i in range(3)], det


def edge_matrix(pts, t):
    return [[pts[t[j]][i] - pts[t[3]][i] for j in range(3)] for i in range(3)]


def fem_energy(sim_path, rest, tets, volumes, xs, v, m):
    """The total energy of fem.sim's state, computed here from the state alone: Neo-Hookean
    W psi(F) per tet, psi = mu/2 (tr(F'F) - 3) - mu log J + lambda/2 (log J)^2, with the
    program's E and nu (mu = E / (2 nu), sic), plus kinetic and gravitational energy."""
    E, nu, g = const_value(sim_path, "E"), const_value(sim_path, "nu"), const_value(sim_path, "gravity")
    mu, lam = 0.5 * E / nu, E * nu / ((1 + nu) * (1 - 2 * nu))
    total = 0.0
    for t, w in zip(tets, volumes):
        B, _ = inverse3(edge_matrix(rest, t))
        D = edge_matrix(xs, t)
        F = [[sum(D[i][k] * B[k][j] for k in range(3)) for j in range(3)] for i in range(3)]
        _, J = inverse3(F)
        c = sum(F[i][j] ** 2 for i in range(3) for j in range(3))
        total += w * (0.5 * mu * (c - 3) - mu * math.log(J) + 0.5 * lam * math.log(J) ** 2)
    for x, vi, (mi,) in zip(xs, v, m):
        total += 0.5 * mi * sum(a * a for a in vi) - mi * sum(a * b for a, b in zip(g, x))
    return total


def csv_column(path, name):
    rows = [line.strip().split(",") for line in open(path) if line.strip()]
    k = rows[0].index(name)
    return [float(r[k]) for r in rows[1:]]


def check_scene(simit, scene_path, outdir, frames, mesh, cell_type, masses, volumes=None,
                energy=None):
    """`energy(xs, point_data)`, when given, computes the last frame's total energy, which must
    match the `energy` column of the scene's statistics CSV."""
    scene = tomllib.load(open(scene_path, "rb"))
    out = scene["output"]
    points_set = scene["sets"][out["points"]]
    sim = os.path.join(os.path.dirname(scene_path), scene["program"])
    comps, _ = program_facts(sim)
    pts, cells = mesh
    final_csv = os.path.join(outdir, "final.csv")
    cmd = [simit, "run", "--frames", str(frames), "--output", outdir, "--final-csv", final_csv,
           scene_path]
    print(" ".join(cmd), flush=True)
    if subprocess.call(cmd, stdout=subprocess.DEVNULL) != 0:
        fail("simit run failed")
    files = read_pvd(os.path.join(outdir, out["name"] + ".pvd"), frames, scene.get("frame_time", 1))
    pinned = pinning_rule(points_set["fields"]["pinned"], pts)
    if not 0 < sum(pinned) < len(pts):
        fail("the pinning rule pins %d of %d points" % (sum(pinned), len(pts)))
    arity = len(cells[0])
    for k, f in enumerate(files):
        grid = read_vtu(f)
        if grid.GetNumberOfPoints() != len(pts) or grid.GetNumberOfCells() != len(cells):
            fail("%s: %d points and %d cells, expected %d and %d" % (
                f, grid.GetNumberOfPoints(), grid.GetNumberOfCells(), len(pts), len(cells)))
        types = {grid.GetCellType(c) for c in range(len(cells))}
        if types != {cell_type}:
            fail("%s: cell types %s, expected only %d" % (f, sorted(types), cell_type))
        if k == 0:
            ids = vtk.vtkIdList()
            for c, expected in enumerate(cells):
                grid.GetCellPoints(c, ids)
                got = tuple(ids.GetId(i) for i in range(ids.GetNumberOfIds()))
                if got != tuple(expected):
                    fail("%s: cell %d has points %s, expected %s" % (f, c, got, expected))
        xs = [grid.GetPoint(i) for i in range(len(pts))]
        if not all(math.isfinite(c) for p in xs for c in p):
            fail(f + ": non-finite points")
        if k == 0 and any(abs(a - b) > 1e-15 for p, q in zip(xs, pts) for a, b in zip(p, q)):
            fail(f + ": frame 0's points are not the mesh's")
        for i in (i for i in range(len(pts)) if pinned[i]):
            if any(abs(a - b) > 1e-15 for a, b in zip(xs[i], pts[i])):
                fail("%s: pinned point %d moved to %s from %s" % (f, i, xs[i], pts[i]))
        pd, cd = grid.GetPointData(), grid.GetCellData()
        for name in out.get("point_fields", []):
            values = array_values(pd, name, len(pts), comps[name], f)
            if name == "pinned" and [int(v[0]) for v in values] != pinned:
                fail("%s: 'pinned' differs from the rule %r" % (f, points_set["fields"]["pinned"]))
            if name == "v" and any(any(v) for i, v in enumerate(values) if pinned[i]):
                fail(f + ": a pinned point has a velocity")
            if name == "m":
                for i, (v,) in enumerate(values):
                    if not close(v, masses[i], 1e-12):
                        fail("%s: m[%d] = %.17g, expected %.17g" % (f, i, v, masses[i]))
                total = sum(v for (v,) in values)
        for name in out.get("cell_fields", []):
            values = array_values(cd, name, len(cells), comps[name], f)
            if name == "W":
                for c, (w,) in enumerate(values):
                    if not close(w, volumes[c], 1e-12):
                        fail("%s: W[%d] = %.17g, expected the volume %.17g" % (f, c, w, volumes[c]))
    final = [tuple(float(v) for v in line.split(",")) for line in open(final_csv).readlines()[1:]]
    worst = max(abs(a - b) for p, q in zip(xs, final) for a, b in zip(p, q))
    if len(final) != len(xs) or worst > 1e-12:
        fail("the last frame's points differ from --final-csv by %g" % worst)
    print("ok: %d .vtu files of %d points and %d cells; %d pinned; total mass %.12g "
          "(expected %.12g); last frame = --final-csv (max difference %g)"
          % (len(files), len(pts), len(cells), sum(pinned), total, sum(masses), worst))
    if not close(total, sum(masses), 1e-12):
        fail("the masses sum to %.17g, expected %.17g" % (total, sum(masses)))
    if energy:
        expected = energy(xs, pd)
        got = csv_column(os.path.join(outdir, out["csv"]), "energy")[-1]
        print("ok: energy of the last frame %.12g (the program's CSV: %.12g)" % (expected, got))
        if not close(got, expected, 1e-9):
            fail("the CSV's energy %.17g differs from %.17g computed from the state" % (got, expected))


def main():
    simit, source, outdir = sys.argv[1:4]
    examples = os.path.join(source, "examples")

    # fem: lumped masses density W / 4 per tet corner, W the rest volume.
    pts, tets = read_tetgen(os.path.join(examples, "data", "bunny.1.node"))
    _, density = program_facts(os.path.join(examples, "fem", "fem.sim"))
    volumes = [tet_rest_volume(pts, t) for t in tets]
    if min(volumes) <= 0:
        fail("bunny.1.ele: a tet is not in TetGen's orientation")
    masses = [0.0] * len(pts)
    for t, w in zip(tets, volumes):
        for i in t:
            masses[i] += 0.25 * density * w
    print("fem bunny: volume %.12g, density %g, mass %.12g" % (sum(volumes), density,
                                                                density * sum(volumes)))
    fem_sim = os.path.join(examples, "fem", "fem.sim")
    energy = lambda xs, pd: fem_energy(
        fem_sim, pts, tets, volumes, xs, array_values(pd, "v", len(pts), 3, "energy"),
        array_values(pd, "m", len(pts), 1, "energy"))
    check_scene(simit, os.path.join(examples, "fem", "bunny.toml"), os.path.join(outdir, "fem"),
                3, (pts, tets), VTK_TETRA, masses, volumes, energy)

    # cloth: density area / 3 per triangle corner; the unit square weighs density.
    scene = tomllib.load(open(os.path.join(examples, "cloth", "square.toml"), "rb"))
    pts, tris = square_cloth(scene["sets"]["points"]["n"])
    _, density = program_facts(os.path.join(examples, "cloth", "cloth.sim"))
    masses = [0.0] * len(pts)
    for t in tris:
        for i in t:
            masses[i] += density * triangle_area(pts, t) / 3
    print("cloth square: area %.12g, density %g" % (sum(triangle_area(pts, t) for t in tris),
                                                    density))
    # The flat cloth starts at rest at y = 0 (energy 0), and Velocity Verlet nearly conserves
    # energy: what the program reports must stay tiny against the kinetic energy it gained,
    # computed here from the last frame's v and m.
    def cloth_energy(xs, pd):
        v = array_values(pd, "v", len(pts), 3, "energy")
        m = array_values(pd, "m", len(pts), 1, "energy")
        kinetic = sum(0.5 * mi * sum(a * a for a in vi) for vi, (mi,) in zip(v, m))
        got = csv_column(os.path.join(outdir, "cloth", scene["output"]["csv"]), "energy")[-1]
        print("ok: cloth energy %.3g J against a kinetic energy of %.3g J" % (got, kinetic))
        if not abs(got) <= 1e-5 * kinetic:
            fail("the cloth's energy drifted to %g J (kinetic %g J)" % (got, kinetic))
        return got
    check_scene(simit, os.path.join(examples, "cloth", "square.toml"),
                os.path.join(outdir, "cloth"), 2, (pts, tris), VTK_TRIANGLE, masses, None,
                cloth_energy)


main()
