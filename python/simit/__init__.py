"""Simit, a language for physical simulation, from Python.

Programs (simit.Program), sets whose fields are numpy views of the storage the programs run
on (simit.Set), scene files (simit.Scene) and mesh files (simit.read_mesh). See the
project's python/README.md.
"""

from ._errors import BindError, CompileError, Diagnostic, Error, RuntimeError  # noqa: A004
from ._mesh import Mesh
from ._simit import (
    Function,
    Matrix,
    Program,
    Scene,
    Set,
    __version__,
    default_threads,
    jit_available,
    read_mesh,
)

__all__ = [
    "BindError", "CompileError", "Diagnostic", "Error", "Function", "Matrix", "Mesh", "Program",
    "RuntimeError", "Scene", "Set", "__version__", "default_threads", "jit_available",
    "read_mesh",
]


def _progress(frames):
    """A progress bar over the frames where tqdm is installed, else plain lines."""
    try:
        from tqdm import tqdm  # optional: Debian's python3-tqdm
    except ImportError:
        return None
    return tqdm(total=frames, unit="frame")


def _scene_run(self, frames=None, progress=True):
    """Runs `frames` frames (the scene's count when None) after init, as `simit run` does,
    writes the output the scene asks for and closes it. Returns the last step's results."""
    import sys
    import time

    total = self.frames if frames is None else int(frames)
    if total < 0:
        raise Error(f"frames must be >= 0, not {total}")
    if not self.initialised:
        self.init()
    bar = _progress(total) if progress else None
    results = {}
    start = time.perf_counter()
    try:
        for n in range(1, total + 1):
            t0 = time.perf_counter()
            results = self.step()
            if bar is not None:
                bar.update(1)
            elif progress:
                ms = 1e3 * (time.perf_counter() - t0)
                print(f"frame {n}/{total}: {ms:.1f} ms", file=sys.stderr, flush=True)
    finally:
        if bar is not None:
            bar.close()
    self.close()
    if progress and bar is None and total:
        elapsed = time.perf_counter() - start
        print(f"{total} frames in {elapsed:.2f} s", file=sys.stderr, flush=True)
    return results


Scene.run = _scene_run
