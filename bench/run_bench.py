#!/usr/bin/env python3
"""The examples' benchmark table: every executor of `simit` against the Eigen baselines.

Usage: bench/run_bench.py [--build DIR] [--frames N] [--dragon160k] [--cloth 32,64]
                          [--only SUBSTRING]... [--baseline-only SUBSTRING]...
                          [--compare-baseline LABEL=DIR]... [--compare-simit LABEL=DIR]...
                          [--fem-sim-form] [--threads N[,M...]]
                          [--executors interpreter,...] [--out FILE]...

For each example and mesh (fem: bunny, dragon40k and, with --dragon160k, dragon160k;
springs: bunny; cloth: the generated N x N square for each --cloth size) it runs the scene
once per executor (`simit run SCENE`, which writes a per-frame CSV) and the hand-written
baseline (bench/baselines/EXAMPLE_baseline.cpp) once, for the same number of frames, and
prints one row per run. Cloths above 64 points a side diverge at cloth.sim's step (NaN in
the first frame, the baseline's too): they run a copy of cloth.sim with the step shrunk by
(N / 64)^2 (the mesh column says the step), without a baseline, whose step is fixed.

  threads      the threads the run used: --threads N for the baselines and simit's JIT,
               1 for the interpreter (which runs on one thread whatever N);
  ms/frame     median over the frames of the frame's wall time (set-up, reading the mesh,
               `init` and writing output are outside it);
  assembly     median of the time in outermost map/apply assemblies (simit's assembly_ms
               column; the baselines' "assembly", for cloth "forces");
  solve        median of the rest of the frame (simit's solve_ms: everything outside the
               maps, mostly the CG solve; the baselines' "solve", for cloth "integration").
               The two medians need not add up to the ms/frame median;
  CG it/frame  median CG iterations per frame ("-": cloth is explicit, no solve);
  rel. resid.  the last frame's relative residual |r| / |b| at CG exit. fem.sim and
               springs.sim return it as cg_residual (sqrt(r'r / b'b)) and the baselines
               print the same quantity, so no conversion is needed;
  peak MB      the child's peak resident set (ru_maxrss from os.wait4);
  LOC          non-blank, non-comment lines of the .sim program or of the baseline's own
               .cpp (the helpers every baseline shares, baseline_common.{h,cpp}, are counted
               once in the footnote);
  vs baseline  ms/frame divided by the baseline's ms/frame measured in this run;
  rel. err     max |x - x_ref| / max |x_ref| over the final positions, x_ref those of the
               first executor run (the interpreter by default; "-" when none ran);
               "same bits" where the final positions' CSV is byte for byte the reference's.
               With CG stopped by its iteration cap this is mostly rounding amplified by
               unpreconditioned CG; the scene_*_vs_baseline tests compare converged runs.

Executors (--executors, comma-separated, default interpreter,jit): interpreter, jit and gpu
(`simit run --executor gpu`: the compiled maps on an NVIDIA GPU, solver loops on the CPU),
and jit-float32 and gpu-float32, the same under `--float32` (their error column is against
the first executor's float64 positions).
An executor this simit cannot run (no JIT, no GPU: `simit run --executor gpu` says why) is
left out of every case with a note giving the reason. --only SUBSTRING, repeatable, keeps
the cases whose example/mesh contains any of them.

--baseline-only SUBSTRING runs only the baselines on the matching cases (dragon160k takes
about 40 s a frame under the interpreter). --compare-baseline LABEL=DIR adds rows for the
baselines of another build folder (an older version, say); --compare-simit LABEL=DIR runs
the executors of another build's simit beside this one's, case by case (the previous commit,
to show a change costs nothing); --fem-sim-form adds a row for
fem_baseline --sim-form, whose stiffness is evaluated column by column from dP (as fem.sim
wrote it before) rather than in closed form. --baseline-cpu-clock times the baselines' frames in thread CPU time, which the
machine's load inflates far less than wall time (compare baselines with baselines then;
one thread only).

--threads N (default 1) runs both sides on N threads: `simit run --threads N` (the JIT's
maps and solver loops) and `EXAMPLE_baseline --threads N` (the baselines' OpenMP loops:
partitioned element loops, CG by rows). simit gets --threads whenever its `run --help` lists
the option, 1 included, since its own default is every core; a simit that predates the
option runs on one thread and is given nothing (with N above 1 its runs are skipped with a
note). Baselines get --threads only when N is above 1, so that the --compare-baseline builds
that predate it still run at 1 (above 1 those are skipped with a note). The default keeps
the table comparable with one-thread results from before the option.
--threads 1,2 (several counts) runs each case at every count one after the other, in every
repeat, so that the counts see the machine alike, and adds the column "vs 1 thread": a
row's ms/frame over the same runner's at the first count (the interpreter runs at the first
count only).

Simit and the baseline run with the same CG stopping rule (r'r <= cg_tol or cg_max
iterations): the baseline gets the scene's [tensors] cg_tol and cg_max through --cg-tol and
--cg-max. The script compares the iteration counts frame by frame and prints the frames
where they differ; likewise the total energy (the programs' `energy` statistic and the
baselines' printed one, which they compute the same way inside the frame), noted where it
differs by more than 1e-6 relative.

Not a test: nothing here passes or fails on time. The machine's load shows in the numbers;
the medians damp it, and --repeat N runs every case N times, keeping for each runner the
least of the N medians of each timing column (load only ever adds time). The default (about 10 minutes with the interpreter on a 2-core machine)
runs 5 frames of each example; --frames changes that for all of them.
"""
import argparse
import copy
import filecmp
import functools
import math
import os
import re
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
import tomllib

from bench_tables import (COLUMNS, read_baseline_log, read_simit_csv, relative_error,
                          render_markdown, render_text, write_csv)

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def executor_flag(simit):
    """The option that selects an executor: --executor, or --backend in a simit from before
    that name (the CLI keeps --backend as another name of --executor)."""
    return "--executor" if help_mentions(simit, "--executor") else "--backend"


def scene_run(executor, extra_flags):
    """The argv of `simit run` under EXECUTOR (None: simit's default, the interpreter) with
    EXTRA_FLAGS; THREADS (a list, maybe empty) holds the --threads flag when the run passes
    one."""
    def argv(simit, scene, frames, outdir, final_csv, threads):
        selected = [executor_flag(simit), executor] if executor else []
        return ([simit, "run"] + selected + extra_flags + threads +
                ["--frames", str(frames), "--output", outdir, "--final-csv", final_csv, scene])
    return argv


# Executors of simit, in table order: name -> (argv builder, why this simit cannot run it
# ("" when it can), whether it runs on --threads N threads). The JIT and the GPU executor
# compile every site at its first execution (--jit-threshold 0: the compile time falls in the
# first frame, outside the medians) and print their traces (--jit-stats), whose compile times
# and CPU times go into the notes. The GPU executor's solver loops run on --threads N.
EXECUTORS = {
    "interpreter": (scene_run(None, []), lambda simit: "", False),
    "jit": (scene_run("jit", ["--jit-threshold", "0", "--jit-stats"]),
            lambda simit: executor_unavailable(simit, "jit"), True),
    "gpu": (scene_run("gpu", ["--jit-threshold", "0", "--jit-stats"]),
            lambda simit: executor_unavailable(simit, "gpu"), True),
    "jit-float32": (scene_run("jit", ["--float32", "--jit-threshold", "0", "--jit-stats"]),
                    lambda simit: executor_unavailable(simit, "jit"), True),
    "gpu-float32": (scene_run("gpu", ["--float32", "--jit-threshold", "0", "--jit-stats"]),
                    lambda simit: executor_unavailable(simit, "gpu"), True),
}
DEFAULT_EXECUTORS = "interpreter,jit"


@functools.lru_cache(maxsize=None)
def executor_unavailable(simit, executor):
    """Why SIMIT cannot run EXECUTOR (jit or gpu), "" when it can: a tiny program is run
    with it, and its error message is the reason (for the GPU: no driver, no device)."""
    if not help_mentions(simit, "--backend"):
        return "this simit has no --executor option (built before the JIT)"
    if executor != "jit" and not help_mentions(simit, "|" + executor):
        return "this simit has no %s executor (simit run --help lists none)" % executor
    with tempfile.NamedTemporaryFile("w", suffix=".sim", delete=False) as f:
        f.write("export func one() -> (x : float)\n  x = 1.0;\nend\n")
    try:
        out = subprocess.run([simit, "run", executor_flag(simit), executor, f.name,
                              "--call", "one"], capture_output=True, text=True)
    finally:
        os.unlink(f.name)
    if out.returncode == 0:
        return ""
    lines = (out.stderr or out.stdout).strip().splitlines()
    why = lines[-1] if lines else "exit status %d" % out.returncode
    return why.replace(f.name + ": ", "").replace("error: ", "")


def jit_available(simit):
    """Whether this simit has the JIT (built with LLVM): a tiny program runs with it."""
    return executor_unavailable(simit, "jit") == ""


def jit_traces(log_path):
    """The `--jit-stats` lines of a run's log: one per trace, without the keys."""
    try:
        with open(log_path) as f:
            text = f.read()
    except OSError:
        return []
    at = text.find("jit traces:")
    if at < 0:
        return []
    return [line.strip() for line in text[at:].splitlines()[2:]
            if line.strip() and not line.strip().startswith("key:")]


@functools.lru_cache(maxsize=None)
def help_mentions(simit, flag):
    """Whether `simit run --help` lists FLAG (for executors that need a newer simit)."""
    out = subprocess.run([simit, "run", "--help"], capture_output=True, text=True)
    return flag in out.stdout


def baseline_has_threads(baseline):
    """Whether a baseline's --help lists --threads (a baseline built before it has not)."""
    out = subprocess.run([baseline, "--help"], capture_output=True, text=True)
    return "--threads" in out.stdout


def simit_thread_flags(simit, threads):
    """The --threads flag for a simit run: always where this simit has the option (its default
    is every core), none where it predates it (one thread); None when THREADS is above 1 and
    this simit cannot run it."""
    if help_mentions(simit, "--threads"):
        return ["--threads", str(threads)]
    return [] if threads == 1 else None


def count_loc(path):
    """Non-blank lines that are not only comments (.sim: % and %{ %}; C++: // and /* */)."""
    text = open(path).read()
    if path.endswith(".sim"):
        text = re.sub(r"%\{.*?%\}", "", text, flags=re.S)
        text = re.sub(r"%.*", "", text)
    else:
        text = re.sub(r"/\*.*?\*/", "", text, flags=re.S)
        text = re.sub(r"//.*", "", text)
    return sum(1 for line in text.splitlines() if line.strip())


def run_child(argv, log_path, timeout):
    """Runs argv with stdout and stderr into log_path; returns (exit code, peak RSS in MB,
    wall seconds). The peak comes from the child's own rusage (os.wait4)."""
    start = time.monotonic()
    with open(log_path, "w") as log:
        child = subprocess.Popen(argv, stdout=log, stderr=subprocess.STDOUT, cwd=ROOT)
    deadline = start + timeout
    while True:
        pid, status, usage = os.wait4(child.pid, os.WNOHANG)
        if pid:
            break
        if time.monotonic() > deadline:
            child.kill()
            pid, status, usage = os.wait4(child.pid, 0)
            break
        time.sleep(0.05)
    child.returncode = os.waitstatus_to_exitcode(status)  # reaped here, not by Popen
    return child.returncode, usage.ru_maxrss / 1024.0, time.monotonic() - start


def median(values):
    return statistics.median(values) if values else float("nan")


class Case:
    """One example on one mesh: its scene (maybe generated) and its baseline's input."""

    def __init__(self, example, mesh, scene, baseline_input, default_frames):
        self.example, self.mesh = example, mesh
        self.scene, self.baseline_input = scene, baseline_input
        self.default_frames = default_frames
        with open(scene, "rb") as f:
            doc = tomllib.load(f)
        self.program = os.path.normpath(os.path.join(os.path.dirname(scene), doc["program"]))
        self.tensors = doc.get("tensors", {})
        self.baseline_source = os.path.join(ROOT, "bench", "baselines", example + "_baseline.cpp")
        self.note = None  # what the table's reader should know about the case, or None

    @property
    def name(self):
        return self.example + "/" + self.mesh


def bench_scene(source, workdir, name, cloth_n=None, program=None):
    """A copy of SOURCE in WORKDIR with the program and mesh paths made absolute (the program
    PROGRAM when given), [output] csv added when it has none, background = false (every run
    writes its frames between frames, as the tables before that key did: a writer beside a
    one-thread run takes memory bandwidth from it, about 3-5% of fem dragon160k's frame, and
    ms/frame leaves the writing out) and, for the cloth, n points per side (the example ships
    n = 32)."""
    with open(source, "rb") as f:
        doc = tomllib.load(f)
    if "output" not in doc:
        sys.exit("%s has no [output] table; the benchmark needs one (points, csv)" % source)
    base = os.path.dirname(os.path.abspath(source))
    text = open(source).read()
    def absolute(m):
        if m.group(1) == "program" and program:
            return 'program = "%s"' % program
        return '%s = "%s"' % (m.group(1), os.path.normpath(os.path.join(base, m.group(2))))
    text = re.sub(r'(?m)^(program|mesh) = "([^"]+)"', absolute, text)
    if cloth_n is not None:
        text = re.sub(r"(?m)^n = \d+", "n = %d" % cloth_n, text)
    added = "" if "csv" in doc["output"] else '\ncsv = "stats.csv"'
    if "background" not in doc["output"]:
        added += "\nbackground = false"
    text = re.sub(r"(?m)^\[output\]", lambda m: "[output]" + added, text, count=1)
    path = os.path.join(workdir, name + ".toml")
    with open(path, "w") as f:
        f.write(text)
    return path


def scene_without_background(scene):
    """The copy of SCENE (a bench_scene copy) without the background key it added, for a
    --compare-simit build that may predate the key (and writes its frames in turn)."""
    path = scene[:-len(".toml")] + "-older.toml"
    if not os.path.exists(path):
        text = open(scene).read().replace("\nbackground = false", "", 1)
        with open(path, "w") as f:
            f.write(text)
    return path


# The largest cloth side at which cloth.sim's explicit step (h = 2e-4, 50 steps a frame) is
# stable: at 128 and 256 points a side the stability limit, which shrinks with the edge
# length, is below it, and the baseline (the same fixed step) and simit both reach NaN in the
# first frame. Larger cloths run a copy of cloth.sim whose step is shrunk by (n / 64)^2 (the
# bending term's limit goes with the square of the edge: a step shrunk by n / 64 alone still
# diverges at 256), the frame still 1/100 s, without a baseline row, whose step is fixed.
CLOTH_STABLE_N = 64


def cloth_program(n, workdir):
    """For a cloth of N > CLOTH_STABLE_N points a side: (a copy of cloth.sim in WORKDIR with
    h and substeps scaled, h); else (None, None), the shipped program."""
    if n <= CLOTH_STABLE_N:
        return None, None
    source = os.path.join(ROOT, "examples", "cloth", "cloth.sim")
    code = open(source).read()
    h = float(re.search(r"(?m)^const h\s*=\s*([^;%]+);", code).group(1))
    substeps = int(re.search(r"(?m)^const substeps\s*=\s*([^;%]+);", code).group(1))
    steps = math.ceil(substeps * (n / CLOTH_STABLE_N) ** 2)
    step = h * substeps / steps
    code = re.sub(r"(?m)^const h\s*=\s*[^;]+;", "const h = %r;" % step, code, count=1)
    code = re.sub(r"(?m)^const substeps\s*=\s*[^;]+;", "const substeps = %d;" % steps, code,
                  count=1)
    path = os.path.join(workdir, "cloth%d.sim" % n)
    with open(path, "w") as f:
        f.write(code)
    return path, step


def cases(args, workdir, notes):
    ex = os.path.join(ROOT, "examples")
    data = os.path.join(ex, "data")

    def case(example, mesh, scene, baseline_input, frames):
        return Case(example, mesh, bench_scene(os.path.join(ex, example, scene), workdir,
                                               example + "-" + mesh),
                    baseline_input, frames)

    out = [case("fem", "bunny", "bunny.toml", os.path.join(data, "bunny.1.node"), 5),
           case("fem", "dragon40k", "dragon40k.toml", os.path.join(data, "dragon40k.node"), 5)]
    if args.dragon160k:
        out.append(case("fem", "dragon160k", "dragon160k.toml",
                        os.path.join(data, "dragon160k.node"), 3))
    out.append(case("springs", "bunny", "bunny.toml", os.path.join(data, "bunny.1.node"), 5))
    for n in args.cloth:
        program, step = cloth_program(n, workdir)
        scene = bench_scene(os.path.join(ex, "cloth", "square.toml"), workdir, "square%d" % n, n,
                            program)
        if program is None:
            out.append(Case("cloth", "square%d" % n, scene, str(n), 5))
            continue
        mesh = "square%d h=%.3g" % (n, step)
        out.append(Case("cloth", mesh, scene, None, 5))
        out[-1].note = ("cloth/%s: the shipped step h diverges above %d points a side, so this "
                        "case runs cloth.sim with h = %.3g (%d steps a frame), and no baseline "
                        "(its step is fixed)" % (mesh, CLOTH_STABLE_N, step, round(0.01 / step)))
    kept = [c for c in out if not args.only or any(o in c.name for o in args.only)]
    notes.extend(c.note for c in kept if c.note)
    return kept


def row_of(case, who, threads, frames_run, code, peak, data, loc):
    ok = code == 0 and len(data["ms"]) == frames_run
    return {
        "example": case.example, "mesh": case.mesh, "runner": who, "threads": threads,
        "frames": len(data["ms"]), "ok": ok,
        "ms": median(data["ms"]), "assembly": median(data["assembly"]),
        "solve": median(data["solve"]),
        "iterations": median(data["iterations"]) if data["iterations"] else None,
        "residual": data["residual"][-1] if data["residual"] else None,
        "peak_mb": peak, "loc": loc, "ratio": None, "scaling": None, "error": None,
        "same_bits": False,
    }


def run_baseline(case, args, workdir, notes, label, build, extra_args):
    """Runs one baseline build's EXAMPLE_baseline on CASE; returns (row, per-frame data,
    final positions CSV), or None when that build's baseline cannot run --threads N."""
    frames = args.frames or case.default_frames
    stem = os.path.join(workdir, "%s-%s-%s" % (case.example, case.mesh,
                                                re.sub(r"[^\w-]+", "_", label)))
    argv = [os.path.join(build, "bench", case.example + "_baseline")] + extra_args
    if args.threads != 1:
        if not baseline_has_threads(argv[0]):
            notes.append("%s %s: skipped, %s has no --threads (built before it)"
                         % (case.name, label, argv[0]))
            return None
        argv += ["--threads", str(args.threads)]
    if args.baseline_cpu_clock:
        argv.append("--cpu-clock")
    if "cg_tol" in case.tensors:
        argv += ["--cg-tol", repr(float(case.tensors["cg_tol"]))]
    if "cg_max" in case.tensors:
        argv += ["--cg-max", str(int(case.tensors["cg_max"]))]
    positions = stem + "-positions.csv"
    argv += ["--csv", positions, case.baseline_input, str(frames)]
    print("  " + " ".join(argv), flush=True)
    code, peak, _ = run_child(argv, stem + ".log", args.timeout)
    data = read_baseline_log(stem + ".log")
    if code != 0:
        notes.append("%s %s exited with %d (log %s.log)" % (case.name, label, code, stem))
    # Another build's source is not at hand: its LOC is left blank.
    loc = count_loc(case.baseline_source) if build == args.build else None
    row = row_of(case, label, args.threads, frames, code, peak, data, loc)
    return row, data, positions


# Energies further apart than this, relative, get a note. Capped CG leaves each solve's
# rounding in the iterates, so the energies agree less closely than in the converged
# scene_*_vs_baseline tests (fem bunny, 100 iterations: about 1e-8).
ENERGY_NOTE_RTOL = 1e-6


def note_energy_differences(case, name, energies, base_energies, notes):
    """A note for the frames where the program's energy statistic and the baseline's differ."""
    diffs = [(k + 1, a, b) for k, (a, b) in enumerate(zip(energies, base_energies))
             if not abs(a - b) <= ENERGY_NOTE_RTOL * abs(b)]
    if diffs or len(energies) != len(base_energies):
        notes.append("%s %s: the energy differs from the baseline's (relative %.0e) in frames %s"
                     % (case.name, name, ENERGY_NOTE_RTOL,
                        ", ".join("%d (%.9g vs %.9g)" % d for d in diffs)
                        or "(frame counts differ)"))


def baseline_only(case, args):
    return any(pattern in case.name for pattern in args.baseline_only)


def measure(case, args, workdir, notes):
    frames = args.frames or case.default_frames
    rows = []
    # The baseline first: its numbers are the reference of this case's ratios (a case with
    # no baseline input has none: a cloth whose step the baselines cannot shrink).
    base_row, base, base_positions = None, {"iterations": [], "energy": []}, None
    if case.baseline_input is not None:
        baseline_run = run_baseline(case, args, workdir, notes, "baseline", args.build, [])
        if baseline_run is None:  # main() checked this build's baselines: not reached
            sys.exit("%s: this build's baseline cannot run --threads" % case.name)
        base_row, base, base_positions = baseline_run
        base_row["ratio"] = 1.0
    variants = [(label, build, []) for label, build in args.compare_baseline]
    if case.example == "fem" and args.fem_sim_form:
        variants.insert(0, ("baseline --sim-form", args.build, ["--sim-form"]))
    if base_row is None:
        variants = []
    others = []  # (row, final positions) of the other baselines
    for label, build, extra in variants:
        run = run_baseline(case, args, workdir, notes, label, build, extra)
        if run:
            others.append((run[0], run[2]))
    reference = None  # the first executor's final positions: the error column's reference
    # Each executor of this simit, then of each --compare-simit build, side by side.
    runs = [(name, name, args.simit) for name in args.executors]
    runs += [(name + " " + label, name, os.path.join(build, "tools", "simit"))
             for label, build in args.compare_simit for name in args.executors]
    for runner, name, simit in ([] if baseline_only(case, args) else runs):
        make_argv, unavailable, threaded = EXECUTORS[name]
        if not threaded and not getattr(args, "first_count", True):
            continue  # one thread whatever the count: its row is the first count's
        why = unavailable(simit)
        if why:
            notes.append("%s: executor %s is not available in %s: %s"
                         % (case.name, name, simit, why))
            continue
        thread_flags = simit_thread_flags(simit, args.threads)
        if thread_flags is None and not threaded:
            thread_flags = []  # one thread whatever N: a simit without --threads runs it too
        if thread_flags is None:
            notes.append("%s %s: skipped, %s has no --threads (built before it)"
                         % (case.name, runner, simit))
            continue
        outdir = os.path.join(workdir, re.sub(r"[^\w-]+", "_", case.example + "-" + case.mesh +
                                              "-" + runner))
        shutil.rmtree(outdir, ignore_errors=True)
        positions = outdir + "-final.csv"
        scene = case.scene if simit == args.simit else scene_without_background(case.scene)
        argv = make_argv(simit, scene, frames, outdir, positions, thread_flags)
        print("  " + " ".join(argv), flush=True)
        code, peak, wall = run_child(argv, outdir + ".log", args.timeout)
        try:
            data = read_simit_csv(outdir)
        except (OSError, RuntimeError) as e:
            data = {"ms": [], "assembly": [], "solve": [], "iterations": [], "residual": [],
                    "energy": []}
            notes.append("%s %s: %s" % (case.name, runner, e))
        if code != 0:
            notes.append("%s %s exited with %d after %.0f s (log %s.log)"
                         % (case.name, runner, code, wall, outdir))
        row = row_of(case, runner, args.threads if threaded else 1, frames, code, peak, data,
                     count_loc(case.program))
        for trace in jit_traces(outdir + ".log"):
            notes.append("%s %s trace: %s" % (case.name, runner, trace))
        if base_row and base_row["ms"] > 0:
            row["ratio"] = row["ms"] / base_row["ms"]
        if reference is None and code == 0:
            reference = positions
        else:
            row["error"] = relative_error(positions, reference) if reference else None
            row["same_bits"] = bool(reference) and code == 0 and \
                filecmp.cmp(positions, reference, shallow=False)
        if base_row is None:
            rows.append(row)
            continue
        # Same stopping rule, same iterates: the iteration counts should match frame by frame.
        if data["iterations"] or base["iterations"]:
            diffs = [(k + 1, a, b) for k, (a, b) in
                     enumerate(zip(data["iterations"], base["iterations"])) if a != b]
            if diffs or len(data["iterations"]) != len(base["iterations"]):
                notes.append("%s %s: CG iterations differ from the baseline in frames %s"
                             % (case.name, runner, ", ".join("%d (%d vs %d)" % d for d in diffs)
                                or "(frame counts differ)"))
        note_energy_differences(case, runner, data["energy"], base["energy"], notes)
        rows.append(row)
    for row, positions in ([(base_row, base_positions)] if base_row else []) + others:
        if row is not base_row and base_row["ms"] > 0:
            row["ratio"] = row["ms"] / base_row["ms"]
        if reference:
            row["error"] = relative_error(positions, reference)
        rows.append(row)
    return rows


def measure_counts(case, args, workdir, notes):
    """CASE's rows at each thread count of --threads, the counts run one after the other in
    every repeat (so that a machine whose speed drifts affects them alike), each count's rows
    the least of its repeats; with several counts, each row's ms/frame against the same
    runner's at the first count ("scaling")."""
    counts = args.thread_counts
    runs = {t: [] for t in counts}
    for _ in range(args.repeat):
        for t in counts:
            at = copy.copy(args)
            at.threads, at.first_count = t, t == counts[0]
            runs[t].append(measure(case, at, workdir, notes))
    rows = []
    for t in counts:
        rows += fastest_of(runs[t])
    if len(counts) > 1:
        first = {r["runner"]: r for r in rows if r["threads"] == counts[0] or r["runner"] ==
                 "interpreter"}
        for r in rows:
            ref = first.get(r["runner"])
            r["scaling"] = r["ms"] / ref["ms"] if ref and ref["ms"] > 0 else None
    return rows


def fastest_of(runs):
    """One row per runner from several runs of a case: the least median of each timing
    column (a busy machine only ever adds time), the rest from the first run, and the
    ratios recomputed against the baseline's combined row."""
    rows = [dict(r) for r in runs[0]]
    for row, *others in zip(rows, *runs[1:]):
        for key in ("ms", "assembly", "solve"):
            row[key] = min([row[key]] + [o[key] for o in others])
        row["ok"] = row["ok"] and all(o["ok"] for o in others)
    base = next((r for r in rows if r["runner"] == "baseline"), None)
    for row in rows:
        row["ratio"] = row["ms"] / base["ms"] if base and base["ms"] > 0 else None
    return rows


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--build", default=os.path.join(ROOT, "build"),
                   help="the build folder with tools/simit and bench/*_baseline (default build)")
    p.add_argument("--frames", type=int, default=0,
                   help="frames per run (default: 5; 3 for dragon160k)")
    p.add_argument("--dragon160k", action="store_true", help="also fem on dragon160k (slow)")
    p.add_argument("--baseline-only", action="append", default=[], metavar="SUBSTRING",
                   help="run only the baselines on the cases whose example/mesh contains this "
                        "(repeatable; e.g. dragon160k, an hour under the interpreter)")
    p.add_argument("--compare-baseline", action="append", default=[], metavar="LABEL=DIR",
                   help="also run the baselines of another build folder DIR as rows LABEL "
                        "(e.g. an older version of the baselines; repeatable)")
    p.add_argument("--compare-simit", action="append", default=[], metavar="LABEL=DIR",
                   help="also run the executors of another build folder DIR's simit, as rows "
                        "'EXECUTOR LABEL' beside this build's (e.g. the previous commit; "
                        "repeatable)")
    p.add_argument("--baseline-cpu-clock", action="store_true",
                   help="time the baselines' frames in thread CPU time (--cpu-clock), which a "
                        "busy machine inflates less than wall time; simit stays on wall time "
                        "(one thread only: not with --threads above 1)")
    p.add_argument("--threads", default="1", metavar="N[,M...]",
                   help="run the baselines (--threads N, OpenMP) and simit's JIT (--threads N) "
                        "on N threads; the interpreter runs on one (default 1, the one-thread "
                        "table of before the option). Several counts (1,2) run each case at "
                        "each count side by side, every repeat, and add a column: ms/frame "
                        "against the same runner at the first count")
    p.add_argument("--fem-sim-form", action="store_true",
                   help="also run fem_baseline --sim-form (the stiffness column by column from dP)")
    p.add_argument("--cloth", default="32,64", help="cloth sizes, comma-separated (default 32,64)")
    p.add_argument("--repeat", type=int, default=1,
                   help="run each case N times and keep each timing's least median "
                        "(default 1; for a busy machine)")
    p.add_argument("--only", action="append", default=[], metavar="SUBSTRING",
                   help="run only the cases whose example/mesh contains this (repeatable: "
                        "any of them)")
    p.add_argument("--executors", default=DEFAULT_EXECUTORS,
                   help="comma-separated, from: %s (default %s)"
                        % (", ".join(EXECUTORS), DEFAULT_EXECUTORS))
    p.add_argument("--out", action="append", default=[],
                   help="also write the table to FILE: .md as markdown, anything else as CSV")
    p.add_argument("--keep", default="", help="keep the runs' output in this folder")
    p.add_argument("--timeout", type=float, default=1800, help="seconds per run (default 1800)")
    args = p.parse_args()
    args.build = os.path.abspath(args.build)
    args.simit = os.path.join(args.build, "tools", "simit")
    args.cloth = [int(n) for n in args.cloth.split(",") if n.strip()]
    args.executors = [e for e in args.executors.split(",") if e]
    try:
        args.thread_counts = [int(n) for n in args.threads.split(",")]
    except ValueError:
        args.thread_counts = []
    if not args.thread_counts or min(args.thread_counts) < 1:
        p.error("--threads needs whole numbers >= 1, comma-separated, got '%s'" % args.threads)
    args.threads = max(args.thread_counts)  # the checks below; measure() runs each count
    if args.baseline_cpu_clock and args.threads > 1:
        p.error("--baseline-cpu-clock times one thread's CPU time: it cannot go with "
                "--threads %d (time threaded runs in wall time)" % args.threads)

    def label_dirs(option, specs):
        """(label, absolute folder) of each LABEL=DIR given to OPTION."""
        out = []
        for spec in specs:
            label, sep, build = spec.partition("=")
            if not sep or not label or not build:
                p.error("%s needs LABEL=DIR, got '%s'" % (option, spec))
            out.append((label, os.path.abspath(build)))
        return out

    compare = args.compare_baseline = label_dirs("--compare-baseline", args.compare_baseline)
    args.compare_simit = label_dirs("--compare-simit", args.compare_simit)
    for e in args.executors:
        if e not in EXECUTORS:
            p.error("unknown executor '%s' (known: %s)" % (e, ", ".join(EXECUTORS)))
    simits = [args.simit] + [os.path.join(b, "tools", "simit") for _, b in args.compare_simit]
    missing = [f for f in simits + [os.path.join(build, "bench", x + "_baseline")
                                    for build in [args.build] + [b for _, b in compare]
                                    for x in ("fem", "springs", "cloth")]
               if not os.access(f, os.X_OK)]
    if missing:
        sys.exit("missing: %s (build the targets simit and *_baseline in %s)"
                 % (", ".join(missing), args.build))
    if args.threads > 1:
        old = [x for x in ("fem", "springs", "cloth")
               if not baseline_has_threads(os.path.join(args.build, "bench", x + "_baseline"))]
        if old:
            sys.exit("the baselines in %s have no --threads (%s): rebuild them"
                     % (args.build, ", ".join(old)))

    workdir = os.path.abspath(args.keep) if args.keep else tempfile.mkdtemp(prefix="simit-bench-")
    os.makedirs(workdir, exist_ok=True)
    if len(args.thread_counts) > 1:
        COLUMNS.insert(COLUMNS.index(("ratio", "vs baseline")) + 1,
                       ("scaling", "vs %d thread%s" % (args.thread_counts[0],
                                                       "" if args.thread_counts[0] == 1 else "s")))
    rows, notes = [], []
    started = time.monotonic()
    try:
        for case in cases(args, workdir, notes):
            print("%s (%d frames)" % (case.name, args.frames or case.default_frames), flush=True)
            rows += measure_counts(case, args, workdir, notes)
    finally:
        if not args.keep:
            shutil.rmtree(workdir, ignore_errors=True)
    print()
    print(render_text(rows))
    common = sum(count_loc(os.path.join(ROOT, "bench", "baselines", f))
                 for f in ("baseline_common.h", "baseline_common.cpp"))
    print("\nms: medians over the frames; solve = frame - assembly (simit: everything outside "
          "the maps, mostly CG).")
    print("Baseline LOC excludes baseline_common.{h,cpp} (%d lines shared by the three)." % common)
    print("Threads: %s (the baselines' --threads and the JIT's; the interpreter runs on one)."
          % ", ".join(str(t) for t in args.thread_counts))
    # Linux counts the launcher's resident set at exec into the child's ru_maxrss.
    _, floor, _ = run_child(["true"], os.devnull, 10)
    print("Peak MB has a floor of %.0f MB (this script's own RSS, which Linux counts into the "
          "child's peak at exec)." % floor)
    if args.baseline_cpu_clock:
        print("The baselines' times are thread CPU time (--cpu-clock), simit's wall time: "
              "ratios between the two mix clocks.")
    print("Total wall time %.0f s." % (time.monotonic() - started))
    for n in notes:
        print("note: " + n)
    for path in args.out:
        if path.endswith(".md"):
            with open(path, "w") as f:
                f.write(render_markdown(rows) + "\n")
        else:
            write_csv(rows, path)
        print("wrote " + path)


if __name__ == "__main__":
    main()
