#!/usr/bin/python3
"""The strong-scaling model of a distributed CG iteration, from 1 to 1,024 ranks.

Usage: /usr/bin/python3 bench/scaling_model.py [--build DIR] [--mesh BASE.node]
           [--parts K,...] [--partition-csv FILE]... [--work DIR] [--frames N] [--results DIR]

Measures, on this machine:
  1. the partition per rank count: `simit partition MESH --parts 1,2,...,1024 --csv` on the
     dragon160k mesh refined twice by bench/refine_tets.py (10,278,784 tets), or on --mesh;
     --partition-csv reuses saved outputs of that command instead (it takes minutes on 10M
     tets; the work folder keeps each run's as partition.csv), --parts names other counts;
  2. the time of one CG iteration per row on one rank: `simit run examples/fem/dragon160k.toml
     --executor jit --threads 1`, from the stats CSV's solve_ms / cg_iterations / vertices
     (the median of the frames after the first, whose solve includes first touches);
  3. the cost of a message between two MPI ranks and of an MPI_Allgather of one double:
     bench/mpi_message_cost.cpp, built with mpicxx into the work folder and run on 2 ranks.
Then models one CG iteration on the busiest rank of K:
  compute    = rows of the largest part x time per row
  exchange   = most neighbours x latency + most ghosts x 24 bytes / bandwidth
               (one ghost refresh of a vector of 3-vectors: the product A p)
  reductions = 2 inner products x ceil(log2 K) x the 2-rank MPI_Allgather time
and writes the table and its reading to RESULTS/scaling_model.md and scaling_model.csv
(default bench/results/). Needs numpy only for the mesh refinement.
"""

import argparse
import csv
import io
import math
import os
import platform
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

BENCH = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(BENCH)
PARTS = [2**k for k in range(11)]  # 1 .. 1024: the rank counts the model is asked for
GHOST_BYTES = 24  # one ghost entry of a vector of 3-vectors of doubles
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


def measure_partition(simit, mesh, vertices, parts, saved, work):
    """The partition's CSV line per rank count, and how it was obtained."""
    by_k = {}
    if saved:
        for path in saved:
            try:
                with open(path) as f:
                    by_k.update(parse_partition(f.read(), path, vertices))
            except OSError as e:
                raise ModelError(f"{path}: {e.strerror}")
        how = "read from saved outputs of that command"
    else:
        cmd = ["nice", simit, "partition", mesh, "--parts", ",".join(map(str, parts)), "--csv"]
        t0 = time.perf_counter()
        stdout, _ = run(cmd, "simit partition")
        wall = time.perf_counter() - t0
        with open(os.path.join(work, "partition.csv"), "w") as f:
            f.write(stdout)  # for --partition-csv next time
        by_k = parse_partition(stdout, "simit partition", vertices)
        how = f"run here ({wall:.0f} s in all, the mesh's reading included)"
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


# --- The model --------------------------------------------------------------------------------

def model(partition, vertices, cg, mpi, latency_scale=1.0):
    """One row per rank count: the busiest rank's terms of one CG iteration, in us."""
    rows = []
    for k, p in partition.items():
        owned = vertices if k == 1 else math.ceil(vertices * float(p["vertex_imbalance"]) / k)
        ghosts, neighbours = int(p["most_ghosts"]), int(p["most_neighbours"])
        compute = owned * cg["us_per_row"]
        ghost_bytes = ghosts * GHOST_BYTES / mpi["bytes_per_us"]
        exchange = neighbours * mpi["latency_us"] * latency_scale + ghost_bytes
        reductions = 2 * math.ceil(math.log2(k)) * mpi["allgather_us"] * latency_scale
        rows.append({
            "ranks": k, "rows_per_rank": owned, "ghosts": ghosts, "neighbours": neighbours,
            "compute_us": compute, "exchange_us": exchange, "reductions_us": reductions,
            "total_us": compute + exchange + reductions, "exchange_bytes_us": ghost_bytes,
            "cut_edges": int(p["cut_edges"]), "vertex_imbalance": float(p["vertex_imbalance"]),
            "element_imbalance": float(p["element_imbalance"]),
            "ghosts_all_parts": int(p["ghosts"]), "partition_ms": float(p["ms"]),
        })
    for r in rows:
        r["speedup"] = rows[0]["total_us"] / r["total_us"]
        r["efficiency"] = r["speedup"] / r["ranks"]
    return rows


def latency_for_half(partition, vertices, cg, mpi):
    """The factor on both measured latencies at which the most ranks up to 1,024 fall to 50%
    efficiency; None where no factor does."""
    at = max(i for i, k in enumerate(partition) if k <= 1024)
    base = model(partition, vertices, cg, mpi)[at]
    no_latency = model(partition, vertices, cg, mpi, latency_scale=0.0)[at]
    latency_part = base["total_us"] - no_latency["total_us"]
    target = model(partition, vertices, cg, mpi)[0]["total_us"] / (0.5 * base["ranks"])
    if latency_part <= 0 or target <= no_latency["total_us"]:
        return None  # one rank only, or under 50% even with free messages
    return (target - no_latency["total_us"]) / latency_part


def fmt(x, digits=1):
    return f"{x:,.{digits}f}"


def write_csv(path, rows):
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        for r in rows:
            w.writerow({k: (f"{v:.6g}" if isinstance(v, float) else v) for k, v in r.items()})


def blocks_per_row(cut_edges, cut_percent, vertices):
    """Nonzero 3x3 blocks per row of the system matrix: 1 + twice the graph's edges per vertex
    (the graph's edges from a partition line's cut and its share)."""
    return 1 + 2 * (cut_edges / (cut_percent / 100)) / vertices


def mesh_blocks_per_row(partition, vertices):
    """Blocks per row from the partition line with the largest cut (the most digits)."""
    p = max(partition.values(), key=lambda p: int(p["cut_edges"]))
    if int(p["cut_edges"]) == 0:
        raise ModelError("the partition cuts no edge: give it more than 1 part")
    return blocks_per_row(int(p["cut_edges"]), float(p["cut_percent"]), vertices)


def small_blocks_per_row(simit, vertices):
    """Blocks per row of the mesh the CG time was measured on (a quick partition of it)."""
    mesh = os.path.join(ROOT, "examples", "data", "dragon160k.node")
    stdout, _ = run([simit, "partition", mesh, "--parts", "64", "--csv"], "simit partition")
    return mesh_blocks_per_row(parse_partition(stdout, "simit partition", vertices), vertices)


def first_under_half(partition, vertices, cg, mpi, scale):
    """The least rank count whose efficiency falls under 50% with the latencies scaled."""
    rows = model(partition, vertices, cg, mpi, latency_scale=scale)
    return next((r["ranks"] for r in rows if r["efficiency"] < 0.5), None)


def explanation(rows, factor, mpi, crossings):
    within = [r for r in rows if r["ranks"] <= 1024]
    last = within[-1]
    below = next((r for r in rows if r["efficiency"] < 0.5), None)
    lines = []

    def terms(r):
        overhead = {"the ghost exchange": r["exchange_us"], "the reductions": r["reductions_us"]}
        worst = max(overhead, key=overhead.get)
        return (f"the busiest rank's {r['rows_per_rank']:,} rows compute in "
                f"{fmt(r['compute_us'])} us, against {fmt(r['exchange_us'])} us of ghost "
                f"exchange ({r['neighbours']} neighbours, {r['ghosts']:,} ghosts) and "
                f"{fmt(r['reductions_us'])} us of reductions: the larger overhead is {worst}")

    if below and below["ranks"] <= 1024:
        lines.append(f"The efficiency falls under 50% at **{below['ranks']:,} ranks** "
                     f"({below['efficiency']:.0%}): {terms(below)}.")
    else:
        lines.append(f"With these costs the efficiency stays above 50% up to "
                     f"{last['ranks']:,} ranks ({last['efficiency']:.0%} there): {terms(last)}.")
        if below:
            lines.append(f"On partitions of the same mesh beyond 1,024 it falls under 50% at "
                         f"**{below['ranks']:,} ranks** ({below['efficiency']:.0%}): "
                         f"{terms(below)}.")
    first = next((r for r in rows if r["ranks"] > 1), None)
    if first:
        most = max(within, key=lambda r: r["exchange_bytes_us"])
        shrink = (f"Their bytes do (the ghosts' bytes cost {fmt(most['exchange_bytes_us'])} us "
                  f"at {most['ranks']} ranks, {fmt(last['exchange_bytes_us'])} us at "
                  f"{last['ranks']:,}), but their count grows"
                  if most is not last else "Their count grows")
        lines.append(
            f"Why: the compute halves with every doubling of K, while the messages do not shrink "
            f"({fmt(first['exchange_us'] + first['reductions_us'])} us at {first['ranks']} "
            f"ranks, {fmt(last['exchange_us'] + last['reductions_us'])} us at "
            f"{last['ranks']:,}). {shrink}: a part's neighbours, from {first['neighbours']} to "
            f"{last['neighbours']}, "
            f"each a message's latency, and the reductions' ceil(log2 K) allgather steps. The "
            f"rest of the loss is the load imbalance (the largest part "
            f"{last['vertex_imbalance']:.3f}x the mean).")
    for scale, k in crossings:
        lines.append(f"With both latencies {'halved' if scale < 1 else 'doubled'}, the "
                     f"efficiency falls under 50% at " +
                     (f"{k:,} ranks." if k else "none of these rank counts."))
    if factor is not None:
        lines.append(
            f"Both measured latencies multiplied by {factor:.2g} (a message's "
            f"{fmt(factor * mpi['latency_us'], 2)} us, an allgather step's "
            f"{fmt(factor * mpi['allgather_us'], 2)} us) would put {last['ranks']:,} ranks at "
            f"50% efficiency.")
    return lines


def write_markdown(path, rows, info):
    cg, mpi = info["cg"], info["mpi"]
    beyond = [r for r in rows if r["ranks"] > 1024]
    top = [r for r in rows if r["ranks"] <= 1024][-1]
    top_mb = top["rows_per_rank"] * info["blocks_big"] * 72 / 1e6
    counts = ", ".join(f"{r['ranks']:,}" for r in rows)
    out = []
    out.append("# Strong scaling of a distributed CG iteration, 1 to 1,024 ranks (a model)\n")
    out.append(
        "Written by `bench/scaling_model.py` (re-run it to refresh this file and "
        "`scaling_model.csv`, which holds the table and the partition's figures). It models the "
        "busiest rank's share of one iteration of the fem example's CG (docs/distributed.md: a "
        "product `A * p` whose ghost rows are refreshed from their owners, then two inner "
        "products summed across the ranks) on a "
        f"{info['tets']:,}-tet mesh, from the partition METIS computes on that mesh and the "
        "costs measured on this machine. Nothing but those measurements enters it.\n")
    out.append("## Machine\n")
    out.append(f"- {info['machine']}\n- {mpi['mpi']}, shared-memory transport between two "
               "processes (`vader`, single copy disabled as in a container)\n")
    out.append("## Inputs measured\n")
    out.append(
        f"- **Mesh**: {info['mesh_note']}: {info['vertices']:,} vertices (rows), "
        f"{info['tets']:,} tets, {info['blocks_big']:.1f} nonzero 3x3 blocks per row of the "
        "system matrix (1 + twice the vertex graph's edges per vertex).\n"
        f"- **Partition**: `simit partition MESH --parts K,... --csv` for K = {counts}, "
        f"{info['partition_how']}; METIS took "
        f"{fmt(sum(r['partition_ms'] for r in rows) / 1e3)} s for these "
        f"{len(rows)} counts ({fmt(rows[-1]['partition_ms'] / 1e3)} s at {rows[-1]['ranks']:,}). "
        "Rows per rank: the vertices over K times the largest part's vertices over the mean "
        f"({min(r['vertex_imbalance'] for r in rows[1:]):.3f} to "
        f"{max(r['vertex_imbalance'] for r in rows[1:]):.3f} from 2 parts on); ghosts and "
        "neighbours: the most of any part (the two maxima "
        "may be different parts, so the exchange is an upper bound).\n"
        f"- **Time per row of one CG iteration**: {fmt(cg['us_per_row'] * 1e3)} ns, from "
        f"`{cg['command']}`: the stats CSV's solve_ms / cg_iterations / vertices "
        f"({cg['vertices']:,}, {info['blocks_small']:.1f} blocks per row), the least of the "
        f"frames after the first in {len(cg['runs'])} runs (solve ms / CG iterations: "
        + "; ".join(", ".join(f"{fmt(float(s['solve_ms']))} / {s['cg_iterations']}"
                              for s in frames) for frames in cg["runs"]) + "). "
        "solve_ms times the whole solver loop of a frame, so the per-row figure includes the "
        "loop's vector updates and its two inner products on one rank.\n"
        f"- **Messages** (`bench/mpi_message_cost.cpp`, 2 ranks; per figure the median of many "
        f"repeats, the least of {mpi['runs']} runs, since other work on the shared cores only "
        f"adds to it): latency {fmt(mpi['latency_us'], 2)} us (half a round trip of 8 bytes; "
        f"the runs: {', '.join(fmt(x, 2) for x in mpi['latency_runs'])}), bandwidth "
        f"{fmt(mpi['bytes_per_us'] / 1e3, 2)} GB/s (the least-squares slope of time over size "
        "from 64 KiB to 1 MiB), MPI_Allgather of one double on 2 ranks "
        f"{fmt(mpi['allgather_us'], 2)} us (the runs: "
        f"{', '.join(fmt(x, 2) for x in mpi['allgather_runs'])}). **These are shared-memory "
        "costs between two processes on one 2-core virtual machine**, not a network's.\n")
    out.append("| bytes | half round trip, median us | least of any repeat, us |\n"
               "|---:|---:|---:|")
    for b, t, lo in mpi["pingpong"]:
        out.append(f"| {b:,} | {t:.2f} | {lo:.2f} |")
    out.append("")
    out.append("## The model\n")
    out.append(
        "Per CG iteration on the busiest of K ranks (us): compute = rows per rank x time per "
        "row; exchange = neighbours x latency + ghosts x 24 bytes / bandwidth (one refresh of "
        "a vector of 3-vectors); reductions = 2 x ceil(log2 K) x the 2-rank MPI_Allgather "
        "(a recursive-doubling allgather of K ranks takes ceil(log2 K) such steps). Total = "
        "their sum (no overlap of messages with work); speed-up = total(1) / total(K); "
        "efficiency = speed-up / K."
        + (" The rows past 1,024 (in italics) are partitions of the same mesh, to show where "
           "the efficiency falls under 50%." if beyond else "") + "\n")
    out.append("| K | rows per rank | ghosts | neighbours | compute us | exchange us | "
               "reductions us | total us | speed-up | efficiency |")
    out.append("|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for r in rows:
        cells = [f"{r['ranks']:,}", f"{r['rows_per_rank']:,}", f"{r['ghosts']:,}",
                 f"{r['neighbours']}", fmt(r["compute_us"]), fmt(r["exchange_us"]),
                 fmt(r["reductions_us"]), fmt(r["total_us"]), fmt(r["speedup"]),
                 f"{r['efficiency']:.0%}"]
        if r["ranks"] > 1024:
            cells = [f"*{c}*" for c in cells]
        out.append("| " + " | ".join(cells) + " |")
    out.append("")
    out.append("## Where it stops scaling\n")
    for line in explanation(rows, info["factor"], mpi, info["crossings"]):
        out.append(line + "\n")
    out.append("## What the model leaves out\n")
    out.append(
        "- **The cache.** The time per row is measured on one rank of "
        f"{cg['vertices']:,} rows, whose CG iteration does not fit this machine's cache "
        "(bench/results/README.md). The busiest part at "
        f"{top['ranks']:,} ranks holds {top_mb:.1f} MB of matrix blocks (72 bytes each), "
        "within a server's cache: its rows would run faster than measured, so at high K the "
        "compute term is an upper bound and the real efficiency lower than modelled.\n"
        f"- **The mesh's rows.** The refined mesh has {info['blocks_big']:.1f} blocks per row "
        f"against the measured mesh's {info['blocks_small']:.1f}: its rows cost about "
        f"{100 * (info['blocks_big'] / info['blocks_small'] - 1):.0f}% more, which the model "
        "leaves out (it scales every K alike and so leaves the efficiency as it is).\n"
        "- **The network.** The latencies are shared memory's. Across nodes a message costs "
        "more (the network's latency, and the switches'), and an allgather of 1,024 ranks more "
        "than 10 of the 2-rank steps measured (synchronisation, noise): the last line above "
        "gives the latency factor at which 1,024 ranks reach 50%.\n"
        "- **The rest of a frame.** Assembly (each rank computes its own and its boundary "
        "elements, with no messages) and the output gathered to rank 0 are not modelled, nor "
        "are messages overlapped with work. The model is per CG iteration: the iteration "
        "counts on ranks stay within about 1% of one process's (docs/distributed.md).\n")
    with open(path, "w") as f:
        f.write("\n".join(out))


def machine():
    model_name = ""
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    model_name = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    cores = os.cpu_count() or 0
    return (f"{model_name or platform.processor()}, {cores} cores ({platform.machine()}, "
            f"{platform.system()}), shared with other work while measured")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--build", default=os.path.join(ROOT, "build"), help="the build folder")
    ap.add_argument("--mesh", help="a TetGen .node file to partition (default: dragon160k "
                    "refined twice into the work folder)")
    ap.add_argument("--parts", default=",".join(map(str, PARTS)),
                    help="the rank counts to partition for (default 1,2,4,...,1024; 1 needed)")
    ap.add_argument("--partition-csv", action="append",
                    help="a saved output of `simit partition MESH --parts K,... --csv` for the "
                    "mesh, instead of running it (repeatable: the lines are merged)")
    ap.add_argument("--work", help="the folder for the mesh and builds (default: a new "
                    "temporary folder, removed at the end)")
    ap.add_argument("--frames", type=int, default=5,
                    help="frames of the fem run that measures the CG (default 5, at least 2)")
    ap.add_argument("--cg-runs", type=int, default=3,
                    help="runs of the fem scene; the least frame counts (default 3)")
    ap.add_argument("--mpi-runs", type=int, default=3,
                    help="runs of the message costs; the least median counts (default 3)")
    ap.add_argument("--results", default=os.path.join(BENCH, "results"),
                    help="where scaling_model.md and .csv go")
    args = ap.parse_args()
    if args.cg_runs < 1:
        ap.error("--cg-runs must be at least 1")
    if args.mpi_runs < 1:
        ap.error("--mpi-runs must be at least 1")
    if args.frames < 2:
        ap.error("--frames must be at least 2 (the first frame is not counted)")
    try:
        parts = sorted({int(k) for k in args.parts.split(",")})
    except ValueError:
        ap.error(f"--parts: not a list of integers: {args.parts}")
    if 1 not in parts or parts[0] < 1:
        ap.error("--parts must hold 1 (the reference) and only positive counts")
    simit = os.path.join(args.build, "tools", "simit")
    if not os.access(simit, os.X_OK):
        sys.exit(f"scaling_model.py: {simit} not found (build the simit target)")
    work = args.work or tempfile.mkdtemp(prefix="simit_scaling_")
    os.makedirs(work, exist_ok=True)
    try:
        mesh = args.mesh or refined_mesh(work)
        base = mesh[:-5] if mesh.endswith(".node") else mesh
        vertices = header_count(base + ".node")
        tets = header_count(base + ".ele")
        print(f"mesh: {vertices:,} vertices, {tets:,} tets; partitioning ...", flush=True)
        partition, how = measure_partition(simit, mesh, vertices, parts, args.partition_csv,
                                           work)
        print("message costs ...", flush=True)
        mpi = measure_mpi(work, args.mpi_runs)
        print("CG time per row ...", flush=True)
        cg = measure_cg(simit, work, args.frames, args.cg_runs)
        rows = model(partition, vertices, cg, mpi)
        note = (f"`{os.path.basename(base)}`" if args.mesh else
                "dragon160k refined twice by regular 1:8 subdivision (`bench/refine_tets.py`, "
                "which checks that the tets' volume is kept)")
        info = {"cg": cg, "mpi": mpi, "vertices": vertices, "tets": tets, "mesh_note": note,
                "blocks_big": mesh_blocks_per_row(partition, vertices),
                "blocks_small": small_blocks_per_row(simit, cg["vertices"]),
                "partition_how": how, "machine": machine(),
                "factor": latency_for_half(partition, vertices, cg, mpi),
                "crossings": [(f, first_under_half(partition, vertices, cg, mpi, f))
                              for f in (0.5, 2.0)]}
        os.makedirs(args.results, exist_ok=True)
        write_csv(os.path.join(args.results, "scaling_model.csv"), rows)
        write_markdown(os.path.join(args.results, "scaling_model.md"), rows, info)
    except ModelError as e:
        sys.exit(f"scaling_model.py: {e}")
    finally:
        if not args.work:
            shutil.rmtree(work, ignore_errors=True)
    print(f"{'K':>5} {'rows':>9} {'ghosts':>7} {'nbrs':>5} {'compute':>10} {'exchange':>9} "
          f"{'reduce':>7} {'total':>10} {'speed-up':>8} {'eff':>5}")
    for r in rows:
        print(f"{r['ranks']:>5} {r['rows_per_rank']:>9,} {r['ghosts']:>7,} {r['neighbours']:>5} "
              f"{r['compute_us']:>10.1f} {r['exchange_us']:>9.1f} {r['reductions_us']:>7.1f} "
              f"{r['total_us']:>10.1f} {r['speedup']:>8.1f} {r['efficiency']:>5.0%}")
    for line in explanation(rows, info["factor"], mpi, info["crossings"]):
        print(line.replace("**", ""))
    print(f"wrote {os.path.join(args.results, 'scaling_model.md')} and scaling_model.csv")


if __name__ == "__main__":
    main()
