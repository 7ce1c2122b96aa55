#!/usr/bin/python3
"""The strong-scaling model of a distributed CG iteration, from 1 to 1,024 ranks.

Usage: /usr/bin/python3 bench/scaling_model.py [--build DIR] [--mesh BASE.node]
           [--parts K,...] [--partition-csv FILE]... [--work DIR] [--frames N]
           [--cg-runs N] [--mpi-runs N] [--combine-runs N] [--results DIR]

Measures, on this machine (bench/scaling_measure.py):
  1. the partition per rank count: `simit partition MESH --parts 1,2,...,1024 --csv
     --reorder rcm` on the dragon160k mesh refined twice by bench/refine_tets.py (10,278,784
     tets), or on --mesh. That is the partition `simit run --distributed` runs on: the vertices
     renumbered by reverse Cuthill-McKee (a scene's default), each rank owning whole chunks of
     256 consecutive vertices (the chunks of the blocked sums, runtime::kSumChunk, read from
     src/runtime/blocked_sum.h), METIS cutting between chunks, and vertex by vertex where the
     ranks outnumber the chunks (dist::partition_in_chunks). --partition-csv reuses a work
     folder's partition.csv, which this script writes with the command that made it (the
     chunk partition takes seconds, the vertex-by-vertex one past the chunk count minutes);
     --parts names other counts;
  2. the time of one CG iteration per row on one rank: `simit run examples/fem/dragon160k.toml
     --executor jit --threads 1`, from the stats CSV's solve_ms / cg_iterations / vertices
     (the least of the frames after the first, whose solve includes first touches, over
     --cg-runs runs: other work on the shared cores only adds to a frame's time);
  3. the cost of a message between two MPI ranks and of an MPI_Allgather of one double:
     bench/mpi_message_cost.cpp, built with mpicxx into the work folder and run on 2 ranks
     (per figure the least of --mpi-runs runs' medians);
  4. the arithmetic of a reduction on one rank: bench/sum_combine_cost.cpp, built with g++
     into the work folder against the build's libsimit_dist.a and libsimit_runtime.a and run
     per rank count K: one dist::combine_contributions over the contributions of K ranks
     owning runs of whole chunks (past the chunk count, every term shared), and the busiest
     rank's dist::sum_contribution (per figure the least of --combine-runs runs' medians).
Then models one CG iteration on the busiest rank of K:
  compute    = rows of the largest part x time per row
  exchange   = most neighbours x latency + most ghosts x 24 bytes / bandwidth
               (one ghost refresh of a vector of 3-vectors: the product A p)
  reductions = 2 inner products x (ceil(log2 K) x the 2-rank MPI_Allgather time
               + the bytes every rank receives / bandwidth + combine + contribution), 0 at
               K = 1: one MPI_Allgatherv of a pair (chunk index, partial) of 2 doubles per
               chunk, 16 x ceil(V / 256) bytes, or, past the chunk count, of a pair per
               vertex, 16 x V bytes; then every rank combines all the pairs in chunk order,
               after it built its own contribution (dist/sum_terms.h)
and writes the table and its reading to RESULTS/scaling_model.md and scaling_model.csv
(default bench/results/). Needs numpy only for the mesh refinement.
"""

import argparse
import csv
import math
import os
import platform
import shutil
import sys
import tempfile
import time

# The measurements (bench/scaling_measure.py): this script's own folder is on the path.
from scaling_measure import (REORDER, ModelError, header_count, measure_combine, measure_cg,
                             measure_mpi, measure_partition, parse_partition, partition_command,
                             refined_mesh, run, sum_chunk)

BENCH = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(BENCH)
PARTS = [2**k for k in range(11)]  # 1 .. 1024: the rank counts the model is asked for
GHOST_BYTES = 24  # one ghost entry of a vector of 3-vectors of doubles
PAIR_BYTES = 16  # one (chunk index, partial) pair, or (term index, term), of a reduction
# The previous model's figures at 1,024 ranks (bench/results/scaling_model.md before each rank
# owned whole chunks): METIS cut the refined dragon vertex by vertex, and a reduction was one
# MPI_Allgather of one double per rank. Quoted, not measured: the comparison in the results.
PREVIOUS_1024 = {"vertices": 1794594, "rows_per_rank": 1806, "cut_edges": 1407113,
                 "ghosts": 944, "neighbours": 24, "exchange_us": 8.5, "reductions_us": 6.8,
                 "total_us": 117.8, "efficiency": 0.84,
                 # that run's measured costs
                 "ns_per_row": 56.8, "latency_us": 0.29, "allgather_us": 0.34}
# --- The model --------------------------------------------------------------------------------

def reduction_bytes(k, vertices, chunk):
    """What every rank receives in one reduction's MPI_Allgatherv: a pair of doubles per chunk
    (each owned whole by one rank), or past the chunk count, where the parts are cut vertex by
    vertex and a chunk's terms travel one by one, a pair per vertex."""
    if k == 1:
        return 0
    chunks = math.ceil(vertices / chunk)
    return PAIR_BYTES * (chunks if k <= chunks else vertices)


def model(partition, vertices, cg, mpi, chunk, arith, latency_scale=1.0,
          reduction_bytes_scale=1.0, arithmetic_scale=1.0):
    """One row per rank count: the busiest rank's terms of one CG iteration, in us."""
    rows = []
    for k, p in partition.items():
        a = arith["by_k"][k]
        owned = vertices if k == 1 else math.ceil(vertices * float(p["vertex_imbalance"]) / k)
        ghosts, neighbours = int(p["most_ghosts"]), int(p["most_neighbours"])
        compute = owned * cg["us_per_row"]
        ghost_bytes = ghosts * GHOST_BYTES / mpi["bytes_per_us"]
        exchange = neighbours * mpi["latency_us"] * latency_scale + ghost_bytes
        received = reduction_bytes(k, vertices, chunk)
        sum_bytes = 2 * received / mpi["bytes_per_us"] * reduction_bytes_scale
        steps = 2 * math.ceil(math.log2(k)) * mpi["allgather_us"] * latency_scale
        # Every rank's combine of all the pairs and the busiest rank's own contribution, per
        # reduction as measured (0 at K = 1, where the sum is the one process's).
        combine = 2 * a["combine_us"] * arithmetic_scale
        contribution = 2 * a["contribution_us"] * arithmetic_scale
        reductions = steps + sum_bytes + combine + contribution
        rows.append({
            "ranks": k, "rows_per_rank": owned, "ghosts": ghosts, "neighbours": neighbours,
            "compute_us": compute, "exchange_us": exchange, "reductions_us": reductions,
            "combine_us": combine, "contribution_us": contribution,
            "total_us": compute + exchange + reductions, "exchange_bytes_us": ghost_bytes,
            "reduction_bytes": received, "reduction_bytes_us": sum_bytes,
            "reduction_messages_us": steps + sum_bytes, "combine_pairs": a["pairs"],
            "contribution_terms": a["terms"],
            "owns": "chunks" if k <= math.ceil(vertices / chunk) else "vertices",
            "cut_edges": int(p["cut_edges"]), "vertex_imbalance": float(p["vertex_imbalance"]),
            "element_imbalance": float(p["element_imbalance"]),
            "ghosts_all_parts": int(p["ghosts"]), "partition_ms": float(p["ms"]),
        })
    for r in rows:
        r["speedup"] = rows[0]["total_us"] / r["total_us"]
        r["efficiency"] = r["speedup"] / r["ranks"]
    return rows


def latency_for_half(partition, vertices, cg, mpi, chunk, arith):
    """The factor on both measured latencies at which the most ranks up to 1,024 fall to 50%
    efficiency; None where no factor does."""
    at = max(i for i, k in enumerate(partition) if k <= 1024)
    rows = model(partition, vertices, cg, mpi, chunk, arith)
    base = rows[at]
    no_latency = model(partition, vertices, cg, mpi, chunk, arith, latency_scale=0.0)[at]
    latency_part = base["total_us"] - no_latency["total_us"]
    target = rows[0]["total_us"] / (0.5 * base["ranks"])
    if latency_part <= 0 or target <= no_latency["total_us"]:
        return None  # one rank only, or under 50% even with free messages
    return (target - no_latency["total_us"]) / latency_part


def fmt(x, digits=1):
    return f"{x:,.{digits}f}"


def percent(x):
    """An efficiency in whole percents, or to a tenth under 1%."""
    return f"{x:.0%}" if x >= 0.01 else f"{x:.1%}"


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
    stdout, _ = run(partition_command(simit, mesh, [64])[1:], "simit partition")
    return mesh_blocks_per_row(parse_partition(stdout, "simit partition", vertices), vertices)


def first_under_half(partition, vertices, cg, mpi, chunk, arith, scale):
    """The least rank count whose efficiency falls under 50% with the latencies scaled."""
    rows = model(partition, vertices, cg, mpi, chunk, arith, latency_scale=scale)
    return next((r["ranks"] for r in rows if r["efficiency"] < 0.5), None)


def explanation(rows, info):
    factor, mpi, crossings = info["factor"], info["mpi"], info["crossings"]
    chunks = math.ceil(info["vertices"] / info["chunk"])
    within = [r for r in rows if r["ranks"] <= 1024]
    last = within[-1]
    below = next((r for r in rows if r["efficiency"] < 0.5), None)
    lines = []

    def terms(r):
        overhead = {"the ghost exchange": r["exchange_us"],
                    "the reductions' messages": r["reduction_messages_us"],
                    "the combining of the sums": r["combine_us"],
                    "the rank's own contributions to the sums": r["contribution_us"]}
        worst = max(overhead, key=overhead.get)
        return (f"the busiest rank's {r['rows_per_rank']:,} rows compute in "
                f"{fmt(r['compute_us'])} us, against {fmt(r['exchange_us'])} us of ghost "
                f"exchange ({r['neighbours']} neighbours, {r['ghosts']:,} ghosts) and "
                f"{fmt(r['reductions_us'])} us of reductions: "
                f"{fmt(r['reduction_messages_us'])} us of messages "
                f"({r['reduction_bytes']:,} bytes received per reduction), "
                f"{fmt(r['combine_us'])} us combining {r['combine_pairs']:,} pairs and "
                f"{fmt(r['contribution_us'])} us building the rank's contribution (two of each "
                f"per iteration); the largest overhead is {worst}")

    if below and below["ranks"] <= 1024:
        lines.append(f"The efficiency falls under 50% at **{below['ranks']:,} ranks** "
                     f"({below['efficiency']:.0%}): {terms(below)}.")
        if below is not last:
            lines.append(f"At {last['ranks']:,} ranks ({percent(last['efficiency'])}): "
                         f"{terms(last)}.")
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
        shrink = (f"The ghosts' bytes do (they cost {fmt(most['exchange_bytes_us'])} us at "
                  f"{most['ranks']} ranks, {fmt(last['exchange_bytes_us'])} us at "
                  f"{last['ranks']:,}), but the messages' count grows"
                  if most is not last else "The messages' count grows")
        # The reductions' bytes, the combine and the imbalance of whole chunks, at the most
        # ranks that still own whole chunks.
        whole = [r for r in within if r["owns"] == "chunks"][-1]
        share = whole["reduction_bytes_us"] / whole["compute_us"]
        arith = info["arith"]
        overheads = whole["exchange_us"] + whole["reduction_messages_us"] + whole["combine_us"]
        lines.append(
            f"Why: the compute halves with every doubling of K, and so does a rank's own "
            f"contribution to the sums ({fmt(first['contribution_us'])} us an iteration at "
            f"{first['ranks']} ranks for {first['contribution_terms']:,} terms, "
            f"{fmt(last['contribution_us'])} us at {last['ranks']:,}), while the messages do "
            f"not shrink ({fmt(first['exchange_us'] + first['reduction_messages_us'])} us at "
            f"{first['ranks']} ranks, "
            f"{fmt(last['exchange_us'] + last['reduction_messages_us'])} us at "
            f"{last['ranks']:,}) and the combining does not shrink at all. {shrink}: a part's "
            f"neighbours, from {first['neighbours']} to {last['neighbours']}, each a message's "
            f"latency, and the reductions' ceil(log2 K) allgather steps. The reductions' bytes "
            f"do not shrink: every rank receives the pair of every chunk, {PAIR_BYTES} x "
            f"{chunks:,} = {PAIR_BYTES * chunks:,} bytes per reduction at any K up to "
            f"{chunks:,}, {fmt(whole['reduction_bytes_us'])} us an iteration, which is "
            f"{share:.0%} of the busiest rank's compute at {whole['ranks']:,} ranks. Nor does "
            f"the combining: every rank places the {chunks:,} pairs by their chunk index and "
            f"adds the partials in chunk order, a chain of {chunks:,} dependent additions, "
            f"{fmt(arith['by_k'][whole['ranks']]['combine_us'])} us per reduction at any K up "
            f"to {chunks:,}, {fmt(whole['combine_us'])} us an iteration, "
            f"{whole['combine_us'] / whole['compute_us']:.0%} of the busiest rank's compute at "
            f"{whole['ranks']:,} ranks: the messages and the combining together are "
            f"{overheads / whole['compute_us']:.1f}x the compute there. The rest of the loss is "
            f"the ranks' contributions, which shrink with K but add "
            f"{whole['contribution_us'] / whole['compute_us']:.0%} to the busiest rank's "
            f"compute at {whole['ranks']:,} ranks (about as much at every K: a pass over the "
            f"rank's terms), and the load imbalance: a rank owns whole chunks of "
            f"{info['chunk']} rows, "
            f"{chunks / whole['ranks']:.2g} of them on average at {whole['ranks']:,} ranks, and "
            f"the largest part holds "
            f"{whole['vertex_imbalance']:.3f}x the mean.")
    past = [r for r in rows if r["owns"] == "vertices"]
    if past:
        r = past[0]
        lines.append(
            f"Past {chunks:,} ranks there are fewer chunks than ranks: the parts are cut vertex "
            f"by vertex, the chunks are shared by several ranks, and a shared chunk's terms "
            f"travel one by one (the model counts a pair per vertex): every rank receives "
            f"{r['reduction_bytes'] / 1e6:.1f} MB per reduction, "
            f"{fmt(r['reduction_bytes_us'])} us an iteration, and combines "
            f"{r['combine_pairs']:,} shared terms (a sort of the pairs, then each chunk's "
            f"partial from its terms), {fmt(r['combine_us'] / 2e3)} ms per reduction as "
            f"measured, against {fmt(r['compute_us'])} us of compute at {r['ranks']:,} ranks "
            f"({percent(r['efficiency'])} efficiency): more ranks than chunks never pay. The "
            f"combine there is measured with each rank's terms scattered over the whole set "
            f"(each term's rank drawn from its index), so that the gathered pairs come as "
            f"{r['ranks']:,} interleaved ascending runs: the upper side of the sort. A METIS "
            f"part's vertices, numbered by RCM, come in longer runs, which sort faster; the "
            f"bytes, the chunks' partials and the chain of additions are the same either way.")
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
    elif last["ranks"] > 1:
        lines.append(
            f"No latency puts {last['ranks']:,} ranks at 50% efficiency: with free messages "
            f"(both latencies 0) the bytes, the combining, the contributions and the load "
            f"imbalance alone keep it under 50%.")
    return lines


def comparison(rows, info):
    """The paragraph against the previous model's vertex-level partition, where it applies (the
    default mesh, 1,024 ranks modelled); None elsewhere."""
    old = PREVIOUS_1024
    now = next((r for r in rows if r["ranks"] == 1024), None)
    if now is None or info["vertices"] != old["vertices"] or info["custom_mesh"]:
        return None
    # Both partitions under this run's costs: the previous one with its one-double
    # reductions, this one with those (no bytes per chunk), and this one as modelled.
    cg, mpi = info["cg"], info["mpi"]
    steps = 2 * math.ceil(math.log2(1024)) * mpi["allgather_us"]
    prev_total = (old["rows_per_rank"] * cg["us_per_row"] + old["neighbours"] * mpi["latency_us"]
                  + old["ghosts"] * GHOST_BYTES / mpi["bytes_per_us"] + steps)
    prev_eff = rows[0]["total_us"] / (1024 * prev_total)
    no_bytes = info["no_reduction_bytes_1024"]
    no_arith = info["no_arithmetic_1024"]
    cut = "fewer" if old["cut_edges"] < now["cut_edges"] else "more"

    costs_share = ("Most" if abs(old["efficiency"] - prev_eff) > abs(prev_eff - now["efficiency"])
                   else "Part")

    def points(loss):
        return f"{'cost' if loss >= 0 else 'gain'} {abs(100 * loss):.0f} points"

    return (
        f"Against the previous, vertex-level partition (this file before the ranks owned whole "
        f"chunks): METIS cut the refined dragon vertex by vertex, and a reduction was one "
        f"MPI_Allgather of one double per rank. At 1,024 ranks it cut "
        f"{old['cut_edges']:,} edges, {cut} than the chunk partition's "
        f"{now['cut_edges']:,}; its busiest rank held {old['rows_per_rank']:,} rows (here "
        f"{now['rows_per_rank']:,}) and {old['ghosts']:,} ghosts from {old['neighbours']} "
        f"neighbours (here {now['ghosts']:,} from {now['neighbours']}), and the model gave "
        f"**{old['efficiency']:.0%} efficiency** ({old['exchange_us']} us of exchange, "
        f"{old['reductions_us']} us of reductions, {old['total_us']} us in all). Now it gives "
        f"**{now['efficiency']:.0%}**. {costs_share} of the difference is the measured costs: "
        "that run "
        f"measured {old['ns_per_row']} ns per row, a latency of {old['latency_us']} us and an "
        f"allgather step of {old['allgather_us']} us, this one {fmt(cg['us_per_row'] * 1e3)} "
        f"ns, {fmt(mpi['latency_us'], 2)} us and {fmt(mpi['allgather_us'], 2)} us, and the "
        f"cheaper the rows, the more the messages weigh. Under this run's "
        f"costs the previous partition and reductions would give {prev_eff:.0%}, the chunk "
        f"partition with the previous reductions (the allgather steps alone: no bytes per "
        f"chunk, no combining) {no_bytes['efficiency']:.0%}, with the bytes per chunk "
        f"{no_arith['efficiency']:.0%}, and with its whole reductions "
        f"{now['efficiency']:.0%}: the chunk partition's parts (their rows, ghosts and "
        f"neighbours) {points(prev_eff - no_bytes['efficiency'])}, the reductions' bytes "
        f"{points(no_bytes['efficiency'] - no_arith['efficiency'])}, their combining and the "
        f"ranks' contributions {points(no_arith['efficiency'] - now['efficiency'])}. What "
        f"that buys: the vertex-level partition's sums grouped their terms per rank and could "
        f"not give one process's bits; a run on the chunk partition gives them, the CG "
        f"iterations included (docs/arithmetic.md, \"Distributed runs\").")


def write_markdown(path, rows, info):
    cg, mpi = info["cg"], info["mpi"]
    beyond = [r for r in rows if r["ranks"] > 1024]
    top = [r for r in rows if r["ranks"] <= 1024][-1]
    top_mb = top["rows_per_rank"] * info["blocks_big"] * 72 / 1e6
    big_mb = info["vertices"] * info["blocks_big"] * 72 / 1e6
    small_mb = cg["vertices"] * info["blocks_small"] * 72 / 1e6
    counts = ", ".join(f"{r['ranks']:,}" for r in rows)
    chunks = math.ceil(info["vertices"] / info["chunk"])
    vertex_wise = " and ".join(f"{r['ranks']:,}" for r in rows if r["owns"] == "vertices")
    chunk_top = [r for r in rows if r["owns"] == "chunks"][-1]
    out = []
    out.append("# Strong scaling of a distributed CG iteration, 1 to 1,024 ranks (a model)\n")
    out.append(
        "Written by `bench/scaling_model.py` (re-run it to refresh this file and "
        "`scaling_model.csv`, which holds the table and the partition's figures). It models the "
        "busiest rank's share of one iteration of the fem example's CG (docs/distributed.md: a "
        "product `A * p` whose ghost rows are refreshed from their owners, then two inner "
        "products summed across the ranks, each rank sending a pair per chunk of the blocked "
        "sums it owns) on a "
        f"{info['tets']:,}-tet mesh, from the partition a distributed run computes on that "
        "mesh (whole chunks of the blocked sums per rank, after the scene's RCM renumbering) "
        "and the costs measured on this machine. Nothing but those measurements enters it.\n")
    out.append("## Machine\n")
    out.append(f"- {info['machine']}\n- {mpi['mpi']}, shared-memory transport between two "
               "processes (`vader`, single copy disabled as in a container)\n")
    out.append("## Inputs measured\n")
    out.append(
        f"- **Mesh**: {info['mesh_note']}: {info['vertices']:,} vertices (rows), "
        f"{info['tets']:,} tets, {info['blocks_big']:.1f} nonzero 3x3 blocks per row of the "
        "system matrix (1 + twice the vertex graph's edges per vertex).\n"
        f"- **Partition**: `simit partition MESH --parts K,... --csv --reorder {REORDER}` "
        f"for K = {counts}, {info['partition_how']}. It is the partition `simit run "
        "--distributed` runs on (dist::partition_in_chunks): the vertices renumbered by "
        "reverse Cuthill-McKee as a scene renumbers them by default, then each rank owning "
        f"whole chunks of {info['chunk']} consecutive vertices, the chunks of the blocked sums "
        f"({chunks:,} chunks), with METIS cutting the graph between chunks"
        + (f"; at more ranks than chunks (K = {vertex_wise}) vertex by vertex"
           if vertex_wise else "") +
        f". The partitioner took {fmt(sum(r['partition_ms'] for r in rows) / 1e3)} s for these "
        f"{len(rows)} counts ({fmt(rows[-1]['partition_ms'] / 1e3)} s at "
        f"{rows[-1]['ranks']:,}"
        + (f"; {fmt(sum(r['partition_ms'] for r in rows if r['owns'] == 'chunks') / 1e3)} s "
           f"for the chunk partitions up to {chunk_top['ranks']:,}" if vertex_wise else "")
        + "). Rows per rank: the vertices over K times the largest part's vertices over the "
        f"mean ({min(r['vertex_imbalance'] for r in rows[1:]):.3f} to "
        f"{max(r['vertex_imbalance'] for r in rows[1:]):.3f} from 2 parts on; whole chunks "
        "make the parts coarser as K grows); ghosts and neighbours: the most of any part (the "
        "two maxima may be different parts, so the exchange is an upper bound).\n"
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
    arith = info["arith"]
    chunk_ks = [r for r in rows if r["ranks"] > 1 and r["owns"] == "chunks"]
    contribution_short = max((1 - r["contribution_terms"] / r["rows_per_rank"]
                              for r in chunk_ks), default=0.0)
    out.append(
        f"- **A reduction's arithmetic on one rank** (`bench/sum_combine_cost.cpp`, built with "
        f"`{arith['command']}`, run once per K; per figure the median of many calls after "
        "warm-ups, which take the buffers' first touches, the least of "
        f"{arith['runs']} runs): K contributions built with dist::sum_contribution from "
        f"{info['vertices']:,} terms of fixed values, each rank owning a run of whole chunks "
        "as the chunk partition gives them, concatenated in rank order as the allgather gives "
        "them, then one dist::combine_contributions over them (its sum checked against "
        "runtime::blocked_dot's bits). "
        + (f"Up to {chunks:,} ranks the combined pairs are the same at every K, one per chunk "
           f"in chunk order: **{fmt(chunk_ks[0]['combine_us'] / 2, 2)} us per reduction** for "
           f"the {chunks:,} pairs, the least of the {len(arith['chunk_runs'])} medians "
           f"measured at {len(chunk_ks)} rank counts (they range from "
           f"{fmt(min(arith['chunk_runs']), 2)} to {fmt(max(arith['chunk_runs']), 2)} us). "
           if chunk_ks else "")
        + (f"Past {chunks:,} ranks every term is shared, each rank's terms scattered over the "
           "whole set (each term's rank drawn from its index): "
           + "; ".join(f"{fmt(r['combine_us'] / 2e3, 1)} ms per reduction for "
                       f"{r['combine_pairs']:,} pairs at {r['ranks']:,} ranks (the runs: "
                       + ", ".join(fmt(x / 1e3, 1)
                                   for x in arith['by_k'][r['ranks']]['combine_runs'])
                       + " ms)" for r in rows if r["owns"] == "vertices") + ". "
           if vertex_wise else "")
        + "The contribution is the busiest rank's (the most terms: "
        f"ceil({chunks:,} / K) whole chunks, up to {contribution_short:.0%} fewer terms than "
        "the partition's busiest part has rows, taken as measured), one sum_contribution per "
        "reduction:\n")
    out.append("| K | terms of the busiest rank | its contribution, us per reduction | "
               "pairs combined | combine, us per reduction |\n|---:|---:|---:|---:|---:|")
    for r in rows:
        if r["ranks"] > 1:
            out.append(f"| {r['ranks']:,} | {r['contribution_terms']:,} | "
                       f"{fmt(r['contribution_us'] / 2, 2)} | {r['combine_pairs']:,} | "
                       f"{fmt(r['combine_us'] / 2, 2)} |")
    out.append("")
    out.append("## The model\n")
    out.append(
        "Per CG iteration on the busiest of K ranks (us): compute = rows per rank x time per "
        "row; exchange = neighbours x latency + ghosts x 24 bytes / bandwidth (one refresh of "
        "a vector of 3-vectors); reductions = 2 x (ceil(log2 K) x the 2-rank MPI_Allgather "
        "+ bytes received / bandwidth + combine + contribution), 0 at K = 1. Each reduction "
        "starts with the rank building its contribution (a pair per chunk it owns whole, "
        "with the chunk's partial from its terms), then is one MPI_Allgatherv "
        "that gives every rank every chunk's pair (chunk index, partial), 2 doubles: "
        f"{PAIR_BYTES} x {chunks:,} = {PAIR_BYTES * chunks:,} bytes received by every rank at "
        f"any K up to {chunks:,}, or, where the parts are cut vertex by vertex and the chunks "
        f"shared, a pair per vertex, {PAIR_BYTES} x {info['vertices']:,} bytes; the "
        "allgather's ceil(log2 K) recursive-doubling steps cost the measured 2-rank "
        "allgather each. Every rank then combines all the pairs: each partial placed by its "
        "chunk index (a shared chunk's terms sorted and summed first), and the partials "
        "added in chunk order, which gives one process's bits (docs/arithmetic.md, "
        "\"Distributed runs\"). The combine and the contribution are the measured figures "
        "above, twice each per iteration; the table's reductions include them, and its "
        "combine and contribution columns show their part. Total = their sum (no "
        "overlap of messages with work); speed-up = total(1) / total(K); efficiency = "
        "speed-up / K."
        + (" The rows past 1,024 (in italics) are partitions of the same mesh, to show where "
           "the efficiency falls under 50%." if beyond else "") + "\n")
    out.append("| K | rows per rank | ghosts | neighbours | bytes per reduction | compute us | "
               "exchange us | reductions us | of which combine us | of which contribution us | "
               "total us | speed-up | efficiency |")
    out.append("|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for r in rows:
        cells = [f"{r['ranks']:,}", f"{r['rows_per_rank']:,}", f"{r['ghosts']:,}",
                 f"{r['neighbours']}", f"{r['reduction_bytes']:,}", fmt(r["compute_us"]),
                 fmt(r["exchange_us"]), fmt(r["reductions_us"]), fmt(r["combine_us"]),
                 fmt(r["contribution_us"]), fmt(r["total_us"]), fmt(r["speedup"]),
                 percent(r["efficiency"])]
        if r["ranks"] > 1024:
            cells = [f"*{c}*" for c in cells]
        out.append("| " + " | ".join(cells) + " |")
    out.append("")
    out.append("## Where it stops scaling\n")
    for line in explanation(rows, info):
        out.append(line + "\n")
    previous = comparison(rows, info)
    if previous:
        out.append("## Against the vertex-level partition\n")
        out.append(previous + "\n")
    out.append("## What the model leaves out\n")
    out.append(
        "- **The cache.** The time per row is measured on one rank of "
        f"{cg['vertices']:,} rows, whose matrix holds {small_mb:.1f} MB of blocks (72 bytes "
        "each), and the model costs every row alike. The one-rank reference's "
        f"{big_mb:,.0f} MB stream from memory, whatever the cache; the busiest part at "
        f"{top['ranks']:,} ranks holds {top_mb:.1f} MB, within a server's cache. Where the "
        "measured mesh's blocks fit this machine's cache (which the CPU generation decides), "
        "the reference runs slower per row than modelled, and the real speed-ups are larger "
        "than modelled; where they do not, the busiest parts run faster than modelled. Either "
        "way the modelled efficiency at high K is a lower bound, and the messages' share of "
        "an iteration is what the table shows or more.\n"
        f"- **The mesh's rows.** The refined mesh has {info['blocks_big']:.1f} blocks per row "
        f"against the measured mesh's {info['blocks_small']:.1f}: its rows cost about "
        f"{100 * (info['blocks_big'] / info['blocks_small'] - 1):.0f}% more, which the model "
        "leaves out (it scales every K alike and so leaves the efficiency as it is).\n"
        "- **The network.** The latencies and the bandwidth are shared memory's. Across nodes "
        "a message costs more (the network's latency, and the switches'), an allgather of "
        "1,024 ranks more than 10 of the 2-rank steps measured (synchronisation, noise), and "
        "the reductions' bytes arrive at the network's bandwidth, which a node's ranks share: "
        + ("the last line of \"Where it stops scaling\" gives the latency factor at which "
           f"{top['ranks']:,} ranks reach 50%." if info["factor"] is not None else
           "the lines that end \"Where it stops scaling\" give the effect of halved and "
           f"doubled latencies (at {top['ranks']:,} ranks no latency reaches 50%: the "
           "bytes, the combining, the contributions and the load imbalance keep it under).")
        + "\n"
        "- **The combining.** Modelled as measured, on one core of this machine with the "
        "buffers warm: every rank's combine of all the pairs after each reduction's "
        f"allgather (dist/sum_terms.cpp: each of the {chunks:,} partials placed by its chunk "
        f"index, then {chunks:,} additions in chunk order, each waiting for the one before), "
        f"{fmt(top['combine_us'] / 2, 2)} us per reduction on every rank whatever K, against "
        f"the {top['rows_per_rank']:,} rows of the busiest rank at {top['ranks']:,} "
        f"({fmt(top['combine_us'])} us an iteration, "
        f"{top['combine_us'] / top['compute_us']:.0%} of its compute), and the busiest rank's "
        "own contribution, which shrinks with its rows. Left out: the copying of a rank's "
        "owned element sums and their global indices into the contribution's input "
        "(dist/mpi/scene_distribution.cpp), which grows with the rank's rows like the "
        "compute; and on the other side the one-rank reference's time per row already holds "
        "its inner products' chunk partials, which a rank's contribution computes again for "
        "its chunks, so that part of the contribution is counted twice. A combine on a busy "
        "core, or one whose pairs arrive from other sockets' caches, costs more than the "
        "figure measured."
        + (" Past the chunk count the combine is measured with each rank's terms scattered "
           "over the whole set, the upper side of the sort of the shared terms (a METIS "
           "part's vertices come in longer runs)." if vertex_wise else "") + "\n"
        "- **The rest of a frame.** Assembly (each rank computes its own and its boundary "
        "elements, with no messages) and the output gathered to rank 0 are not modelled, nor "
        "are messages overlapped with work. The model is per CG iteration, and the iterations "
        "are one process's: a run on ranks gives one process's bits, its CG iteration counts "
        "included (docs/arithmetic.md, \"Distributed runs\").\n")
    with open(path, "w") as f:
        f.write("\n".join(out))


def machine():
    fields = {}
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                key, _, value = line.partition(":")
                key = key.strip()
                if key in ("model name", "cpu family", "model") and key not in fields:
                    fields[key] = value.strip()
                if not line.strip() and fields:
                    break  # the first processor's lines only
    except OSError:
        pass
    # A virtual machine's model name may say little ("AMD EPYC"): its family and model tell
    # the generation, and so the caches the time per row depends on.
    family = (f" (family {fields['cpu family']}, model {fields['model']})"
              if "cpu family" in fields and "model" in fields else "")
    cores = os.cpu_count() or 0
    return (f"{fields.get('model name') or platform.processor()}{family}, {cores} cores "
            f"({platform.machine()}, {platform.system()}), shared with other work while "
            "measured")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--build", default=os.path.join(ROOT, "build"), help="the build folder")
    ap.add_argument("--mesh", help="a TetGen .node file to partition (default: dragon160k "
                    "refined twice into the work folder)")
    ap.add_argument("--parts", default=",".join(map(str, PARTS)),
                    help="the rank counts to partition for (default 1,2,4,...,1024; 1 needed)")
    ap.add_argument("--partition-csv", action="append",
                    help="a work folder's partition.csv, the saved output of `simit partition "
                    f"MESH --parts K,... --csv --reorder {REORDER}` for the mesh, instead of "
                    "running it (repeatable: the lines are merged)")
    ap.add_argument("--work", help="the folder for the mesh and builds (default: a new "
                    "temporary folder, removed at the end)")
    ap.add_argument("--frames", type=int, default=5,
                    help="frames of the fem run that measures the CG (default 5, at least 2)")
    ap.add_argument("--cg-runs", type=int, default=3,
                    help="runs of the fem scene; the least frame counts (default 3)")
    ap.add_argument("--mpi-runs", type=int, default=3,
                    help="runs of the message costs; the least median counts (default 3)")
    ap.add_argument("--combine-runs", type=int, default=3,
                    help="runs of the reduction's arithmetic per rank count; the least median "
                    "counts (default 3)")
    ap.add_argument("--results", default=os.path.join(BENCH, "results"),
                    help="where scaling_model.md and .csv go")
    args = ap.parse_args()
    if args.cg_runs < 1:
        ap.error("--cg-runs must be at least 1")
    if args.mpi_runs < 1:
        ap.error("--mpi-runs must be at least 1")
    if args.combine_runs < 1:
        ap.error("--combine-runs must be at least 1")
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
    started = time.perf_counter()
    try:
        chunk = sum_chunk()
        mesh = args.mesh or refined_mesh(work)
        base = mesh[:-5] if mesh.endswith(".node") else mesh
        vertices = header_count(base + ".node")
        tets = header_count(base + ".ele")
        print(f"mesh: {vertices:,} vertices, {tets:,} tets; partitioning ...", flush=True)
        partition, how = measure_partition(simit, mesh, vertices, parts, args.partition_csv,
                                           work)
        print("message costs ...", flush=True)
        mpi = measure_mpi(work, args.mpi_runs)
        print("the reductions' combine and contribution ...", flush=True)
        arith = measure_combine(args.build, work, list(partition), vertices, chunk,
                                args.combine_runs)
        print("CG time per row ...", flush=True)
        cg = measure_cg(simit, work, args.frames, args.cg_runs)
        rows = model(partition, vertices, cg, mpi, chunk, arith)
        no_bytes = model(partition, vertices, cg, mpi, chunk, arith, reduction_bytes_scale=0.0,
                         arithmetic_scale=0.0)
        no_arith = model(partition, vertices, cg, mpi, chunk, arith, arithmetic_scale=0.0)
        note = (f"`{os.path.basename(base)}`" if args.mesh else
                "dragon160k refined twice by regular 1:8 subdivision (`bench/refine_tets.py`, "
                "which checks that the tets' volume is kept)")
        info = {"cg": cg, "mpi": mpi, "arith": arith, "vertices": vertices, "tets": tets,
                "mesh_note": note, "chunk": chunk, "custom_mesh": bool(args.mesh),
                "no_reduction_bytes_1024": next((r for r in no_bytes if r["ranks"] == 1024),
                                                None),
                "no_arithmetic_1024": next((r for r in no_arith if r["ranks"] == 1024), None),
                "blocks_big": mesh_blocks_per_row(partition, vertices),
                "blocks_small": small_blocks_per_row(simit, cg["vertices"]),
                "partition_how": how, "machine": machine(),
                "factor": latency_for_half(partition, vertices, cg, mpi, chunk, arith),
                "crossings": [(f, first_under_half(partition, vertices, cg, mpi, chunk, arith,
                                                   f))
                              for f in (0.5, 2.0)]}
        os.makedirs(args.results, exist_ok=True)
        write_csv(os.path.join(args.results, "scaling_model.csv"), rows)
        write_markdown(os.path.join(args.results, "scaling_model.md"), rows, info)
    except ModelError as e:
        sys.exit(f"scaling_model.py: {e}")
    finally:
        if not args.work:
            shutil.rmtree(work, ignore_errors=True)
    print(f"{'K':>5} {'rows':>9} {'ghosts':>7} {'nbrs':>5} {'bytes':>11} {'compute':>10} "
          f"{'exchange':>9} {'reduce':>8} {'combine':>8} {'contrib':>8} {'total':>10} "
          f"{'speed-up':>8} {'eff':>5}")
    for r in rows:
        print(f"{r['ranks']:>5} {r['rows_per_rank']:>9,} {r['ghosts']:>7,} {r['neighbours']:>5} "
              f"{r['reduction_bytes']:>11,} {r['compute_us']:>10.1f} {r['exchange_us']:>9.1f} "
              f"{r['reductions_us']:>8.1f} {r['combine_us']:>8.1f} "
              f"{r['contribution_us']:>8.1f} {r['total_us']:>10.1f} {r['speedup']:>8.1f} "
              f"{r['efficiency']:>5.1%}")
    for line in explanation(rows, info) + [comparison(rows, info) or ""]:
        print(line.replace("**", ""))
    print(f"wrote {os.path.join(args.results, 'scaling_model.md')} and scaling_model.csv "
          f"({time.perf_counter() - started:.0f} s in all)")


if __name__ == "__main__":
    main()
