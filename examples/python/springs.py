#!/usr/bin/python3
"""The springs example driven from Python: the bunny's mesh read with simit.read_mesh, the
sets made from numpy arrays, springs.sim compiled and stepped, the energy per frame plotted.

Usage: PYTHONPATH=build/python /usr/bin/python3 examples/python/springs.py [FRAMES] [PNG]
"""
import argparse
import sys
from pathlib import Path

import numpy as np

import simit

HERE = Path(__file__).resolve().parent
EXAMPLES = HERE.parent
MESH = EXAMPLES / "data" / "bunny.1.node"
PROGRAM = EXAMPLES / "springs" / "springs.sim"


def build_sets(mesh_path=MESH):
    """The sets of examples/springs/bunny.toml: one point per mesh vertex, rescaled to [0, 1]
    on each axis and pinned where the rescaled z < 0.1, at rest; one spring per line of the
    .edge file. springs.sim's init computes the masses and rest lengths."""
    mesh = simit.read_mesh(str(mesh_path))
    lo, hi = mesh.points.min(axis=0), mesh.points.max(axis=0)
    x = (mesh.points - lo) / (hi - lo)

    points = simit.Set(len(x))
    points.add_field("x", float, shape=(3,))[:] = x
    points.add_field("v", float, shape=(3,))  # zero: at rest
    points.add_field("m", float)
    points.add_field("pinned", bool)[:] = x[:, 2] < 0.1
    springs = simit.Set(endpoints=(points, points), connectivity=mesh.edges)
    springs.add_field("l0", float)
    return points, springs


def choose_backend():
    if simit.jit_available():
        return "jit"
    print("this build has no JIT (built without LLVM): running the interpreter", file=sys.stderr)
    return "interpreter"


def run(frames=100, png="springs_energy.png", backend=None, verbose=True):
    """Runs `frames` frames and plots the energy per frame to `png`. Returns the energies."""
    backend = backend or choose_backend()
    program = simit.Program(str(PROGRAM), backend=backend)
    init = program.compile("init")
    step = program.compile("step")
    points, springs = build_sets()
    for fn in (init, step):
        fn.bind("points", points)
        fn.bind("springs", springs)
    # The scene's [tensors]: CG stops at r'r <= 1e-12 or after 50 iterations.
    step.bind("cg_tol", 1e-12)
    step.bind("cg_max", 50)
    init.run()

    x = points["x"]  # a view: each step's positions show in it
    energies = np.empty(frames)
    for frame in range(frames):
        step.run()
        energies[frame] = step.result("energy")
        if verbose and ((frame + 1) % 10 == 0 or frame + 1 == frames):
            print(
                f"frame {frame + 1}: energy {energies[frame]:.6f}, "
                f"CG {step.result('cg_iterations')} iterations, "
                f"lowest point y = {x[:, 1].min():.4f}"
            )

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6, 4))
    ax.plot(np.arange(1, frames + 1), energies)
    ax.set_xlabel("frame")
    ax.set_ylabel("total energy (J)")
    ax.set_title(f"springs bunny ({backend})")
    fig.tight_layout()
    fig.savefig(png)
    plt.close(fig)
    if verbose:
        print(f"wrote {Path(png).resolve()}")
    return energies


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("frames", nargs="?", type=int, default=100, help="frames (default 100)")
    parser.add_argument(
        "png", nargs="?", default="springs_energy.png", help="the plot (default springs_energy.png)"
    )
    args = parser.parse_args(argv)
    if args.frames < 1:
        parser.error("frames must be at least 1")
    run(args.frames, args.png)


if __name__ == "__main__":
    main()
