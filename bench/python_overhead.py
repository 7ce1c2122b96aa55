#!/usr/bin/python3
"""Per-frame time of the fem bunny stepped from Python (simit.Scene, step() in a loop,
reorder=True as `simit run` renumbers, output=False) against `simit run` on the same scene,
executor and frame count. Repeats alternate between the two; medians; prints the ratio.

Usage: PYTHONPATH=build/python /usr/bin/python3 bench/python_overhead.py
           [--frames 20] [--repeats 5] [--executor interpreter|jit|both] [--threads N]
           [--simit PATH]

Neither side writes output: `simit run` runs a copy of the scene without its [output] table
and reports each frame's ms in its progress lines ("this frame X ms", to 0.1 ms) and their
mean in its last line ("N frames, X ms/frame"); Python's frame is the wall time of one
scene.step() call, which adds the module's work (the GIL, the results dict) to the same step.
Two figures per side: the mean over all frames (as `simit run` prints it: the first frame
holds the JIT's compiles, which its kernel cache may skip) and the median of frames 2..N
(the steady state, the figure the ratio is about).
"""
import argparse
import os
import re
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
SCENE = REPO / "examples" / "fem" / "bunny.toml"


def default_simit():
    for candidate in (REPO / "build" / "simit", REPO / "build" / "tools" / "simit"):
        if candidate.is_file():
            return candidate
    return REPO / "build" / "simit"


def scene_without_output(folder):
    """A copy of the scene with no [output] table, so that `simit run` writes nothing either
    (writing the .vtu series would load the frames it times), its paths made absolute."""
    text = SCENE.read_text()
    text = text[: text.index("[output]")]
    text = re.sub(r'^(\s*(?:program|mesh)\s*=\s*")([^"]+)"',
                  lambda m: f'{m.group(1)}{(SCENE.parent / m.group(2)).resolve()}"',
                  text, flags=re.M)  # fmt: skip
    copy = Path(folder) / SCENE.name
    copy.write_text(text)
    return copy


def cli_frames(simit_path, executor, frames, threads):
    """Per-frame ms of one `simit run`, from its progress lines ("this frame X ms"); checks
    them against its last line ("N frames, X ms/frame")."""
    with tempfile.TemporaryDirectory() as folder:
        scene = scene_without_output(folder)
        proc = subprocess.run(
            [str(simit_path), "run", str(scene), "--frames", str(frames), "--executor", executor,
             *(["--threads", str(threads)] if threads else [])],
            capture_output=True, text=True, check=True, cwd=folder,
        )  # fmt: skip
        if sorted(os.listdir(folder)) != [SCENE.name]:
            sys.exit(f"simit run wrote files: {os.listdir(folder)}")
    ms = [float(m) for m in re.findall(r"this frame ([0-9.]+) ms", proc.stdout)]
    summary = re.search(r"(\d+) frames, ([0-9.]+) ms/frame", proc.stdout)
    if summary is None or int(summary.group(1)) != frames or len(ms) != frames:
        sys.exit(f"unexpected output of simit run:\n{proc.stdout}")
    printed = float(summary.group(2))
    # The progress lines round to 0.1 ms.
    if abs(printed - statistics.fmean(ms)) > 0.1 + 1e-3 * printed:
        sys.exit(f"simit run printed {printed} ms/frame, its frames' mean is "
                 f"{statistics.fmean(ms)}")
    return ms


def python_frames(executor, frames, threads):
    """Per-frame ms of scene.step() in a loop."""
    import simit

    scene = simit.Scene(str(SCENE), backend=executor, threads=threads, reorder=True, output=False)
    scene.init()
    ms = []
    for _ in range(frames):
        start = time.perf_counter()
        scene.step()
        ms.append((time.perf_counter() - start) * 1e3)
    scene.close()
    return ms


def measure(simit_path, executor, frames, repeats, threads):
    sides = {"simit run": [], "python": []}
    for r in range(repeats):
        # Alternate which goes first, so that neither always runs on a warmer machine.
        order = ["simit run", "python"] if r % 2 == 0 else ["python", "simit run"]
        for side in order:
            if side == "simit run":
                sides[side].append(cli_frames(simit_path, executor, frames, threads))
            else:
                sides[side].append(python_frames(executor, frames, threads))
    rows = {}
    for side, runs in sides.items():
        mean_all = statistics.median(statistics.fmean(run) for run in runs)
        steady = statistics.median(statistics.median(run[1:]) for run in runs)
        rows[side] = (mean_all, steady)
    print(f"fem bunny, {executor}, threads {threads or 'default (every core)'}, {frames} frames,"
          f" {repeats} interleaved repeats (medians):")
    for side, (mean_all, steady) in rows.items():
        print(f"  {side:10s} {mean_all:9.2f} ms/frame (all frames)"
              f"  {steady:9.2f} ms/frame (frames 2..)")
    ratio = rows["python"][1] / rows["simit run"][1]
    ratio_all = rows["python"][0] / rows["simit run"][0]
    print(f"  python / simit run: {ratio:.3f} (frames 2..), {ratio_all:.3f} (all frames)")
    return ratio


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=20)
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--executor", choices=["interpreter", "jit", "both"], default="both")
    parser.add_argument("--threads", type=int, default=None,
                        help="the JIT's threads on both sides (default: every core)")
    parser.add_argument("--simit", type=Path, default=default_simit())
    args = parser.parse_args()
    if args.frames < 2:
        parser.error("--frames must be at least 2")
    import simit

    executors = ["interpreter", "jit"] if args.executor == "both" else [args.executor]
    if "jit" in executors and not simit.jit_available():
        print("this build has no JIT: measuring the interpreter only")
        executors = ["interpreter"]
    for executor in executors:
        measure(args.simit, executor, args.frames, args.repeats, args.threads)


if __name__ == "__main__":
    main()
