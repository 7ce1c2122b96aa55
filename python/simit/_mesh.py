"""simit.Mesh: what simit.read_mesh returns."""


class Mesh:
    """A mesh file's contents: `points` (n, 3) float64, and `tets` (m, 4), `triangles`
    (m, 3), `edges` (m, 2) int32 arrays of 0-based vertex indices, or None where the file
    has none of them."""

    path = None
    points = None
    tets = None
    triangles = None
    edges = None

    def __repr__(self):
        parts = [f"{len(self.points)} points"]
        for name in ("tets", "triangles", "edges"):
            value = getattr(self, name)
            if value is not None:
                parts.append(f"{len(value)} {name}")
        return f"simit.Mesh({self.path!r}: {', '.join(parts)})"
