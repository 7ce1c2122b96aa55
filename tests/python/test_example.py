# examples/python/springs.py: it runs, plots, and its energies are those of `simit run` on the
# springs bunny scene kept in the mesh's numbering.
import importlib.util
import os
import subprocess
import sys

import numpy as np
import pytest

import simit
from conftest import REPO, read_stats_csv, run_cli, scene_copy

EXAMPLE = REPO / "examples" / "python" / "springs.py"
FRAMES = 3


@pytest.fixture(scope="module")
def example():
    spec = importlib.util.spec_from_file_location("springs_example", EXAMPLE)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_example_energies_match_simit_run(example, tmp_path, simit_binary):
    png = tmp_path / "energy.png"
    energies = example.run(FRAMES, str(png), verbose=False)
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert energies.shape == (FRAMES,) and np.isfinite(energies).all()

    backend = "jit" if simit.jit_available() else "interpreter"
    scene = scene_copy(REPO / "examples" / "springs" / "bunny.toml", tmp_path, reorder=False)
    out = tmp_path / "cli"
    run_cli(simit_binary, "run", scene, "--frames", FRAMES, "--executor", backend,
            "--output", out, cwd=tmp_path)  # fmt: skip
    np.testing.assert_array_equal(energies, read_stats_csv(out / "bunny_stats.csv")["energy"])


def test_example_as_a_script(tmp_path):
    png = tmp_path / "plot.png"
    env = dict(os.environ)
    # The module this test imported, wherever it was found.
    module_dir = os.path.dirname(os.path.dirname(os.path.abspath(simit.__file__)))
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [module_dir, env.get("PYTHONPATH")]))
    proc = subprocess.run(
        [sys.executable, str(EXAMPLE), "2", str(png)],
        cwd=tmp_path, env=env, capture_output=True, text=True, timeout=300,
    )  # fmt: skip
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert png.is_file() and png.stat().st_size > 0
    assert f"wrote {png}" in proc.stdout
    energy = float(proc.stdout.split("frame 2: energy ")[1].split(",")[0])
    assert np.isfinite(energy)
    assert list(tmp_path.iterdir()) == [png]  # nothing else written
