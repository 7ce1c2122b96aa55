#!/usr/bin/env python3
"""The speed-and-error report of the fem example: CG tolerance x float64/float32.

Usage: bench/fem_accuracy.py [--build DIR] [--scene SCENE] [--frames K] [--tols LIST]
                             [--cg-max N] [--out DIR]

Runs examples/fem/bunny.toml (or --scene) for K frames (default 5) once per point of the
sweep: every CG tolerance of --tols (default 1e-2, 1e-3, ..., 1e-16) with float64 and with
float32 (`simit run --float32`). Each point gives the median ms/frame and the error of the
final positions against a reference run: float64 with CG converged to a relative residual
|r| / |b| <= 1e-14 in every frame.

Units of the tolerance. fem.sim's CG stops when r'r <= cg_tol (or after cg_max iterations),
r being the residual of (M - h^2 K) v' = M v + h (f + M g): an absolute bound on the squared
2-norm of a momentum residual, in (kg m/s)^2, not a relative one. Each point also records the
relative residual sqrt(r'r / b'b) that the program returns (cg_residual), the last frame's.
On the bunny b'b is about 10 (kg m/s)^2, so cg_tol = 1e-12 stops near |r|/|b| = 3e-7, and
the scene's own cg_max = 100 stops first (at about 4e-5): the sweep raises cg_max (--cg-max,
default 1000) so that the tolerance decides.

The reference uses cg_tol = 1e-28 (|r|/|b| about 3e-15 on the bunny) and cg_max = 20000;
the script checks that every reference frame reached |r|/|b| <= 1e-14 and tightens cg_tol
(up to three times) when one did not.

Error: max over vertices of |x - x_ref| divided by max over vertices of |x_ref| (the scale of
the object), and the RMS of |x - x_ref| over the same scale; also the max error relative to
the largest displacement of the reference over the K frames (max |x_ref - x_0|), which says
how much of the motion is wrong.

Writes DIR/fem_accuracy.csv, DIR/fem_accuracy.png (error against the median wall ms/frame),
DIR/fem_accuracy_cpu.png (against CPU ms/frame: the run's CPU time less that of a run of no
frames, over K; steadier than wall time when other processes share the machine) and
DIR/fem_accuracy_tol.png (against cg_tol), default DIR fem-accuracy: with gnuplot where
installed, else with the build's bench/plot_png. The precisions alternate at each tolerance,
so that a change of the machine's load hits both alike. Not a test; the default sweep takes about
10 minutes with the interpreter (about 2 s/frame on the bunny). Note that the interpreter
emulates float32 by rounding every result, so its float32 times say nothing about the speed
of single precision; what the float32 series shows is its error floor.
"""
import argparse
import csv
import math
import os
import re
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DEFAULT_TOLS = ",".join("1e-%d" % k for k in range(2, 17))


def make_scene(source, cg_tol, cg_max, workdir, name):
    """A copy of SOURCE with the program and mesh paths made absolute and [tensors] set."""
    base = os.path.dirname(os.path.abspath(source))
    text = open(source).read()
    def absolute(m):
        return '%s = "%s"' % (m.group(1), os.path.normpath(os.path.join(base, m.group(2))))
    text = re.sub(r'(?m)^(program|mesh) = "([^"]+)"', absolute, text)
    text, n_tol = re.subn(r"(?m)^cg_tol = \S+", "cg_tol = %r" % cg_tol, text)
    text, n_max = re.subn(r"(?m)^cg_max = \S+", "cg_max = %d" % cg_max, text)
    if n_tol != 1 or n_max != 1:
        sys.exit("%s: expected one 'cg_tol = ' and one 'cg_max = ' line in [tensors]" % source)
    path = os.path.join(workdir, name + ".toml")
    with open(path, "w") as f:
        f.write(text)
    return path


def read_positions(path):
    with open(path) as f:
        rows = list(csv.reader(f))
    return [tuple(float(v) for v in r) for r in rows[1:] if r]


def run(simit, scene, frames, outdir, float32):
    """Runs the scene; returns the per-frame rows of its CSV, final positions and CPU seconds."""
    shutil.rmtree(outdir, ignore_errors=True)
    final = outdir + "-final.csv"
    argv = [simit, "run"] + (["--float32"] if float32 else []) + [
        "--frames", str(frames), "--output", outdir, "--final-csv", final, scene]
    with open(outdir + ".log", "w") as log:
        child = subprocess.Popen(argv, stdout=log, stderr=subprocess.STDOUT, cwd=ROOT)
        _, status, usage = os.wait4(child.pid, 0)
    child.returncode = os.waitstatus_to_exitcode(status)  # reaped by wait4
    if child.returncode != 0:
        sys.exit("failed (%d): %s; see %s.log" % (child.returncode, " ".join(argv), outdir))
    stats = [f for f in os.listdir(outdir) if f.endswith(".csv")]
    with open(os.path.join(outdir, stats[0])) as f:
        rows = list(csv.DictReader(f))
    return rows, read_positions(final), usage.ru_utime + usage.ru_stime


def errors(x, ref, x0):
    scale = max(math.sqrt(sum(c * c for c in p)) for p in ref)
    motion = max(math.dist(p, q) for p, q in zip(ref, x0))
    d = [math.dist(p, q) for p, q in zip(x, ref)]
    worst = max(d)
    rms = math.sqrt(sum(e * e for e in d) / len(d))
    return worst / scale, rms / scale, worst / motion if motion > 0 else float("nan")


def plot(csv_path, png_path, build, xcol, xlabel, title):
    """Log-log plot of max_rel_error against column XCOL, one series per precision."""
    ylabel = "max position error / object size"  # max |x - x_ref| / max |x_ref|
    gnuplot = shutil.which("gnuplot")
    if gnuplot:
        rows = list(csv.DictReader(open(csv_path)))
        floor = 1e-17  # an exact match has no place on a log axis
        datafiles = []
        for prec in ("float64", "float32"):
            path = "%s.%s.%s.dat" % (csv_path, xcol, prec)
            with open(path, "w") as f:
                for r in rows:
                    if r["precision"] == prec:
                        f.write("%s %g\n" % (r[xcol], max(float(r["max_rel_error"]), floor)))
            datafiles.append((prec, path))
        script = "\n".join([
            "set terminal pngcairo size 820,580",
            "set output '%s'" % png_path,
            "set logscale xy", "set grid",
            'set title "%s"' % title, 'set xlabel "%s"' % xlabel, 'set ylabel "%s"' % ylabel,
            "set format x '%g'", "set format y '1e%L'", "set key top right",
            "plot " + ", ".join("'%s' using 1:2 with linespoints title '%s'" % (p, n)
                                 for n, p in datafiles)])
        subprocess.run([gnuplot], input=script, text=True, check=True)
        for _, p in datafiles:
            os.remove(p)
        return "gnuplot"
    plotter = os.path.join(build, "bench", "plot_png")
    if not os.access(plotter, os.X_OK):
        print("no gnuplot and no %s (build the target plot_png): no plot" % plotter)
        return None
    subprocess.run([plotter, csv_path, png_path, "--x", xcol, "--y", "max_rel_error",
                    "--series", "precision", "--title", title, "--xlabel", xlabel,
                    "--ylabel", ylabel], check=True)
    return "plot_png"


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--build", default=os.path.join(ROOT, "build"),
                   help="the build folder with tools/simit (and bench/plot_png); default build")
    p.add_argument("--scene", default=os.path.join(ROOT, "examples", "fem", "bunny.toml"))
    p.add_argument("--frames", type=int, default=5, help="frames per run, K (default 5)")
    p.add_argument("--tols", default=DEFAULT_TOLS,
                   help="CG tolerances (r'r, absolute), comma-separated (default 1e-2 .. 1e-16)")
    p.add_argument("--cg-max", type=int, default=1000,
                   help="CG iteration cap of the sweep (default 1000)")
    p.add_argument("--ref-tol", type=float, default=1e-28,
                   help="cg_tol of the reference (default 1e-28; tightened when needed)")
    p.add_argument("--out", default="fem-accuracy", help="output folder (default fem-accuracy)")
    args = p.parse_args()
    build = os.path.abspath(args.build)
    simit = os.path.join(build, "tools", "simit")
    if not os.access(simit, os.X_OK):
        sys.exit("missing %s (build the target simit)" % simit)
    tols = [float(t) for t in args.tols.split(",") if t.strip()]
    os.makedirs(args.out, exist_ok=True)
    workdir = tempfile.mkdtemp(prefix="simit-fem-accuracy-")
    started = time.monotonic()
    try:
        # Rest positions (0 frames), then the reference, tightened until it is converged.
        scene = make_scene(args.scene, args.ref_tol, 20000, workdir, "rest")
        _, x0, setup_cpu = run(simit, scene, 0, os.path.join(workdir, "rest"), False)
        ref_tol = args.ref_tol
        for attempt in range(4):
            scene = make_scene(args.scene, ref_tol, 20000, workdir, "reference")
            rows, ref, _ = run(simit, scene, args.frames, os.path.join(workdir, "reference"), False)
            worst = max(float(r["cg_residual"]) for r in rows)
            iters = [int(r["cg_iterations"]) for r in rows]
            print("reference: cg_tol %g, CG iterations %s, max |r|/|b| %.2e"
                  % (ref_tol, iters, worst), flush=True)
            if worst <= 1e-14:
                break
            if attempt == 3:
                sys.exit("the reference did not converge to |r|/|b| <= 1e-14")
            ref_tol *= (1e-14 / worst) ** 2 / 4

        # The two precisions alternate, so that a change in the machine's load between the
        # beginning and the end of the sweep does not separate them.
        results = []
        for tol in tols:
            for prec in ("float64", "float32"):
                scene = make_scene(args.scene, tol, args.cg_max, workdir, "point")
                rows, x, cpu = run(simit, scene, args.frames, os.path.join(workdir, "point"),
                                   prec == "float32")
                worst, rms, of_motion = errors(x, ref, x0)
                its = [int(r["cg_iterations"]) for r in rows]
                point = {
                    "precision": prec, "cg_tol": tol,
                    "ms_per_frame": statistics.median(float(r["ms"]) for r in rows),
                    "assembly_ms": statistics.median(float(r["assembly_ms"]) for r in rows),
                    "solve_ms": statistics.median(float(r["solve_ms"]) for r in rows),
                    "cg_iterations": statistics.median(its),
                    "capped": sum(1 for i in its if i >= args.cg_max),
                    "rel_residual": float(rows[-1]["cg_residual"]),
                    "max_rel_error": worst, "rms_rel_error": rms,
                    "max_error_of_motion": of_motion, "cpu_s": cpu,
                    # CPU time per frame: the run's less that of a run without frames (reading,
                    # init, output); unlike wall time, other processes on the machine hardly
                    # change it.
                    "cpu_ms_per_frame": 1e3 * max(0.0, cpu - setup_cpu) / args.frames}
                results.append(point)
                print("%s cg_tol %-7g %8.1f ms/frame (assembly %.1f, solve %.1f), CG %g it%s, "
                      "|r|/|b| %.1e, max rel error %.2e, rms %.2e"
                      % (prec, tol, point["ms_per_frame"], point["assembly_ms"], point["solve_ms"],
                         point["cg_iterations"],
                         " (%d frames capped)" % point["capped"] if point["capped"] else "",
                         point["rel_residual"], worst, rms), flush=True)
    finally:
        shutil.rmtree(workdir, ignore_errors=True)

    csv_path = os.path.join(args.out, "fem_accuracy.csv")
    with open(csv_path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(results[0]))
        w.writeheader()
        for r in sorted(results, key=lambda r: (r["precision"] != "float64", -r["cg_tol"])):
            w.writerow({k: ("%.6g" % v if isinstance(v, float) else v) for k, v in r.items()})
    print("wrote %s" % csv_path)
    # The report's plot; the same against CPU time, which a busy machine disturbs less; and the
    # error against the tolerance itself, free of timing noise.
    what = "fem on %s, %d frames" % (os.path.splitext(os.path.basename(args.scene))[0], args.frames)
    for name, xcol, xlabel, title in (
            ("fem_accuracy.png", "ms_per_frame", "ms/frame (median)", what + ": error vs time"),
            ("fem_accuracy_cpu.png", "cpu_ms_per_frame", "CPU ms/frame",
             what + ": error vs CPU time"),
            ("fem_accuracy_tol.png", "cg_tol", "CG tolerance on r'r", what + ": error vs cg_tol")):
        png_path = os.path.join(args.out, name)
        how = plot(csv_path, png_path, build, xcol, xlabel, title)
        if how:
            print("wrote %s (%s)" % (png_path, how))
    print("total %.0f s" % (time.monotonic() - started))


if __name__ == "__main__":
    main()
