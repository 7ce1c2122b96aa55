"""Checks the numbers in the debugger's expected transcripts against values computed here from
the meshes, so that the transcripts are right and not only repeatable (a ctest).

verify_values.py DIR   (the tests/debugger folder)
"""
import math
import os
import re
import sys

FAILURES = []


def check(ok, what):
    if not ok:
        FAILURES.append(what)


def close(a, b, rtol=1e-12, atol=0.0):
    return abs(a - b) <= max(atol, rtol * max(abs(a), abs(b)))


def read_mesh(directory, base):
    with open(os.path.join(directory, base + ".node")) as f:
        rows = [line.split() for line in f if line.strip()]
    points = {int(r[0]): tuple(float(x) for x in r[1:4]) for r in rows[1:]}
    with open(os.path.join(directory, base + ".ele")) as f:
        rows = [line.split() for line in f if line.strip()]
    tets = {int(r[0]): [int(x) for x in r[1:5]] for r in rows[1:]}
    return points, tets


def edge_det(points, tet):
    """det [x0-x3, x1-x3, x2-x3] (columns), as fem.sim's and tet_energy.sim's edge_matrix."""
    a, b, c, d = (points[v] for v in tet)
    m = [[a[r] - d[r], b[r] - d[r], c[r] - d[r]] for r in range(3)]
    return (m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]))


def numbers(text):
    return [float(x) for x in re.findall(r"-?\d+(?:\.\d+)?(?:e-?\d+)?", text)]


def value_of(transcript, name):
    """The value printed by `print NAME` (`NAME = VALUE`)."""
    m = re.search(r"^" + re.escape(name) + r" = (.*)$", transcript, re.M)
    check(m is not None, "no '%s = ...' line" % name)
    return m.group(1) if m else ""


def endpoints(transcript, func):
    m = re.search(r"(?:map|apply) " + func + r" to tets, element (\d+), endpoints verts\[([\d ]+)\]",
                  transcript)
    check(m is not None, "no map line for " + func)
    return (int(m.group(1)), [int(x) for x in m.group(2).split()]) if m else (-1, [])


def fem_break(directory):
    points, tets = read_mesh(directory, "cube48")
    text = open(os.path.join(directory, "fem_break.expected")).read()
    element, ends = endpoints(text, "tet_force")
    check(element == 17, "the breakpoint stops on element 17, not %d" % element)
    check(ends == tets[17], "endpoints %s, mesh %s" % (ends, tets[17]))
    w = -edge_det(points, tets[17]) / 6.0
    check(close(numbers(value_of(text, "t.W"))[0], w), "t.W != rest volume %r" % w)
    x3 = numbers(value_of(text, "v(3).x"))
    check(all(close(x3[i], points[tets[17][3]][i]) for i in range(3)), "v(3).x != mesh position")
    # At the first frame's force evaluation the mesh is at rest: F = I.
    f = numbers(value_of(text, "F"))
    check(len(f) == 9 and all(close(f[i], 1.0 if i % 4 == 0 else 0.0, atol=1e-12) for i in range(9)),
          "F is not the identity")
    check(close(numbers(value_of(text, "det(F)"))[0], 1.0), "det(F) != 1")


def watch(directory):
    points, tets = read_mesh(directory, "cube48")
    text = open(os.path.join(directory, "watch.expected")).read()
    m = re.search(r"Watchpoint 1: tets.W\[17\]\nOld value = (.*)\nNew value = (.*)\n", text)
    check(m is not None, "no change of tets.W[17]")
    if m:
        check(float(m.group(1)) == 0.0, "W starts at zero")
        check(close(float(m.group(2)), -edge_det(points, tets[17]) / 6.0), "W[17] != rest volume")
    m = re.search(r"Watchpoint 2: verts.x\[7\]\nOld value = (.*)\n", text)
    check(m is not None, "no change of verts.x[7]")
    if m:
        old = numbers(m.group(1))
        check(all(close(old[i], points[7][i]) for i in range(3)), "old x[7] != mesh position")


def nan_trap(directory):
    points, tets = read_mesh(directory, "cube48_flipped")
    in_file = [e for e, t in tets.items() if edge_det(points, t) > 0]
    check(in_file == [29], "the flipped mesh inverts %s, not tet 29" % in_file)
    # The scene orients the tets as it reads them (the first two vertices of an inverted one
    # swapped), then the step pushes the centre vertex (13) by -0.15 along (1, 1, 1).
    for t in tets.values():
        if edge_det(points, t) > 0:
            t[0], t[1] = t[1], t[0]
    points[13] = tuple(c - 0.15 for c in points[13])
    inverted = sorted(e for e, t in tets.items() if edge_det(points, t) > 0)
    text = open(os.path.join(directory, "nan_trap.expected")).read()
    element, ends = endpoints(text, "energy")
    check(inverted and element == inverted[0],
          "the NaN trap names tet %d, the first inverted is %s" % (element, inverted[:1]))
    if inverted:
        t = tets[inverted[0]]
        check(ends == t, "endpoints %s, mesh %s" % (ends, t))
        j = edge_det(points, t)
        check(close(numbers(value_of(text, "J"))[0], j), "J != det of the inverted tet")
        check(close(numbers(value_of(text, "t.vol"))[0], -j / 6.0), "t.vol != -J/6")
        check(value_of(text, "v(0)") == "verts[%d]" % t[0], "v(0) is not the first endpoint")
    check(re.search(r"^NaN trap \(breakpoint 1\): t\.e = nan$", text, re.M) is not None,
          "the trap does not report t.e = nan")


def main():
    directory = sys.argv[1]
    fem_break(directory)
    watch(directory)
    nan_trap(directory)
    for f in FAILURES:
        print("FAIL: " + f)
    sys.exit(1 if FAILURES else 0)


main()
