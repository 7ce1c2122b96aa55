#!/usr/bin/env python3
"""Speed against error for every example (fem, springs, cloth) and every executor built.

Usage: bench/accuracy.py [--build DIR] [--example fem,springs,cloth,...] [--executor LIST]
                         [--frames K] [--points LIST] [--precisions LIST] [--repeat N]
                         [--out DIR] [--plot-only] [--no-plot] [--table]

Each example runs its scene for K frames (default 10) once per point of a sweep, with
float64 and with float32 (`simit run --float32`), and each point gives the median ms/frame
and the error of the final positions against a float64 reference that is converged in the
sweep's own parameter:

  fem      examples/fem/bunny.toml. The sweep is CG's tolerance cg_tol (default 1e-2 .. 1e-16),
  springs  examples/springs/bunny.toml. Same sweep. fem.sim and springs.sim stop CG when
           r'r <= cg_tol or after cg_max iterations; the tolerance is an absolute bound on the
           squared 2-norm of the momentum residual of (M - h^2 K) v' = M v + h (f + M g), in
           (kg m/s)^2, not a relative one. The sweep raises cg_max to --cg-max (default 1000)
           so that the tolerance decides. The reference: cg_tol 1e-30 and cg_max 20000,
           checked to reach |r|/|b| <= 1e-14 (the cg_residual the programs return) in every
           frame, cg_tol tightened (up to three times) when a frame did not.
  cloth    examples/cloth/square.toml. Explicit Velocity Verlet, no solve: its accuracy knob
           is the time step h (cloth.sim's `const h`, with `const substeps` = 0.01 s / h so
           that a frame stays 1/100 s). The scene does not expose h, so each point runs a
           copy of cloth.sim with those two lines changed. Default substeps 15 .. 400; the
           reference: float64 with 1600 substeps (h = 6.25e-6). Steps above the membrane's
           stability limit blow up; such points are recorded as unstable (no error).
  fem_newton      tests/hard/base.toml: examples/fem/fem_newton.sim, Stable Neo-Hookean and
                  Newton (the robust model and integrator) on the hard-case suite's 240-tet
                  bar. The sweep is Newton's tolerance newton_tol (default 1e-1 .. 1e-8 m/s:
                  Newton stops when the RMS over the vertices of |dx| / h is at most that),
                  with the scene's PCG tolerance (relative, 1e-6). The reference: newton_tol
                  1e-9, PCG to |r|/|b| <= 1e-12, checked to stop below newton_max (200) in
                  every frame.
  springs_newton  tests/hard/springs_k1e6.toml: examples/springs/springs_newton.sim, Newton,
                  k = 1e6 N/m. Same sweep and reference.
  fem_newton_cg, springs_newton_cg  the same two scenes and reference, sweeping instead the
                  PCG tolerance cg_tol (relative, default 1e-1 .. 1e-10) at the scene's
                  newton_tol (1e-6 m/s).

Besides the sweep, each example runs once as it ships (its scene unchanged, float64): the
"shipped" point of the table and the plots. The Newton examples also record the Newton
iterations and line-search halvings per frame (the mean over the frames), and in `capped`
the frames where Newton stopped at newton_max.

Executors: --executor interpreter,jit,gpu (default: jit when this simit has it, else the
interpreter; gpu: `simit run --executor gpu`, the compiled maps on an NVIDIA GPU, refused
with simit's reason where it cannot run). The JIT and the GPU executor compile each site at
its first execution (--jit-threshold 0), so their compile time falls in frame 1, which their
medians leave out. The reference runs with the JIT when it is built (its results are the
interpreter's bit for bit), else with the interpreter. The interpreter emulates float32 by rounding every result, so its float32 times
say nothing about the speed of single precision.

Error: max over vertices of |x - x_ref| divided by max over vertices of |x_ref| (the size of
the object), and the RMS of |x - x_ref| over the same size; also the max error relative to
the largest displacement of the reference over the K frames (max |x_ref - x_0|), which says
how much of the motion is wrong. Timings: the median wall ms of the frames (--repeat N: the
least of N such medians); cpu_ms_per_frame is the run's CPU time less that of a run of no
frames, over K (with the JIT it includes the compiling).

Writes DIR/accuracy_EXAMPLE_EXECUTOR.csv per run and DIR/accuracy_EXAMPLE.png (default DIR
bench-accuracy) with matplotlib: error against ms/frame and against the sweep's parameter,
one series per executor and precision, from every accuracy_EXAMPLE_*.csv in DIR (so that an
interpreter run and a JIT run of the same example share one figure). --plot-only redraws the
figures from the CSVs; --no-plot draws none (no matplotlib needed); --table prints each
example's table in markdown. Not a test. With the
JIT the default sweep of all three examples takes a few minutes; with the interpreter about
0.5 to 1 s per fem frame (use --points to thin it).
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

# The same tests of whether this simit has the JIT or can run the GPU executor, and the same
# spelling of the option that selects one.
from run_bench import executor_flag, executor_unavailable, jit_available

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PRECISIONS = ("float64", "float32")
COMPILING = ("jit", "gpu")  # the executors that compile sites (the rest: the interpreter)
FRAME_TIME = 0.01  # cloth's frame, substeps * h


class Example:
    """One example's sweep: its scene, its parameter and how a point changes the scene."""

    def __init__(self, name, scene, param, default_points, label):
        self.name, self.scene, self.param = name, scene, param
        self.default_points, self.label = default_points, label


EXAMPLES = {
    "fem": Example("fem", "examples/fem/bunny.toml", "cg_tol",
                   ["1e-%d" % k for k in range(2, 17)], "CG tolerance cg_tol on r'r"),
    "springs": Example("springs", "examples/springs/bunny.toml", "cg_tol",
                       ["1e-%d" % k for k in range(2, 17)], "CG tolerance cg_tol on r'r"),
    "cloth": Example("cloth", "examples/cloth/square.toml", "h",
                     ["15", "18", "20", "25", "35", "50", "70", "100", "200", "400"],
                     "time step h (s)"),
    "fem_newton": Example("fem_newton", "tests/hard/base.toml", "newton_tol",
                          ["1e-%d" % k for k in range(1, 9)],
                          "Newton tolerance newton_tol (RMS |dx|/h, m/s)"),
    "springs_newton": Example("springs_newton", "tests/hard/springs_k1e6.toml", "newton_tol",
                              ["1e-%d" % k for k in range(1, 9)],
                              "Newton tolerance newton_tol (RMS |dx|/h, m/s)"),
    "fem_newton_cg": Example("fem_newton_cg", "tests/hard/base.toml", "pcg_tol",
                             ["1e-%d" % k for k in range(1, 11)],
                             "PCG tolerance cg_tol (relative, |r|/|b|)"),
    "springs_newton_cg": Example("springs_newton_cg", "tests/hard/springs_k1e6.toml",
                                 "pcg_tol", ["1e-%d" % k for k in range(1, 11)],
                                 "PCG tolerance cg_tol (relative, |r|/|b|)"),
}
# The Newton examples' sweeps: the scene's tensor each one sets, and their reference (as the
# hard-case suite's, tests/hard/run_suite.py).
NEWTON_PARAMS = {"newton_tol": "newton_tol", "pcg_tol": "cg_tol"}
NEWTON_REFERENCE = {"newton_tol": 1e-9, "newton_max": 200, "cg_tol": 1e-12, "cg_max": 100000}


def require_matplotlib():
    try:
        import matplotlib
    except ImportError:
        hint = ""
        if os.path.realpath(sys.executable) != os.path.realpath("/usr/bin/python3") and \
                os.path.exists("/usr/bin/python3"):
            hint = (" (this is %s; Debian's package serves /usr/bin/python3: run the script "
                    "with it)" % sys.executable)
        sys.exit("accuracy.py: matplotlib is missing%s. Install it with "
                 "`scripts/install_deps.sh --bench` (Debian python3-matplotlib)." % hint)
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


def substitute(text, pattern, replacement, what):
    text, n = re.subn(pattern, replacement, text)
    if n != 1:
        sys.exit("accuracy.py: expected exactly one %s, found %d" % (what, n))
    return text


def make_scene(example, workdir, name, cg_tol=None, cg_max=None, substeps=None, tensors=None):
    """A copy of the example's scene in WORKDIR with absolute paths and the point's settings.

    None leaves a setting as the scene (or program) has it; TENSORS sets [tensors] lines."""
    source = os.path.join(ROOT, example.scene)
    base = os.path.dirname(source)
    text = open(source).read()
    program = None
    if substeps is not None:
        # cloth: h and substeps are constants of the program, so the point runs a copy of it.
        sim = re.search(r'(?m)^program = "([^"]+)"', text).group(1)
        code = open(os.path.join(base, sim)).read()
        code = substitute(code, r"(?m)^const h\s*=\s*[^;]+;", "const h = %r;" %
                          (FRAME_TIME / substeps), "'const h = ...;' in " + sim)
        code = substitute(code, r"(?m)^const substeps\s*=\s*[^;]+;",
                          "const substeps = %d;" % substeps, "'const substeps = ...;' in " + sim)
        program = os.path.join(workdir, name + ".sim")
        with open(program, "w") as f:
            f.write(code)

    def absolute(m):
        if m.group(1) == "program" and program:
            return 'program = "%s"' % program
        return '%s = "%s"' % (m.group(1), os.path.normpath(os.path.join(base, m.group(2))))
    text = re.sub(r'(?m)^(program|mesh) = "([^"]+)"', absolute, text)
    if cg_tol is not None:
        text = substitute(text, r"(?m)^cg_tol = \S+", "cg_tol = %r" % cg_tol,
                          "'cg_tol = ' line in " + example.scene)
    if cg_max is not None:
        text = substitute(text, r"(?m)^cg_max = \S+", "cg_max = %d" % cg_max,
                          "'cg_max = ' line in " + example.scene)
    for key, value in (tensors or {}).items():
        text = substitute(text, r"(?m)^%s = \S+" % key, "%s = %r" % (key, value),
                          "'%s = ' line in %s" % (key, example.scene))
    path = os.path.join(workdir, name + ".toml")
    with open(path, "w") as f:
        f.write(text)
    return path


def shipped_settings(example):
    """The scene's own cg_tol and cg_max (fem, springs) or the program's h (cloth)."""
    text = open(os.path.join(ROOT, example.scene)).read()
    if example.param in NEWTON_PARAMS:
        key = NEWTON_PARAMS[example.param]
        return {"value": float(re.search(r"(?m)^%s = (\S+)" % key, text).group(1)),
                "cg_max": None}
    if example.param == "cg_tol":
        tol = float(re.search(r"(?m)^cg_tol = (\S+)", text).group(1))
        cap = int(re.search(r"(?m)^cg_max = (\S+)", text).group(1))
        return {"value": tol, "cg_max": cap}
    sim = re.search(r'(?m)^program = "([^"]+)"', text).group(1)
    code = open(os.path.join(os.path.dirname(os.path.join(ROOT, example.scene)), sim)).read()
    h = float(re.search(r"(?m)^const h\s*=\s*([^;%]+);", code).group(1))
    return {"value": h, "cg_max": None}


def read_positions(path):
    with open(path) as f:
        rows = list(csv.reader(f))
    return [tuple(float(v) for v in r) for r in rows[1:] if r]


def run(simit, executor, scene, frames, outdir, float32):
    """Runs the scene; returns (per-frame rows, final positions, CPU s) or None if it failed."""
    shutil.rmtree(outdir, ignore_errors=True)
    final = outdir + "-final.csv"
    if os.path.exists(final):
        os.remove(final)
    flags = ([executor_flag(simit), executor, "--jit-threshold", "0"]
             if executor in COMPILING else [])
    argv = [simit, "run"] + flags + (["--float32"] if float32 else []) + [
        "--frames", str(frames), "--output", outdir, "--final-csv", final, scene]
    with open(outdir + ".log", "w") as log:
        child = subprocess.Popen(argv, stdout=log, stderr=subprocess.STDOUT, cwd=ROOT)
        _, status, usage = os.wait4(child.pid, 0)
    if os.waitstatus_to_exitcode(status) != 0:
        with open(outdir + ".log") as log:
            tail = log.read().strip().splitlines()[-1:]
        print("  failed: %s: %s" % (" ".join(argv), tail[0] if tail else "(no output)"))
        return None
    stats = [f for f in os.listdir(outdir) if f.endswith(".csv")]
    with open(os.path.join(outdir, stats[0])) as f:
        rows = list(csv.DictReader(f))
    return rows, read_positions(final), usage.ru_utime + usage.ru_stime


def errors(x, ref, x0):
    scale = max(math.sqrt(sum(c * c for c in p)) for p in ref)
    motion = max(math.dist(p, q) for p, q in zip(ref, x0))
    d = [math.dist(p, q) for p, q in zip(x, ref)]
    if not all(math.isfinite(e) for e in d):
        return float("nan"), float("nan"), float("nan")
    worst = max(d)
    rms = math.sqrt(sum(e * e for e in d) / len(d))
    return worst / scale, rms / scale, worst / motion if motion > 0 else float("nan")


def reference(simit, executor, example, args, workdir):
    """The float64 reference positions, converged in the example's sweep parameter."""
    if example.param == "h":
        scene = make_scene(example, workdir, "reference", substeps=args.ref_substeps)
        got = run(simit, executor, scene, args.frames, os.path.join(workdir, "reference"), False)
        if got is None:
            sys.exit("accuracy.py: the cloth reference failed")
        print("reference: %d substeps, h = %g" % (args.ref_substeps,
                                                  FRAME_TIME / args.ref_substeps), flush=True)
        return got[1], "h = %g (%d substeps)" % (FRAME_TIME / args.ref_substeps,
                                                  args.ref_substeps)
    if example.param in NEWTON_PARAMS:
        scene = make_scene(example, workdir, "reference", tensors=NEWTON_REFERENCE)
        got = run(simit, executor, scene, args.frames, os.path.join(workdir, "reference"), False)
        if got is None:
            sys.exit("accuracy.py: the %s reference failed" % example.name)
        rows, ref, _ = got
        its = [int(r["newton_iterations"]) for r in rows]
        worst = max(float(r["cg_residual"]) for r in rows)
        print("reference: Newton iterations %s, last |r|/|b| at most %.1e" % (its, worst),
              flush=True)
        if max(its) >= NEWTON_REFERENCE["newton_max"] or worst > 1e-12:
            sys.exit("accuracy.py: the %s reference did not converge" % example.name)
        return ref, ("newton_tol = %g, cg_tol = %g (relative), at most %d Newton iterations "
                     "a frame" % (NEWTON_REFERENCE["newton_tol"], NEWTON_REFERENCE["cg_tol"],
                                  max(its)))
    ref_tol = args.ref_tol
    for attempt in range(4):
        scene = make_scene(example, workdir, "reference", cg_tol=ref_tol, cg_max=20000)
        got = run(simit, executor, scene, args.frames, os.path.join(workdir, "reference"), False)
        if got is None:
            sys.exit("accuracy.py: the %s reference failed" % example.name)
        rows, ref, _ = got
        worst = max(float(r["cg_residual"]) for r in rows)
        iters = [int(r["cg_iterations"]) for r in rows]
        print("reference: cg_tol %g, CG iterations %s, max |r|/|b| %.2e"
              % (ref_tol, iters, worst), flush=True)
        if worst <= 1e-14:
            return ref, "cg_tol = %g, |r|/|b| <= %.1e in every frame" % (ref_tol, worst)
        ref_tol *= (1e-14 / worst) ** 2 / 4
    sys.exit("accuracy.py: the %s reference did not converge to |r|/|b| <= 1e-14" % example.name)


def measure(simit, executor, example, args, workdir, x0, ref, setup_cpu, prec, value,
            setting):
    """One point: runs the scene as SETTING says and compares with the reference."""
    if example.param == "h":
        scene = make_scene(example, workdir, "point", substeps=setting)
    elif example.param in NEWTON_PARAMS:
        scene = make_scene(example, workdir, "point",
                           tensors={NEWTON_PARAMS[example.param]: value})
    else:
        scene = make_scene(example, workdir, "point", cg_tol=value, cg_max=setting)
    # --repeat N: the least of N medians per timing column (load only ever adds time); the
    # results are deterministic, so the positions of any run will do.
    got, timings = None, []
    for _ in range(args.repeat):
        got = run(simit, executor, scene, args.frames, os.path.join(workdir, "point"),
                  prec == "float32")
        if got is None:
            break
        timings.append(got)
    point = {"example": example.name, "executor": executor, "precision": prec,
             "param": example.param, "value": value,
             "cg_max": setting if example.param == "cg_tol" else "",
             "substeps": setting if example.param == "h" else ""}
    if got is None:
        point.update(status="failed")
        return point
    rows, x, _ = got
    # The JIT and the GPU executor compile in frame 1 (--jit-threshold 0): their medians
    # leave that frame out.
    def skip(frames):
        return frames[1:] if executor in COMPILING and len(frames) > 1 else frames
    worst, rms, of_motion = errors(x, ref, x0)

    def least(column):
        return min(statistics.median(float(r[column]) for r in skip(rs)) for rs, _, _ in timings)
    point.update({
        "status": "ok" if math.isfinite(worst) else "nonfinite",
        "ms_per_frame": least("ms"), "assembly_ms": least("assembly_ms"),
        "solve_ms": least("solve_ms"),
        "max_rel_error": worst, "rms_rel_error": rms, "max_error_of_motion": of_motion,
        "cpu_ms_per_frame": 1e3 * max(0.0, min(c for _, _, c in timings) - setup_cpu) /
        args.frames})
    if "newton_iterations" in rows[0]:
        # Means: Newton's iterations and halvings vary from frame to frame.
        newton = [int(r["newton_iterations"]) for r in rows]
        point.update({"newton_iterations": statistics.mean(newton),
                      "halvings": statistics.mean(int(r["halvings"]) for r in rows),
                      "cg_iterations": statistics.mean(int(r["cg_iterations"]) for r in rows),
                      "capped": sum(1 for i in newton if i >= newton_max(example)),
                      "rel_residual": float(rows[-1]["cg_residual"])})
    elif "cg_iterations" in rows[0]:
        its = [int(r["cg_iterations"]) for r in rows]
        point.update({"cg_iterations": statistics.median(its),
                      "capped": sum(1 for i in its if i >= setting),
                      "rel_residual": float(rows[-1]["cg_residual"])})
    return point


def newton_max(example):
    text = open(os.path.join(ROOT, example.scene)).read()
    return int(re.search(r"(?m)^newton_max = (\S+)", text).group(1))


FIELDS = ["example", "executor", "precision", "param", "value", "cg_max", "substeps", "shipped",
          "status", "ms_per_frame", "assembly_ms", "solve_ms", "newton_iterations", "halvings",
          "cg_iterations", "capped",
          "rel_residual", "max_rel_error", "rms_rel_error", "max_error_of_motion",
          "cpu_ms_per_frame"]


def sweep(simit, executor, ref_executor, example, args, out):
    workdir = tempfile.mkdtemp(prefix="simit-accuracy-")
    try:
        scene = make_scene(example, workdir, "rest")
        got = run(simit, executor, scene, 0, os.path.join(workdir, "rest"), False)
        if got is None:
            sys.exit("accuracy.py: %s did not run" % example.scene)
        _, x0, setup_cpu = got
        ref, how = reference(simit, ref_executor, example, args, workdir)
        shipped = shipped_settings(example)
        points = [(p, float(v)) for v in (args.points or example.default_points)
                  for p in args.precisions]
        results = []
        # The shipped setting first, then the sweep; the precisions alternate at each value so
        # that a change in the machine's load hits both alike.
        runs = [("float64", None, True)] + [(p, v, False) for p, v in points]
        for prec, v, is_shipped in runs:
            if example.param == "h":
                setting = (int(round(FRAME_TIME / shipped["value"])) if is_shipped
                           else int(v))
                value = FRAME_TIME / setting
            else:
                value = shipped["value"] if is_shipped else v
                setting = shipped["cg_max"] if is_shipped else args.cg_max
            point = measure(simit, executor, example, args, workdir, x0, ref, setup_cpu, prec,
                            value, setting)
            point["shipped"] = "yes" if is_shipped else ""
            results.append(point)
            print(describe(point), flush=True)
    finally:
        shutil.rmtree(workdir, ignore_errors=True)
    path = os.path.join(out, "accuracy_%s_%s.csv" % (example.name, executor))
    with open(path, "w", newline="") as f:
        f.write("# reference: float64, %s, %s executor, %d frames\n" % (how, ref_executor,
                                                                      args.frames))
        w = csv.DictWriter(f, fieldnames=FIELDS)
        w.writeheader()
        for r in results:
            w.writerow({k: ("%.6g" % v if isinstance(v, float) else v) for k, v in r.items()})
    print("wrote %s" % path)


def describe(p):
    head = "%s %s %s %s %-8g%s" % (p["example"], p["executor"], p["precision"], p["param"],
                                  p["value"], " (shipped)" if p.get("shipped") else "")
    if p["status"] == "failed":
        return head + ": failed (the run stopped: a NaN, for cloth an unstable step)"
    text = "%s: %8.2f ms/frame (assembly %.2f, solve %.2f)" % (
        head, p["ms_per_frame"], p["assembly_ms"], p["solve_ms"])
    if "newton_iterations" in p:
        text += ", Newton %.1f it/frame (%.1f halvings)" % (p["newton_iterations"],
                                                            p["halvings"])
    if "cg_iterations" in p:
        text += ", CG %g it%s, |r|/|b| %.1e" % (
            p["cg_iterations"], " (%d frames capped)" % p["capped"] if p["capped"] else "",
            p["rel_residual"])
    return text + ", max rel error %.2e, rms %.2e" % (p["max_rel_error"], p["rms_rel_error"])


EXECUTORS = ("interpreter", "jit", "gpu")


def csv_paths(out, name):
    """The example's CSVs in OUT, one per executor (accuracy_fem_*.csv would also match
    accuracy_fem_newton_*.csv)."""
    paths = [os.path.join(out, "accuracy_%s_%s.csv" % (name, e)) for e in EXECUTORS]
    return [p for p in paths if os.path.exists(p)]


def load(out, name):
    rows = []
    for path in csv_paths(out, name):
        with open(path) as f:
            rows += list(csv.DictReader(line for line in f if not line.startswith("#")))
    return rows


def frames_of(out, name):
    """The frame counts the example's CSVs say their runs had (the comment on line 1)."""
    counts = set()
    for path in csv_paths(out, name):
        with open(path) as f:
            m = re.search(r"(\d+) frames", f.readline())
        if m:
            counts.add(int(m.group(1)))
    return "/".join(str(c) for c in sorted(counts)) or "?"


def plot(plt, out, example):
    """accuracy_EXAMPLE.png: error against ms/frame (left) and the sweep parameter (right)."""
    rows = [r for r in load(out, example.name) if r["status"] == "ok"]
    if not rows:
        print("no results for %s in %s: no plot" % (example.name, out))
        return
    floor = 1e-17  # an exact match has no place on a log axis
    newton = example.param in NEWTON_PARAMS
    # The Newton examples add a third panel: Newton iterations per frame against the parameter.
    fig, axes = plt.subplots(1, 3 if newton else 2, figsize=(19 if newton else 13, 5.2))
    styles = {("jit", "float64"): ("C0", "o"), ("jit", "float32"): ("C1", "s"),
              ("interpreter", "float64"): ("C2", "^"), ("interpreter", "float32"): ("C3", "v"),
              ("gpu", "float64"): ("C4", "D"), ("gpu", "float32"): ("C5", "P")}
    for (executor, prec), (color, marker) in styles.items():
        series = sorted((r for r in rows if r["executor"] == executor and
                         r["precision"] == prec and not r["shipped"]),
                        key=lambda r: float(r["value"]))
        if not series:
            continue
        err = [max(float(r["max_rel_error"]), floor) for r in series]
        label = "%s, %s" % (executor, prec)
        # Joined in the order of the parameter: timing noise can fold the line back.
        axes[0].plot([float(r["ms_per_frame"]) for r in series], err, marker=marker,
                     color=color, linewidth=0.8, alpha=0.8, label=label)
        axes[1].plot([float(r["value"]) for r in series], err, marker=marker, color=color,
                     label=label)
        if newton:
            axes[2].plot([float(r["value"]) for r in series],
                         [float(r["newton_iterations"]) for r in series], marker=marker,
                         color=color, label=label)
    labelled = False
    for r in rows:
        if r["shipped"]:
            err = max(float(r["max_rel_error"]), floor)
            if example.param == "cg_tol":
                what = "cg_tol %g, cg_max %s" % (float(r["value"]), r["cg_max"])
            elif newton:
                what = "%s %g" % (NEWTON_PARAMS[example.param], float(r["value"]))
            else:
                what = "h %g" % float(r["value"])
            marks = [(axes[0], float(r["ms_per_frame"]), err), (axes[1], float(r["value"]), err)]
            if newton:
                marks.append((axes[2], float(r["value"]), float(r["newton_iterations"])))
            for ax, x, y in marks:
                ax.plot([x], [y], marker="*", markersize=15, color="k", linestyle="none",
                        label=None if labelled else "as shipped: %s, float64" % what)
            labelled = True
    unstable = sorted({float(r["value"]) for r in load(out, example.name)
                       if r["status"] != "ok"})
    if unstable and example.param == "h":  # the smallest failed value: where the explicit step stops being stable
        axes[1].axvline(unstable[0], color="grey", linestyle=":", linewidth=1)
        axes[1].text(unstable[0], axes[1].get_ylim()[1],
                     "unstable from h = %.3g " % unstable[0], color="grey", va="top",
                     ha="right", fontsize=8)
    ylabel = "max |x - x_ref| / max |x_ref|"
    axes[0].set(xscale="log", yscale="log", xlabel="ms/frame (median)", ylabel=ylabel,
                title="%s: error against time" % example.name)
    axes[1].set(xscale="log", yscale="log", xlabel=example.label, ylabel=ylabel,
                title="%s: error against %s" % (example.name,
                                                 NEWTON_PARAMS.get(example.param, example.param)))
    if newton:
        axes[2].set(xscale="log", xlabel=example.label, ylabel="Newton iterations per frame",
                    title="%s: Newton iterations against %s" %
                    (example.name, NEWTON_PARAMS[example.param]))
        axes[2].invert_xaxis()
    if example.param == "cg_tol" or newton:
        axes[1].invert_xaxis()  # tighter tolerances to the right, like longer times on the left
    for ax in axes:
        ax.grid(True, which="both", alpha=0.3)
    axes[1].legend(fontsize=8, loc="best")  # one legend serves both panels
    fig.suptitle("%s (%s), %s frames; reference float64 converged" %
                 (example.name, os.path.basename(example.scene), frames_of(out, example.name)))
    fig.tight_layout()
    path = os.path.join(out, "accuracy_%s.png" % example.name)
    fig.savefig(path, dpi=100)
    plt.close(fig)
    print("wrote %s" % path)



def table_head(head):
    """A markdown table's header and alignment rows (the first column left, numbers right)."""
    return ["| " + " | ".join(head) + " |",
            "|" + "|".join("---" if i == 0 else "---:" for i in range(len(head))) + "|"]


def table_settings(rows):
    """The (executor, shipped, value) settings of the rows: the JIT first, then the GPU
    executor, then the interpreter; the shipped setting first within each, then by
    decreasing value."""
    settings = []
    for r in rows:
        key = (r["executor"], bool(r["shipped"]), float(r["value"]))
        if key not in settings:
            settings.append(key)
    order = {"jit": 0, "gpu": 1, "interpreter": 2}
    settings.sort(key=lambda k: (order.get(k[0], 2), not k[1], -k[2]))
    return settings

def table(out, example):
    """The example's results as markdown (--table): per executor, a row per setting, the
    shipped one first, and for each precision ms/frame and the max relative error."""
    if example.param in NEWTON_PARAMS:
        return newton_table(out, example)
    rows = load(out, example.name)
    cg = example.param == "cg_tol"
    head = ["executor", example.param, "cg_max" if cg else "substeps"] + \
        (["CG it/frame", "rel. resid."] if cg else []) + \
        ["float64 ms/frame", "float64 error", "float32 ms/frame", "float32 error"]
    lines = table_head(head)
    settings = table_settings(rows)
    for executor, shipped, value in settings:
        by_prec = {r["precision"]: r for r in rows if r["executor"] == executor and
                   bool(r["shipped"]) == shipped and float(r["value"]) == value}
        first = by_prec.get("float64") or by_prec.get("float32")
        cells = [executor, ("**%.3g (shipped)**" if shipped else "%.3g") % value,
                 first["cg_max"] if cg else first["substeps"]]
        if cg:
            ok = first["status"] == "ok"
            capped = " (capped)" if ok and first["capped"] not in ("", "0") else ""
            cells += ["%g%s" % (float(first["cg_iterations"]), capped) if ok else "-",
                      "%.1e" % float(first["rel_residual"]) if ok else "-"]
        for prec in PRECISIONS:
            r = by_prec.get(prec)
            if r is None:
                cells += ["", ""]
            elif r["status"] != "ok":
                cells += ["failed", "-"]
            else:
                ms = float(r["ms_per_frame"])
                cells += ["%.3g" % ms if ms < 1000 else "%.0f" % ms,
                          "%.2e" % float(r["max_rel_error"])]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def newton_table(out, example):
    """--table for the Newton examples: per executor a row per setting, the shipped one
    first; per precision ms/frame, Newton iterations and halvings per frame, the CG
    iterations per frame (summed over Newton's) and the error, as a fraction of the object's
    size and of the reference's motion."""
    rows = load(out, example.name)
    head = ["executor", NEWTON_PARAMS[example.param]]
    for prec in PRECISIONS:
        head += ["%s %s" % (prec, c) for c in ("ms/frame", "Newton it/frame", "halvings/frame",
                                                "CG it/frame", "error", "error of motion")]
    lines = table_head(head)
    settings = table_settings(rows)
    for executor, shipped, value in settings:
        cells = [executor, ("**%.3g (shipped)**" if shipped else "%.3g") % value]
        for prec in PRECISIONS:
            r = [r for r in rows if r["executor"] == executor and r["precision"] == prec and
                 bool(r["shipped"]) == shipped and float(r["value"]) == value]
            if not r:
                cells += [""] * 6
            elif r[0]["status"] != "ok":
                cells += ["failed"] + ["-"] * 5
            else:
                r = r[0]
                ms = float(r["ms_per_frame"])
                capped = " (capped %s)" % r["capped"] if r["capped"] not in ("", "0") else ""
                cells += ["%.3g" % ms if ms < 1000 else "%.0f" % ms,
                          "%.1f%s" % (float(r["newton_iterations"]), capped),
                          "%.1f" % float(r["halvings"]), "%.0f" % float(r["cg_iterations"]),
                          "%.2e" % float(r["max_rel_error"]),
                          "%.2e" % float(r["max_error_of_motion"])]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--build", default=os.path.join(ROOT, "build"),
                   help="the build folder with tools/simit; default build")
    p.add_argument("--example", default="fem,springs,cloth",
                   help="examples, comma-separated (default fem,springs,cloth; also "
                        "fem_newton, springs_newton, fem_newton_cg, springs_newton_cg)")
    p.add_argument("--executor", default=None,
                   help="interpreter, jit, gpu, comma-separated (default: jit if built)")
    p.add_argument("--frames", type=int, default=10, help="frames per run, K (default 10)")
    p.add_argument("--points", default=None,
                   help="the sweep: CG tolerances (fem, springs, *_newton_cg), Newton "
                        "tolerances (*_newton) or substeps per frame (cloth), comma-separated; "
                        "default per example")
    p.add_argument("--precisions", default="float64,float32")
    p.add_argument("--repeat", type=int, default=1,
                   help="runs per point; each timing is the least of their medians (default 1)")
    p.add_argument("--cg-max", type=int, default=1000,
                   help="CG iteration cap of the sweep (default 1000)")
    p.add_argument("--ref-tol", type=float, default=1e-30,
                   help="cg_tol of the reference (default 1e-30; tightened when needed)")
    p.add_argument("--ref-substeps", type=int, default=1600,
                   help="substeps per frame of the cloth reference (default 1600)")
    p.add_argument("--out", default="bench-accuracy", help="output folder (default bench-accuracy)")
    p.add_argument("--plot-only", action="store_true", help="redraw the figures from the CSVs")
    p.add_argument("--no-plot", action="store_true",
                   help="draw no figures (matplotlib is then not needed)")
    p.add_argument("--table", action="store_true",
                   help="also print each example's results as a markdown table")
    args = p.parse_args()
    if args.plot_only and args.no_plot:
        p.error("--plot-only and --no-plot contradict each other")
    plt = None if args.no_plot else require_matplotlib()
    names = [n.strip() for n in args.example.split(",") if n.strip()]
    for n in names:
        if n not in EXAMPLES:
            sys.exit("accuracy.py: unknown example %s (expected %s)" % (n, ", ".join(EXAMPLES)))
    examples = [EXAMPLES[n] for n in names]
    args.points = [v.strip() for v in args.points.split(",")] if args.points else None
    args.precisions = [v.strip() for v in args.precisions.split(",") if v.strip()]
    if any(v not in PRECISIONS for v in args.precisions):
        sys.exit("accuracy.py: --precisions takes float64 and/or float32")
    os.makedirs(args.out, exist_ok=True)
    started = time.monotonic()
    if not args.plot_only:
        simit = os.path.join(os.path.abspath(args.build), "tools", "simit")
        if not os.access(simit, os.X_OK):
            sys.exit("accuracy.py: missing %s (build the target simit)" % simit)
        has_jit = jit_available(simit)
        executors = ([e.strip() for e in args.executor.split(",") if e.strip()]
                     if args.executor else ["jit" if has_jit else "interpreter"])
        for e in executors:
            if e not in EXECUTORS:
                sys.exit("accuracy.py: unknown executor %s (expected %s)"
                         % (e, ", ".join(EXECUTORS)))
            if e == "jit" and not has_jit:
                sys.exit("accuracy.py: this simit has no JIT (configure with "
                         "-DSIMIT_WITH_LLVM=ON)")
            if e == "gpu" and executor_unavailable(simit, "gpu"):
                sys.exit("accuracy.py: the GPU executor cannot run: %s"
                         % executor_unavailable(simit, "gpu"))
        ref_executor = "jit" if has_jit else "interpreter"
        for example in examples:
            for executor in executors:
                sweep(simit, executor, ref_executor, example, args, args.out)
    for example in examples:
        if plt:
            plot(plt, args.out, example)
        if args.table:
            print(table(args.out, example))
    print("total %.0f s" % (time.monotonic() - started))


if __name__ == "__main__":
    main()
