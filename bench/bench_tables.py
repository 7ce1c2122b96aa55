"""Reading the benchmark's runs and writing its table (bench/run_bench.py): simit's per-frame
CSV, a baseline's per-frame log, final positions and their relative error, and the table as
text, Markdown or CSV."""
import csv
import os
import re


def read_simit_csv(outdir):
    names = [f for f in os.listdir(outdir) if f.endswith(".csv")]
    if len(names) != 1:
        raise RuntimeError("expected one per-frame CSV in %s, found %s" % (outdir, names))
    with open(os.path.join(outdir, names[0])) as f:
        rows = list(csv.DictReader(f))
    num = lambda r, k: float(r[k]) if r.get(k) not in (None, "") else None
    return {"ms": [num(r, "ms") for r in rows],
            "assembly": [num(r, "assembly_ms") for r in rows],
            "solve": [num(r, "solve_ms") for r in rows],
            "iterations": [int(num(r, "cg_iterations")) for r in rows if "cg_iterations" in r],
            "residual": [num(r, "cg_residual") for r in rows if "cg_residual" in r],
            "energy": [num(r, "energy") for r in rows if "energy" in r]}


FRAME_LINE = re.compile(r"^frame (\d+): \w+ ([\d.]+) ms, \w+ ([\d.]+) ms"
                        r"(?:, cg (\d+) iterations, residual ([-+\d.e]+))?(?:, energy (\S+))?")


def read_baseline_log(path):
    frames = {"ms": [], "assembly": [], "solve": [], "iterations": [], "residual": [],
              "energy": []}
    for line in open(path):
        m = FRAME_LINE.match(line)
        if not m:
            continue
        a, s = float(m.group(2)), float(m.group(3))
        frames["assembly"].append(a)
        frames["solve"].append(s)
        frames["ms"].append(a + s)
        if m.group(4):
            frames["iterations"].append(int(m.group(4)))
            frames["residual"].append(float(m.group(5)))
        if m.group(6):
            frames["energy"].append(float(m.group(6)))
    return frames


def read_positions(path):
    """The x,y,z rows of a positions CSV (simit --final-csv or a baseline's --csv)."""
    with open(path) as f:
        rows = list(csv.reader(f))
    return [tuple(float(v) for v in r) for r in rows[1:] if r]


def relative_error(path, reference):
    """max |x - x_ref| / max |x_ref| over every coordinate, or None when unreadable."""
    try:
        a, ref = read_positions(path), read_positions(reference)
    except (OSError, ValueError):
        return None
    if len(a) != len(ref) or not ref:
        return None
    scale = max(abs(c) for p in ref for c in p)
    return max(abs(x - y) for p, q in zip(a, ref) for x, y in zip(p, q)) / scale


COLUMNS = [("example", "example"), ("mesh", "mesh"), ("runner", "runner"),
           ("threads", "threads"), ("frames", "frames"), ("ms", "ms/frame"), ("assembly", "assembly ms"),
           ("solve", "solve ms"), ("iterations", "CG it/frame"), ("residual", "rel. resid."),
           ("peak_mb", "peak MB"), ("loc", "LOC"), ("ratio", "vs baseline"),
           ("error", "rel. err")]


def cell(row, key):
    v = row[key]
    if v is None:
        return "-"
    if key in ("ms", "assembly", "solve"):
        return "%.1f" % v if v >= 10 else "%.3f" % v
    if key == "iterations":
        return "%g" % v
    if key == "error" and row["same_bits"]:
        return "same bits"
    if key in ("residual", "error"):
        return "%.2e" % v
    if key == "peak_mb":
        return "%.0f" % v
    if key in ("ratio", "scaling"):
        return "%.1fx" % v if v >= 10 else "%.2fx" % v
    if key == "runner" and not row["ok"]:
        return v + " (failed)"
    return str(v)


def render_text(rows):
    table = [[title for _, title in COLUMNS]] + [[cell(r, k) for k, _ in COLUMNS] for r in rows]
    widths = [max(len(line[i]) for line in table) for i in range(len(COLUMNS))]
    lines = []
    for n, line in enumerate(table):
        lines.append("  ".join(c.rjust(w) if i >= 3 else c.ljust(w)
                               for i, (c, w) in enumerate(zip(line, widths))).rstrip())
        if n == 0:
            lines.append("  ".join("-" * w for w in widths))
    return "\n".join(lines)


def render_markdown(rows):
    out = ["| " + " | ".join(t for _, t in COLUMNS) + " |",
           "|" + "|".join("---" if i < 3 else "---:" for i in range(len(COLUMNS))) + "|"]
    for r in rows:
        out.append("| " + " | ".join(cell(r, k) for k, _ in COLUMNS) + " |")
    return "\n".join(out)


def write_csv(rows, path):
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow([k for k, _ in COLUMNS])
        for r in rows:
            w.writerow(["" if r[k] is None else r[k] for k, _ in COLUMNS])
