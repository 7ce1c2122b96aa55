#!/usr/bin/env python3
"""Runs the hard-case suite (tests/hard/*.toml) and writes its table.

Usage: tests/hard/run_suite.py [--simit PATH] [--frames K] [--cases LIST] [--work DIR]
                               [--table FILE] [--check]

Every case is run with each model and integrator of its program (fem_newton.sim: classic or
Stable Neo-Hookean, linearised step or Newton; springs_newton.sim: linearised step or
Newton; cloth_rest.sim: its one model and explicit integrator), in float64, and the cases
marked float32 also with `simit run --float32`. Every run uses --check-finite, so that a NaN
or an infinity stops it at the operation that made it, naming the line and the element
(never a silent NaN). The error of each run is that of its final positions against a
reference: for the implicit programs the same model with Newton converged in float64
(newton_tol 1e-9 m/s, PCG to a relative residual of 1e-12), for the explicit cloth the same
run in float64 with a step 16 times smaller (EXPLICIT_REFINEMENT):
    error = max over vertices |x - x_ref| / max over vertices |x_ref - x_start|,
the error relative to the largest displacement of the reference over the run.

--table writes the markdown table (case, model, integrator, precision, outcome, error,
Newton and CG iterations per frame, ms per frame) into FILE between the markers
<!-- table --> and <!-- end table -->. --check asserts the suite's claims and exits 1 when
one fails: the asserted runs (Stable Neo-Hookean or springs with Newton, and the explicit
runs of the cases that state a tolerance) finish finite within their tolerance
(ERROR_TOL[precision], or the case's own) of the reference; every other run either finishes
with finite positions or stops with a diagnosis naming file, line and element, or, for a CG
breakdown (p'Ap <= 0, raised by the PCG's `error` statement, which no element causes), file,
line and function.
"""
import argparse
import csv
import math
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))

# case: scene, what it tests, whether float32 runs too, and for an explicit program (no
# integrator to choose) its stated tolerance, or None where the run is not asserted.
CASES = [
    ("base", "base.toml", "fem.sim's set-up on a 240-tet bar", True, None),
    ("inverted", "inverted.toml", "upper half mirrored: 108 tets start inverted", False, None),
    ("nu049", "nu049.toml", "nu = 0.49", False, None),
    ("nu0499", "nu0499.toml", "nu = 0.499", False, None),
    ("dt10", "dt10.toml", "h = 0.05, ten times fem.sim's", True, None),
    ("sliver", "sliver.toml", "24 sliver tets (1e-4 m thick, 1e-2 m wide)", False, None),
    ("springs_k1e6", "springs_k1e6.toml", "springs, k = 1e6 N/m, swinging about one corner",
     True, None),
    # Velocity Verlet's O(h^2) error, not a solver's tolerance: 1e-2 of the motion.
    ("cloth_pinch", "cloth_pinch.toml", "cloth, edges driven together to 1/10 of its width",
     True, {"float64": 1e-2, "float32": 1e-2}),
    # StVK below a stretch of 1/sqrt(3): no converged reference to hold it to (see README).
    ("cloth_squeezed", "cloth_squeezed.toml", "cloth held at 1/4 of its rest width", False,
     None),
    ("cloth_squeezed_corners", "cloth_squeezed_corners.toml",
     "cloth at 1/4 of its rest width, held by two corners", False, None),
]
# Stated tolerances of the robust runs (error relative to the reference's displacement).
ERROR_TOL = {"float64": 1e-3, "float32": 1e-2}
REFERENCE = {"newton_tol": 1e-9, "newton_max": 200, "cg_tol": 1e-12, "cg_max": 100000}
EXPLICIT_REFINEMENT = 16  # the explicit reference's step is the scene's h over this
MODELS = {0: "classic NH", 1: "stable NH"}
INTEGRATORS = {0: "linearised", 1: "Newton"}


def make_scene(source, tensors, workdir, name):
    """A copy of SOURCE with absolute program and mesh paths and [tensors] values replaced."""
    base = os.path.dirname(os.path.abspath(source))
    text = open(source).read()

    def absolute(m):
        return '%s = "%s"' % (m.group(1), os.path.normpath(os.path.join(base, m.group(2))))

    text = re.sub(r'(?m)^(program|mesh) = "([^"]+)"', absolute, text)
    for key, value in tensors.items():
        text, n = re.subn(r"(?m)^%s = \S+" % key, "%s = %r" % (key, value), text)
        if n != 1:
            sys.exit("%s: expected one '%s = ' line" % (source, key))
    path = os.path.join(workdir, name + ".toml")
    with open(path, "w") as f:
        f.write(text)
    return path


def read_positions(path):
    with open(path) as f:
        rows = list(csv.reader(f))
    return [tuple(float(v) for v in r) for r in rows[1:] if r]


def has_key(source, key):
    return re.search(r"(?m)^%s = " % key, open(source).read()) is not None


def tensor_value(source, key):
    return float(re.search(r"(?m)^%s = (\S+)" % key, open(source).read()).group(1))


class Run:
    """One run of a scene: its outcome, per-frame statistics and final positions."""

    def __init__(self, simit, scene, frames, outdir, float32):
        shutil.rmtree(outdir, ignore_errors=True)
        final = outdir + "-final.csv"
        if os.path.exists(final):
            os.remove(final)
        argv = [simit, "run", "--check-finite"] + (["--float32"] if float32 else []) + [
            "--frames", str(frames), "--output", outdir, "--final-csv", final, scene]
        start = time.monotonic()
        proc = subprocess.run(argv, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        self.wall = time.monotonic() - start
        self.log = proc.stdout
        self.status = proc.returncode
        self.rows = []
        self.stats = False
        if os.path.isdir(outdir):
            stats = [f for f in os.listdir(outdir) if f.endswith(".csv")]
            if stats:
                self.stats = True
                with open(os.path.join(outdir, stats[0])) as f:
                    self.rows = list(csv.DictReader(f))
        self.x = read_positions(final) if self.status == 0 and os.path.exists(final) else None
        self.diagnosis = None
        if self.status != 0:
            # file:line:col: runtime error: message, then the frames; keep the message and the
            # innermost frame that names an element, or else the innermost frame.
            m = re.search(r"(\S+):(\d+):\d+: runtime error: (.*)", self.log)
            where = re.search(r"in (\w+) \([^)]*\), mapping over (element \d+ of set '\w+')", self.log)
            inner = re.search(r"^  in (\w+) \(", self.log, re.M)
            if m:
                self.diagnosis = "%s at %s:%s%s" % (
                    m.group(3), os.path.basename(m.group(1)), m.group(2),
                    " in %s, %s" % (where.group(1), where.group(2)) if where else
                    " in %s" % inner.group(1) if inner else "")
            else:
                self.diagnosis = "exit %d: %s" % (self.status, self.log.strip()[-200:])

    def total(self, key):
        return sum(float(r[key]) for r in self.rows if key in r)

    def per_frame(self, key):
        """The mean per frame; NaN (n/a) where the program does not report KEY (cloth)."""
        if not self.rows or key not in self.rows[0]:
            return float("nan")
        return self.total(key) / len(self.rows)

    def finite(self):
        return self.x is not None and all(math.isfinite(c) for p in self.x for c in p)

    def outcome(self):
        if self.diagnosis:
            # The statistics CSV holds the frames finished before the one that stopped.
            frame = " in frame %d" % (len(self.rows) + 1) if self.stats else ""
            return "stopped%s: %s" % (frame, self.diagnosis)
        if not self.finite():
            return "NOT FINITE"
        halvings = self.total("halvings")
        return "finite" + ("; %d line-search halvings" % halvings if halvings else "")


def error(x, ref, start):
    motion = max(math.dist(p, q) for p, q in zip(ref, start))
    worst = max(math.dist(p, q) for p, q in zip(x, ref))
    return worst / motion if motion > 0 else float("nan")


def reference_settings(source):
    """[tensors] of the float64 reference: Newton converged, or an explicit step refined."""
    if has_key(source, "integrator"):
        return dict(REFERENCE, integrator=1)
    return {"h": tensor_value(source, "h") / EXPLICIT_REFINEMENT,
            "substeps": int(tensor_value(source, "substeps")) * EXPLICIT_REFINEMENT}


def run_case(simit, name, scene, float32_too, explicit_tol, frames, work):
    source = os.path.join(HERE, scene)
    models = [0, 1] if has_key(source, "model") else [None]
    # None: an explicit program, which has no integrator to choose.
    integrators = [0, 1] if has_key(source, "integrator") else [None]
    results = []
    start = Run(simit, make_scene(source, {}, work, name + "-start"), 0,
                os.path.join(work, name + "-start"), False)
    for model in models:
        fix = {} if model is None else {"model": model}
        ref_scene = make_scene(source, dict(fix, **reference_settings(source)), work,
                               "%s-m%s-ref" % (name, model))
        ref = Run(simit, ref_scene, frames, os.path.join(work, "%s-m%s-ref" % (name, model)),
                  False)
        for integrator in integrators:
            precisions = ["float64", "float32"] if float32_too and integrator != 0 else ["float64"]
            for prec in precisions:
                tag = "%s-m%s-i%s-%s" % (name, model, integrator, prec)
                sc = make_scene(source, fix if integrator is None else
                                dict(fix, integrator=integrator), work, tag)
                r = Run(simit, sc, frames, os.path.join(work, tag), prec == "float32")
                err = float("nan")
                if r.finite() and ref.finite() and start.x:
                    err = error(r.x, ref.x, start.x)
                if integrator is None:
                    tol = explicit_tol
                elif model != 0 and integrator == 1:
                    tol = ERROR_TOL
                else:
                    tol = None
                results.append({
                    "case": name, "model": model_label(source, model),
                    "integrator": "explicit" if integrator is None else INTEGRATORS[integrator],
                    "precision": prec, "run": r, "reference": ref, "error": err,
                    "tolerance": tol and tol[prec]})
    return results


def model_label(source, model):
    if model is not None:
        return MODELS[model]
    return "StVK cloth" if "cloth" in os.path.basename(source) else "springs"


def fmt(v, spec):
    return "n/a" if v is None or (isinstance(v, float) and math.isnan(v)) else spec % v


def table(results, frames):
    lines = ["| case | model | integrator | precision | outcome | error vs reference | "
             "Newton its/frame | CG its/frame | ms/frame |",
             "|---|---|---|---|---|---|---|---|---|"]
    for r in results:
        run = r["run"]
        ref_note = "" if r["reference"].finite() else " (reference stopped)"
        lines.append("| %s | %s | %s | %s | %s | %s%s | %s | %s | %s |" % (
            r["case"], r["model"], r["integrator"], r["precision"], run.outcome(),
            fmt(r["error"], "%.1e"), ref_note, fmt(run.per_frame("newton_iterations"), "%.1f"),
            fmt(run.per_frame("cg_iterations"), "%.0f"), fmt(run.per_frame("ms"), "%.0f")))
    return "\n".join(lines) + "\n\n%d frames per run.\n" % frames


def check(results):
    failures = []
    for r in results:
        run, label = r["run"], "%s %s %s %s" % (r["case"], r["model"], r["integrator"],
                                                r["precision"])
        if r["tolerance"] is not None:
            if not r["reference"].finite():
                failures.append("%s: the reference did not finish finite: %s" %
                                (label, r["reference"].outcome()))
            if not run.finite():
                failures.append("%s: %s" % (label, run.outcome()))
            elif not r["error"] <= r["tolerance"]:
                failures.append("%s: error %.2e above %g" % (label, r["error"], r["tolerance"]))
        elif run.diagnosis:
            if not (re.search(r"\.sim:\d+ in \w+, element \d+ of set", run.diagnosis) or
                    re.match(r"CG breakdown: .* at \w+\.sim:\d+ in \w+$", run.diagnosis)):
                failures.append("%s: stopped without naming line and element: %s" %
                                (label, run.diagnosis))
        elif not run.finite():
            failures.append("%s: finished with non-finite positions" % label)
    return failures


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--simit", default=os.path.join(ROOT, "build", "tools", "simit"))
    ap.add_argument("--frames", type=int, default=20)
    ap.add_argument("--cases", default=",".join(c[0] for c in CASES))
    ap.add_argument("--work", default=None, help="folder for the runs (default: a temporary one)")
    ap.add_argument("--table", default=None)
    ap.add_argument("--check", action="store_true")
    args = ap.parse_args()
    wanted = args.cases.split(",")
    unknown = set(wanted) - {c[0] for c in CASES}
    if unknown:
        sys.exit("unknown cases: %s" % ", ".join(sorted(unknown)))
    work = args.work or tempfile.mkdtemp(prefix="simit-hard-")
    os.makedirs(work, exist_ok=True)
    results = []
    for name, scene, what, f32, explicit_tol in CASES:
        if name in wanted:
            print("%s: %s" % (name, what), flush=True)
            rs = run_case(args.simit, name, scene, f32, explicit_tol, args.frames, work)
            for r in rs:
                run = r["run"]
                print("  %-10s %-10s %-7s %-60s error %s  %s ms/frame" % (
                    r["model"], r["integrator"], r["precision"], run.outcome()[:60],
                    fmt(r["error"], "%.1e"), fmt(run.per_frame("ms"), "%.0f")), flush=True)
            results += rs
    text = table(results, args.frames)
    if args.table:
        doc = open(args.table).read()
        doc, n = re.subn(r"(?s)<!-- table -->.*<!-- end table -->",
                         lambda _: "<!-- table -->\n" + text + "<!-- end table -->", doc)
        if n != 1:
            sys.exit("%s: no <!-- table --> ... <!-- end table --> markers" % args.table)
        with open(args.table, "w") as f:
            f.write(doc)
    if not args.work:
        shutil.rmtree(work, ignore_errors=True)
    if args.check:
        failures = check(results)
        for f in failures:
            print("FAIL: " + f)
        print("%d runs, %d failures" % (len(results), len(failures)))
        return 1 if failures else 0
    return 0


if __name__ == "__main__":
    sys.exit(main())
