# Shared fixtures and helpers of the Python module's tests: the repository, the simit binary,
# executor selection (the JIT only where the build has it), scene copies and CSV readers.
import os
import re
import subprocess
from pathlib import Path

import numpy as np
import pytest

import simit

REPO = Path(__file__).resolve().parents[2]
BACKENDS = ["interpreter", "jit"]


def simit_binary_path():
    """The `simit` command: $SIMIT_BINARY (ctest sets it), else the build folder's."""
    env = os.environ.get("SIMIT_BINARY")
    if env:
        return Path(env)
    for candidate in (REPO / "build" / "simit", REPO / "build" / "tools" / "simit"):
        if candidate.is_file():
            return candidate
    return REPO / "build" / "simit"


@pytest.fixture(scope="session")
def repo_root():
    return REPO


@pytest.fixture(scope="session")
def simit_binary():
    path = simit_binary_path()
    if not path.is_file():
        pytest.fail(f"no simit binary at {path} (set SIMIT_BINARY)")
    return path


def require_backend(backend):
    """Skips a JIT case in a build without the JIT, after checking that asking for it fails
    with a simit.Error that says why (the README's promise)."""
    if backend == "jit" and not simit.jit_available():
        with pytest.raises(simit.Error) as info:
            simit.Program(source="export func f()\nend\n", backend="jit").compile("f")
        assert re.search(r"(?i)llvm|jit", str(info.value)), str(info.value)
        reason = f"this build has no JIT ({info.value})"
        print(reason)
        pytest.skip(reason)


@pytest.fixture(params=BACKENDS)
def backend(request):
    require_backend(request.param)
    return request.param


def run_cli(binary, *args, cwd=None, check=True):
    """Runs `simit ARGS...` and returns the completed process (output as text)."""
    proc = subprocess.run(
        [str(binary), *map(str, args)], cwd=cwd, capture_output=True, text=True, timeout=300
    )
    if check and proc.returncode != 0:
        raise AssertionError(
            f"simit {' '.join(map(str, args))} failed ({proc.returncode}):\n"
            f"{proc.stdout}\n{proc.stderr}"
        )
    return proc


def read_xyz_csv(path):
    """A --final-csv file: a header `x,y,z` and one line per mesh vertex."""
    with open(path) as f:
        header = f.readline().strip()
    assert header == "x,y,z", header
    return np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)


def read_stats_csv(path):
    """The scene's statistics CSV: a dict from column name to a float array (one per frame)."""
    with open(path) as f:
        names = f.readline().strip().split(",")
    data = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    return {name: data[:, i] for i, name in enumerate(names)}


def scene_copy(scene, folder, reorder=None, output_folder=None):
    """Writes a copy of the scene file `scene` into `folder` with its program and mesh paths
    made absolute (they are relative to the scene file), and `reorder = ...` or the output
    folder set when given. Returns the copy's path."""
    scene = Path(scene).resolve()
    lines = []
    for line in scene.read_text().splitlines():
        m = re.match(r'^(\s*(?:program|mesh)\s*=\s*")([^"]+)(".*)$', line)
        if m and not Path(m.group(2)).is_absolute():
            line = m.group(1) + str((scene.parent / m.group(2)).resolve()) + m.group(3)
        m = re.match(r'^(\s*folder\s*=\s*")([^"]+)(".*)$', line)
        if m and output_folder is not None:
            line = m.group(1) + str(output_folder) + m.group(3)
        lines.append(line)
    if reorder is not None:
        # Top-level keys must precede the first table.
        first_table = next(i for i, l in enumerate(lines) if l.lstrip().startswith("["))
        lines.insert(first_table, f"reorder = {'true' if reorder else 'false'}")
    copy = Path(folder) / scene.name
    copy.write_text("\n".join(lines) + "\n")
    return copy
