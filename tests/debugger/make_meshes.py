"""Writes the debugger tests' meshes: a 2x2x2 block of slightly perturbed cubes cut into 48
tetrahedra (TetGen cube48.node/.ele, every tet in TetGen's orientation, det[x0-x3, x1-x3, x2-x3] < 0),
and a copy (cube48_flipped.node/.ele) in which one tetrahedron (FLIPPED) is inverted by swapping two of its corners."""
import itertools
import math

N = 2          # cubes per axis
H = 0.1        # cube size
FLIPPED = 29   # the inverted tet of cube48_flipped.ele


def vertex(i, j, k):
    return (i * (N + 1) + j) * (N + 1) + k


def position(i, j, k):
    # Deterministic perturbation; the bottom layer (j = 0) stays at y = 0 (pinned there).
    x = i * H + 0.01 * math.sin(1.0 + i + 2 * j + 3 * k)
    y = j * H + (0.01 * math.cos(2.0 + 3 * i + j + k) if j > 0 else 0.0)
    z = k * H + 0.01 * math.sin(3.0 + 2 * i + j + 5 * k)
    return (x, y, z)


def det_edges(p, t):
    a, b, c, d = (p[v] for v in t)
    m = [[a[r] - d[r], b[r] - d[r], c[r] - d[r]] for r in range(3)]
    return (m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]))


def main():
    points = {}
    for i, j, k in itertools.product(range(N + 1), repeat=3):
        points[vertex(i, j, k)] = position(i, j, k)
    tets = []
    for i, j, k in itertools.product(range(N), repeat=3):
        for axes in itertools.permutations(range(3)):
            corner = [i, j, k]
            path = [vertex(*corner)]
            for a in axes:
                corner[a] += 1
                path.append(vertex(*corner))
            t = [path[0], path[1], path[2], path[3]]
            if det_edges(points, t) > 0:
                t[0], t[1] = t[1], t[0]
            tets.append(t)
    for name in ("cube48.node", "cube48_flipped.node"):
        with open(name, "w") as f:
            f.write(f"{len(points)}  3  0  0\n")
            for v in range(len(points)):
                f.write(f"{v}  {points[v][0]:.17g}  {points[v][1]:.17g}  {points[v][2]:.17g}\n")
    for name, flip in (("cube48.ele", None), ("cube48_flipped.ele", FLIPPED)):
        with open(name, "w") as f:
            f.write(f"{len(tets)}  4  0\n")
            for e, t in enumerate(tets):
                a, b, c, d = t
                if e == flip:
                    a, b = b, a
                f.write(f"{e}  {a}  {b}  {c}  {d}\n")


if __name__ == "__main__":
    main()
