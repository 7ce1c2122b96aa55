"""The measurements of the strong-scaling model (bench/scaling_model.py): the partition of the
refined dragon as `simit run --distributed` cuts it, the time of a CG iteration per row, the
costs of MPI messages and of a reduction's arithmetic, each measured on this machine by running
the project's own tools. Every function raises ModelError, naming what failed, when a command
fails or prints what it should not."""

import csv
import io
import math
import os
import re
import shutil
import statistics
import subprocess
import sys
import time

BENCH = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(BENCH)
REORDER = "rcm"  # the scene's default renumbering, which the chunks are runs of

MPI_ENV = {  # OpenMPI as root, in a container, without ssh (docs/distributed.md)
    "OMPI_ALLOW_RUN_AS_ROOT": "1",
    "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM": "1",
    "OMPI_MCA_btl_vader_single_copy_mechanism": "none",
    "OMPI_MCA_plm": "isolated",
}


class ModelError(Exception):
    pass


def run(cmd, what, env=None, cwd=None):
    """stdout of `cmd`; a ModelError naming `what` when it fails."""
    try:
        p = subprocess.run(cmd, capture_output=True, text=True, env=env, cwd=cwd)
    except OSError as e:
        raise ModelError(f"{what}: cannot run {cmd[0]}: {e.strerror}")
    if p.returncode != 0:
        raise ModelError(f"{what} failed (exit {p.returncode}): {' '.join(cmd)}\n"
                         f"{p.stderr.strip()[-2000:]}")
    return p.stdout, p.stderr


def header_count(path):
    """The first number of a TetGen file's header (its vertex or tet count)."""
    try:
        with open(path) as f:
            for line in f:
                line = line.split("#", 1)[0].split()
                if line:
                    return int(line[0])
    except (OSError, ValueError) as e:
        raise ModelError(f"{path}: no TetGen header ({e})")
    raise ModelError(f"{path}: no TetGen header")


# --- 1. The partition -------------------------------------------------------------------------

def refined_mesh(work):
    """dragon160k refined twice (10,278,784 tets) into `work`; the path of its .node file."""
    out = os.path.join(work, "mesh")
    cmd = [sys.executable, os.path.join(BENCH, "refine_tets.py"),
           os.path.join(ROOT, "examples", "data", "dragon160k"), out, "--times", "2"]
    stdout, _ = run(cmd, "the mesh refinement")
    print(stdout.strip())
    return os.path.join(out, "dragon160k.node")


def parse_partition(text, source, vertices):
    lines = text.splitlines()
    start = next((i for i, ln in enumerate(lines) if ln.startswith("parts,")), len(lines))
    # The mesh's summary line ("MESH: N vertices, ...") comes before the CSV header: a saved
    # output of another mesh is refused.
    for ln in lines[:start]:
        words = ln.rsplit(": ", 1)[-1].split()
        if len(words) > 1 and words[1].startswith("vertices") and \
                int(words[0]) != vertices:
            raise ModelError(f"{source}: partitions a mesh of {words[0]} vertices, "
                             f"not this one's {vertices}")
    rows = list(csv.DictReader(lines[start:]))
    need = {"parts", "cut_edges", "cut_percent", "vertex_imbalance", "element_imbalance", "ghosts",
            "most_ghosts", "most_neighbours", "ms"}
    if not rows or not need <= set(rows[0]):
        raise ModelError(f"{source}: not the output of `simit partition --csv` "
                         f"(columns {sorted(need)})")
    return {int(r["parts"]): r for r in rows}


def sum_chunk():
    """The vertices per chunk of the blocked sums (runtime::kSumChunk), which a rank owns whole."""
    path = os.path.join(ROOT, "src", "runtime", "blocked_sum.h")
    try:
        with open(path) as f:
            m = re.search(r"kSumChunk\s*=\s*(\d+)", f.read())
    except OSError as e:
        raise ModelError(f"{path}: {e.strerror} (the chunk size of the blocked sums)")
    if not m:
        raise ModelError(f"{path}: no `kSumChunk = N` (the chunk size of the blocked sums)")
    return int(m.group(1))


def partition_command(simit, mesh, parts):
    return ["nice", simit, "partition", mesh, "--parts", ",".join(map(str, parts)), "--csv",
            "--reorder", REORDER]


SAVED_MARK = "# chunk partition, "  # the first line of a partition.csv this script writes


def measure_partition(simit, mesh, vertices, parts, saved, work):
    """The partition's CSV line per rank count, and how it was obtained."""
    by_k = {}
    if saved:
        for path in saved:
            try:
                with open(path) as f:
                    text = f.read()
            except OSError as e:
                raise ModelError(f"{path}: {e.strerror}")
            # Outputs saved before the ranks owned whole chunks (vertex-level partitions, or
            # without the scene's renumbering) would model another run: only a file this
            # script wrote, naming the command, is taken.
            first = text.split("\n", 1)[0]
            if not first.startswith(SAVED_MARK) or f"--reorder {REORDER}" not in first:
                raise ModelError(f"{path}: not a partition.csv this script wrote (its first line "
                                 f"names `simit partition ... --reorder {REORDER}`); partitions "
                                 "saved before the ranks owned whole chunks are not the run's: "
                                 "run without --partition-csv")
            by_k.update(parse_partition(text, path, vertices))
        how = "read from a saved output of that command"
    else:
        cmd = partition_command(simit, mesh, parts)
        t0 = time.perf_counter()
        stdout, _ = run(cmd, "simit partition")
        wall = time.perf_counter() - t0
        with open(os.path.join(work, "partition.csv"), "w") as f:  # for --partition-csv
            f.write(SAVED_MARK + "`" + " ".join(["simit"] + cmd[2:]) + "`\n" + stdout)
        by_k = parse_partition(stdout, "simit partition", vertices)
        how = (f"run here ({wall:.0f} s in all, the mesh's reading and its renumbering "
               "included)")
    if 1 not in by_k:
        raise ModelError("the partition has no line for 1 part (the model's reference)")
    return {k: by_k[k] for k in sorted(by_k)}, how


# --- 2. The time per row of one CG iteration --------------------------------------------------

def measure_cg(simit, work, frames, runs):
    scene = os.path.join(ROOT, "examples", "fem", "dragon160k.toml")
    vertices = header_count(os.path.join(ROOT, "examples", "data", "dragon160k.node"))
    out = os.path.join(work, "fem")
    cmd = [simit, "run", scene, "--executor", "jit", "--threads", "1", "--frames", str(frames),
           "--output", out]
    stats, per_row = [], []
    for _ in range(runs):
        run(cmd, "simit run (the CG time per row)")
        with open(os.path.join(out, "dragon160k_stats.csv")) as f:
            frames_run = list(csv.DictReader(f))
        if len(frames_run) < 2:
            raise ModelError("the fem run wrote fewer than 2 frames")
        stats.append(frames_run)
        # The first frame's solve includes first touches; of the others the least counts,
        # since other work on the shared cores only adds to a frame's time.
        per_row += [float(s["solve_ms"]) * 1e3 / int(s["cg_iterations"]) / vertices
                    for s in frames_run[1:]]
    return {
        "vertices": vertices,
        "runs": stats,
        "us_per_row": min(per_row),
        "command": " ".join(["simit"] + cmd[1:-2]).replace(ROOT + os.sep, ""),
    }


# --- 3. The cost of a message -----------------------------------------------------------------

def measure_mpi(work, runs):
    for tool in ("mpicxx", "mpirun"):
        if not shutil.which(tool):
            raise ModelError(f"{tool} not found: the message costs need OpenMPI")
    exe = os.path.join(work, "mpi_message_cost")
    run(["mpicxx", "-O2", "-std=c++20", os.path.join(BENCH, "mpi_message_cost.cpp"), "-o", exe],
        "building bench/mpi_message_cost.cpp")
    env = dict(os.environ, **MPI_ENV)
    # Other work on the shared cores only ever adds to a figure (a rank descheduled mid-message
    # waits for its core): of several runs' medians, the least is the machine's own cost.
    pingpong_runs, allgather_runs = {}, []
    for _ in range(runs):
        stdout, _ = run(["mpirun", "-np", "2", "--oversubscribe", exe], "mpi_message_cost",
                        env=env)
        for r in csv.DictReader(io.StringIO(stdout)):
            if r["kind"] == "pingpong":
                pingpong_runs.setdefault(int(r["bytes"]), []).append(
                    (float(r["median_us"]), float(r["min_us"])))
            elif r["kind"] == "allgather":
                allgather_runs.append(float(r["median_us"]))
    if not pingpong_runs or not allgather_runs:
        raise ModelError(f"mpi_message_cost printed no figures:\n{stdout}")
    pingpong = [(b, min(m for m, _ in v), min(lo for _, lo in v))
                for b, v in sorted(pingpong_runs.items())]
    allgather = [min(allgather_runs)]
    # Bandwidth: the least-squares slope of time over size where the bytes dominate (64 KiB
    # and up); latency: the smallest message's time.
    big = [(b, t) for b, t, _ in pingpong if b >= 65536]
    mb = statistics.mean(b for b, _ in big)
    mt = statistics.mean(t for _, t in big)
    slope = sum((b - mb) * (t - mt) for b, t in big) / sum((b - mb) ** 2 for b, _ in big)
    version, _ = run(["mpirun", "--version"], "mpirun --version", env=env)
    return {
        "pingpong": pingpong,
        "latency_us": pingpong[0][1],
        "bytes_per_us": 1.0 / slope,
        "allgather_us": allgather[0],
        "mpi": version.splitlines()[0].strip(),
        "runs": runs,
        "latency_runs": [m for m, _ in pingpong_runs[pingpong[0][0]]],
        "allgather_runs": allgather_runs,
    }


# --- 4. The arithmetic of a reduction ---------------------------------------------------------

def measure_combine(build, work, parts, vertices, chunk, runs):
    """Per rank count K > 1, one reduction's combine on every rank and the busiest rank's
    contribution, in us: bench/sum_combine_cost.cpp against the build's libraries."""
    libs = [os.path.join(build, "src", "dist", "libsimit_dist.a"),
            os.path.join(build, "src", "runtime", "libsimit_runtime.a")]
    for lib in libs:
        if not os.path.exists(lib):
            raise ModelError(f"{lib} not found (build the simit target)")
    if not shutil.which("g++"):
        raise ModelError("g++ not found: the reduction's arithmetic is measured with it")
    exe = os.path.join(work, "sum_combine_cost")
    run(["g++", "-O3", "-std=c++20", "-I", os.path.join(ROOT, "src"),
         os.path.join(BENCH, "sum_combine_cost.cpp")] + libs + ["-o", exe],
        "building bench/sum_combine_cost.cpp")
    chunks = math.ceil(vertices / chunk)
    medians = {}  # (kind, K) -> each run's median
    items = {}
    for _ in range(runs):
        for k in parts:
            if k == 1:
                continue
            stdout, _ = run([exe, str(chunks), str(k), str(vertices)], "sum_combine_cost")
            for r in csv.DictReader(io.StringIO(stdout)):
                medians.setdefault((r["kind"], k), []).append(float(r["median_us"]))
                items[(r["kind"], k)] = int(r["items"])
    # Up to the chunk count the combined pairs are the same at every K (one per chunk, in chunk
    # order): one figure, the least of all those medians, since other work on the shared cores
    # only adds to a figure. Past it each K has its own (every term shared).
    whole = [m for (kind, k), v in medians.items() if kind == "combine" and k <= chunks
             for m in v]
    by_k = {1: {"combine_us": 0.0, "contribution_us": 0.0, "pairs": 0, "terms": 0}}
    for k in parts:
        if k == 1:
            continue
        c = medians.get(("combine", k))
        d = medians.get(("contribution", k))
        if not c or not d:
            raise ModelError(f"sum_combine_cost printed no figures for {k} ranks")
        by_k[k] = {"combine_us": min(whole) if k <= chunks else min(c),
                   "contribution_us": min(d), "pairs": items[("combine", k)],
                   "terms": items[("contribution", k)], "combine_runs": c,
                   "contribution_runs": d}
    return {"by_k": by_k, "runs": runs, "chunk_runs": whole,
            "command": "g++ -O3 -std=c++20 -I src bench/sum_combine_cost.cpp "
                       "build/src/dist/libsimit_dist.a build/src/runtime/libsimit_runtime.a"}
