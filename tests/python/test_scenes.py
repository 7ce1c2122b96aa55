# simit.Scene against `simit run`: the springs and fem bunny scenes stepped 10 frames from
# Python equal the command's --final-csv and statistics, interpreted and compiled; step()'s
# results; what is written with output=False, a folder, or the scene's own [output].
import functools
import re
from pathlib import Path

import numpy as np
import pytest

import simit
from conftest import (
    REPO,
    read_stats_csv,
    read_xyz_csv,
    require_backend,
    run_cli,
    scene_copy,
    simit_binary_path,
)

FRAMES = 10
# Scene name -> (scene file, its vertex set, the position field).
SCENES = {
    "springs": (REPO / "examples" / "springs" / "bunny.toml", "points", "x"),
    "fem": (REPO / "examples" / "fem" / "bunny.toml", "verts", "x"),
}
STEP_RESULTS = {"cg_iterations", "cg_residual", "energy"}


@functools.lru_cache(maxsize=None)
def python_run(name, backend, reorder):
    """FRAMES frames of a scene stepped from Python: the positions in the mesh's numbering
    and step()'s results per frame."""
    path, points, field = SCENES[name]
    scene = simit.Scene(str(path), backend=backend, output=False, reorder=reorder)
    scene.init()
    assert scene.frame == 0
    results = [scene.step() for _ in range(FRAMES)]
    assert scene.frame == FRAMES
    s = scene.sets[points]
    x = np.array(s[field])
    if reorder:
        numbers = np.asarray(s.mesh_numbers)
        assert sorted(numbers.tolist()) == list(range(len(s)))  # a permutation
        in_mesh_order = np.empty_like(x)
        in_mesh_order[numbers] = x  # row i is mesh vertex numbers[i]
        x = in_mesh_order
    scene.close()
    return x, results


@functools.lru_cache(maxsize=None)
def cli_run(name, backend, folder, reorder_copy=False):
    """The same FRAMES frames by `simit run`: its --final-csv and its statistics CSV."""
    path = SCENES[name][0]
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    if reorder_copy:
        path = scene_copy(path, folder, reorder=False)
    final = folder / "final.csv"
    out = folder / "out"
    run_cli(
        simit_binary_path(),
        "run", path, "--frames", FRAMES, "--final-csv", final,
        "--executor", backend, "--output", out,
        cwd=folder,
    )  # fmt: skip
    return read_xyz_csv(final), read_stats_csv(out / "bunny_stats.csv")


def check_against_cli(python, cli):
    x, results = python
    final, stats = cli
    # The CSV prints 17 significant digits, enough to give back every double: equal bits.
    assert x.shape == final.shape
    np.testing.assert_array_equal(x, final)
    assert len(results) == FRAMES == len(stats["frame"])
    for i, r in enumerate(results):
        assert set(r) == STEP_RESULTS
        assert isinstance(r["cg_iterations"], int)
        assert r["cg_iterations"] == stats["cg_iterations"][i]
        assert r["cg_residual"] == stats["cg_residual"][i]
        assert r["energy"] == stats["energy"][i]


@pytest.mark.parametrize("backend", ["interpreter", "jit"])
@pytest.mark.parametrize("name", sorted(SCENES))
def test_scene_matches_simit_run(tmp_path_factory, name, backend):
    require_backend(backend)
    cli = cli_run(name, backend, str(tmp_path_factory.mktemp(f"{name}_{backend}")))
    check_against_cli(python_run(name, backend, True), cli)


@pytest.mark.parametrize("name", sorted(SCENES))
def test_jit_and_interpreter_arrays_equal(name):
    require_backend("jit")
    x_interp, r_interp = python_run(name, "interpreter", True)
    x_jit, r_jit = python_run(name, "jit", True)
    # The project promises the same bits from both executors (README, Renumbering).
    assert x_interp.tobytes() == x_jit.tobytes()
    assert r_interp == r_jit


def test_mesh_order_matches_simit_run_without_renumbering(tmp_path):
    # Python's default keeps the mesh's order; so does a scene with `reorder = false`.
    cli = cli_run("springs", "interpreter", str(tmp_path), reorder_copy=True)
    check_against_cli(python_run("springs", "interpreter", False), cli)
    # The renumbered run sums in another order: close, not equal.
    x_reordered, _ = python_run("springs", "interpreter", True)
    np.testing.assert_allclose(x_reordered, cli[0], rtol=1e-6, atol=1e-9)


def test_mesh_order_sets_follow_the_mesh(repo_root):
    mesh = simit.read_mesh(str(repo_root / "examples" / "data" / "bunny.1.node"))
    scene = simit.Scene(str(SCENES["fem"][0]), output=False)
    scene.init()
    verts, tets = scene.sets["verts"], scene.sets["tets"]
    np.testing.assert_array_equal(verts["x"], mesh.points)  # x = "position", row i = vertex i
    np.testing.assert_array_equal(tets.endpoints, mesh.tets)
    pinned = mesh.points[:, 1] < 1e-4  # pinned = "y < 1e-4"
    np.testing.assert_array_equal(verts["pinned"], pinned)
    # init zeroes the velocity of pinned vertices and keeps [0.1, 0, 0.1] elsewhere.
    np.testing.assert_array_equal(verts["v"][pinned], 0.0)
    np.testing.assert_array_equal(verts["v"][~pinned], np.tile([0.1, 0.0, 0.1], (sum(~pinned), 1)))
    scene.close()


def test_output_false_writes_nothing(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    scene = simit.Scene(str(SCENES["springs"][0]), output=False)
    scene.run(frames=2)
    assert scene.frame == 2
    assert list(tmp_path.iterdir()) == []


def test_output_folder_gets_the_series(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    out = tmp_path / "series"
    with simit.Scene(str(SCENES["springs"][0]), output=str(out)) as scene:
        scene.run(frames=3)
        assert scene.frame == 3
    assert sorted(p.name for p in tmp_path.iterdir()) == ["series"]  # nothing else written
    names = {p.name for p in out.iterdir()}
    vtus = [f"bunny_{i:06d}.vtu" for i in range(4)]  # frame 0 (after init) and 3 frames
    assert set(vtus) | {"bunny.pvd", "bunny_stats.csv"} <= names
    pvd = (out / "bunny.pvd").read_text()
    listed = re.findall(r'<DataSet timestep="([^"]+)"[^>]*file="([^"]+)"', pvd)
    assert [f for _, f in listed] == vtus
    np.testing.assert_allclose([float(t) for t, _ in listed], [0.0, 0.01, 0.02, 0.03])
    stats = read_stats_csv(out / "bunny_stats.csv")
    np.testing.assert_array_equal(stats["frame"], [1, 2, 3])


def test_default_output_is_the_scenes(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    scene = simit.Scene(str(SCENES["springs"][0]))
    scene.run(frames=1)
    pvd = tmp_path / "springs-bunny" / "bunny.pvd"  # [output] folder, relative to the cwd
    assert pvd.is_file()
    assert (tmp_path / "springs-bunny" / "bunny_000001.vtu").is_file()
