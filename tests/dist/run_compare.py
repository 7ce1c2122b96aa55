#!/usr/bin/env python3
"""A scene run in one process against the same scene on two MPI ranks (simit run --distributed).

Usage: run_compare.py SIMIT SCENE WORK (--same-bits | --tolerance T --iterations K)
                      [--stats NAME,...] [--frames N] [--jit] -- MPIRUN ARGS...

Checks: two 2-rank runs write identical bytes (final positions, every .vtu frame, the stats
without their timing columns), and so does a 2-rank run with --executor jit --threads 2 (maps
compiled, on two threads a rank) when --jit says this simit has the JIT;
the final positions of one process and of two ranks differ by at most T (relative to the
largest coordinate), and so do the stats named by --stats (relative to their largest value);
each frame's CG iterations differ by at most K. With --same-bits, one process and two ranks
write the same final positions and stats, byte for byte (the contract's promise where no
direct solve runs: docs/arithmetic.md, "Distributed runs"). Each rank reports its part of
every set: both own elements of every set and hold ghosts, and the owned counts add up to the
sets' sizes in one process.
Exit status 0 when every check holds, 1 otherwise (with the reason).
"""
import argparse
import csv
import filecmp
import os
import re
import shutil
import subprocess
import sys


def run(command):
    done = subprocess.run(command, capture_output=True, text=True, timeout=600)
    if done.returncode != 0:
        sys.exit("FAILED: %s\nexit status %d\n%s%s" % (" ".join(command), done.returncode,
                                                      done.stdout, done.stderr))
    return done.stdout


def positions(path):
    with open(path) as f:
        rows = list(csv.reader(f))
    return [[float(x) for x in row] for row in rows[1:]]


def untimed_stats(folder):
    names = [n for n in os.listdir(folder) if n.endswith(".csv")]
    if len(names) != 1:
        sys.exit("FAILED: expected one stats CSV in %s, found %s" % (folder, names))
    with open(os.path.join(folder, names[0])) as f:
        rows = list(csv.reader(f))
    keep = [i for i, name in enumerate(rows[0]) if not (name == "ms" or name.endswith("_ms"))]
    return [[row[i] for i in keep] for row in rows], rows[0]


def header_counts(path):
    """NumberOfPoints and NumberOfCells of a .vtu (its XML header, before the raw data)."""
    with open(path, "rb") as f:
        head = f.read(4096).decode("latin-1")
    m = re.search(r'NumberOfPoints="(\d+)" NumberOfCells="(\d+)"', head)
    return (int(m.group(1)), int(m.group(2))) if m else (0, 0)


def check_pieces(one, two):
    """Each frame of the 2-rank series is a .pvtu joining one piece per rank: the pieces exist,
    their cells add up to the one-process frame's and their points cover its points."""
    failures = []
    pvtus = sorted(n for n in os.listdir(two) if n.endswith(".pvtu"))
    if not pvtus:
        return ["the 2-rank run wrote no .pvtu frame"]
    for name in pvtus:
        with open(os.path.join(two, name)) as f:
            text = f.read()
        pieces = re.findall(r'<Piece Source="([^"]+)"/>', text)
        if len(pieces) != 2:
            failures.append("%s joins %d pieces, not 2" % (name, len(pieces)))
            continue
        if name not in open(os.path.join(two, [n for n in os.listdir(two)
                                                if n.endswith(".pvd")][0])).read():
            failures.append("%s is not in the .pvd" % name)
        points = cells = 0
        for piece in pieces:
            path = os.path.join(two, piece)
            if not os.path.exists(path):
                failures.append("%s names %s, which does not exist" % (name, piece))
                continue
            p, c = header_counts(path)
            points += p
            cells += c
        serial = os.path.join(one, name[:-len(".pvtu")] + ".vtu")
        p1, c1 = header_counts(serial)
        if cells != c1 or points < p1:
            failures.append("%s: pieces hold %d cells and %d points, one process %d and %d"
                            % (name, cells, points, c1, p1))
    print("%d frames written as .pvtu, each joining 2 pieces" % len(pvtus))
    return failures


def main():
    argv = sys.argv[1:]
    split = argv.index("--")
    parser = argparse.ArgumentParser()
    parser.add_argument("simit")
    parser.add_argument("scene")
    parser.add_argument("work")
    parser.add_argument("--same-bits", action="store_true")
    parser.add_argument("--tolerance", type=float)
    parser.add_argument("--iterations", type=int)
    parser.add_argument("--stats", default="")
    parser.add_argument("--frames", default="")
    parser.add_argument("--jit", action="store_true")
    args = parser.parse_args(argv[:split])
    if args.same_bits:
        args.tolerance, args.iterations = 0.0, 0
    elif args.tolerance is None or args.iterations is None:
        parser.error("give --same-bits, or --tolerance and --iterations")
    mpirun = argv[split + 1:]
    shutil.rmtree(args.work, ignore_errors=True)
    os.makedirs(args.work)
    out = {}
    for name in ["one", "two_a", "two_b"] + (["two_jit"] if args.jit else []):
        folder = os.path.join(args.work, name)
        command = [args.simit, "run", args.scene, "--output", folder,
                   "--final-csv", folder + ".csv"]
        if args.frames:
            command += ["--frames", args.frames]
        if name != "one":
            command = mpirun + [args.simit, "run", "--distributed"] + command[2:]
        if name == "two_jit":
            command += ["--executor", "jit", "--threads", "2", "--jit-cache", "off"]
        out[name] = run(command)
    failures = []
    # Two 2-rank runs, and one with compiled maps: the same bytes.
    a = os.path.join(args.work, "two_a")
    frames = sorted(n for n in os.listdir(a) if n.endswith(".vtu") or n.endswith(".pvtu"))
    if not frames:
        failures.append("the 2-rank run wrote no .vtu frame")
    failures += check_pieces(os.path.join(args.work, "one"), a)
    others = [("two_b", "two 2-rank runs")]
    if args.jit:
        others.append(("two_jit", "2-rank runs with and without the JIT (2 threads a rank)"))
    else:
        print("no run with --executor jit: this simit has no JIT")
    for other, what in others:
        b = os.path.join(args.work, other)
        if not filecmp.cmp(a + ".csv", b + ".csv", shallow=False):
            failures.append(what + " wrote different final positions")
        for n in frames:
            if not filecmp.cmp(os.path.join(a, n), os.path.join(b, n), shallow=False):
                failures.append("%s wrote different %s" % (what, n))
        if untimed_stats(a)[0] != untimed_stats(b)[0]:
            failures.append(what + " wrote different stats")
    # Each rank's part: "rank R: SET N owned + G ghosts, ...; SET ...", and the sizes of one
    # process: "SCENE: SET N, SET N; F frames".
    sizes = dict((name, int(n)) for name, n in
                 re.findall(r"(\w+) (\d+)[,;]", out["one"].splitlines()[0]))
    owned = {}
    for rank, line in re.findall(r"^rank (\d+): (.*)$", out["two_a"], re.M):
        ghosts = 0
        for name, n, g in re.findall(r"(\w+) ([\d,]+) owned \+ ([\d,]+) ghosts", line):
            n, g = int(n.replace(",", "")), int(g.replace(",", ""))
            print("rank %s: %s %d owned, %d ghosts" % (rank, name, n, g))
            if n == 0:
                failures.append("rank %s owns no element of %s" % (rank, name))
            ghosts += g
            owned[name] = owned.get(name, 0) + n
        if ghosts == 0:
            failures.append("rank %s holds no ghost" % rank)
    if not sizes or owned != sizes:
        failures.append("owned counts %s do not add up to the sets' sizes %s" % (owned, sizes))
    # One process against two ranks.
    one, two = positions(os.path.join(args.work, "one.csv")), positions(a + ".csv")
    if len(one) != len(two) or not one:
        failures.append("%d positions in one process, %d on two ranks" % (len(one), len(two)))
    else:
        scale = max(abs(x) for row in one for x in row)
        worst = max(abs(x - y) for r, s in zip(one, two) for x, y in zip(r, s))
        print("positions: largest difference %.3g (%.3g of the largest coordinate, bound %.3g)"
              % (worst, worst / scale, args.tolerance))
        if worst > args.tolerance * scale:
            failures.append("positions differ by %.3g, more than %.3g" % (worst / scale,
                                                                        args.tolerance))
    stats_one, header = untimed_stats(os.path.join(args.work, "one"))
    stats_two, _ = untimed_stats(a)
    if "cg_iterations" in header:
        column = [n for n in stats_one[0]].index("cg_iterations")
        for r, s in zip(stats_one[1:], stats_two[1:]):
            print("frame %s: %s CG iterations in one process, %s on two ranks" % (r[0], r[column],
                                                                                   s[column]))
            if abs(int(r[column]) - int(s[column])) > args.iterations:
                failures.append("frame %s: CG iterations %s and %s differ by more than %d"
                                % (r[0], r[column], s[column], args.iterations))
    for name in [n for n in args.stats.split(",") if n]:
        if name not in header:
            failures.append("no stats column '%s'" % name)
            continue
        column = [n for n in stats_one[0]].index(name)
        ones = [float(r[column]) for r in stats_one[1:]]
        twos = [float(r[column]) for r in stats_two[1:]]
        scale = max(abs(v) for v in ones) or 1.0
        worst = max(abs(x - y) for x, y in zip(ones, twos))
        print("%s: largest difference %.3g of its largest value" % (name, worst / scale))
        if worst > args.tolerance * scale:
            failures.append("%s differs by %.3g, more than %.3g" % (name, worst / scale,
                                                                  args.tolerance))
    if args.same_bits:
        one_csv = os.path.join(args.work, "one.csv")
        if not filecmp.cmp(one_csv, a + ".csv", shallow=False):
            failures.append("one process and two ranks wrote different final positions")
        if stats_one != stats_two:
            failures.append("one process and two ranks wrote different stats")
        else:
            print("one process and two ranks: the same final positions and stats, byte for byte")
    if len(stats_one) != len(stats_two):
        failures.append("%d stats rows in one process, %d on two ranks" % (len(stats_one),
                                                                           len(stats_two)))
    for f in failures:
        print("FAILED: " + f)
    if not failures:
        print("ok: two ranks agree with one process and with themselves")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
