// Element sets derived from a mesh: the unique edges of tets or triangles, the boundary
// triangles of a tet mesh, and the hinges (triangle pairs across an edge) of a surface.
#pragma once

#include <array>
#include <vector>

#include "runtime/mesh/mesh.h"

namespace simit::runtime {

// Each edge once as (lo, hi) with lo < hi, sorted lexicographically, so the same mesh always
// gives the same edge set in the same order.
std::vector<Edge> tet_edges(const std::vector<Tet>& tets);
std::vector<Edge> triangle_edges(const std::vector<Triangle>& triangles);

// The faces that belong to exactly one tet, ordered by tet index and then by the local face
// order (1 2 3), (0 3 2), (0 1 3), (0 2 1), each wound so that (b-a) x (c-a) points out of
// its tet; a tet whose orientation determinant is positive has its faces reversed, so mixed
// orientations still give outward faces. Throws MeshError if an index is out of range or
// three or more tets share a face.
std::vector<Triangle> boundary_triangles(const Mesh& mesh);

// A hinge [a, b, c, d] is a pair of triangles sharing the interior edge a-b: the first, of
// lower index, is (a, b, c) up to rotation of its own winding, and the second is (b, a, d),
// which a consistently oriented surface traverses the other way. Both normals, (b-a) x (c-a)
// and (a-b) x (d-b), then point to the same side, as discrete-shells bending needs. Sorted by
// the edge (min(a,b), max(a,b)); boundary edges give no hinge. Throws MeshError when two
// triangles traverse their shared edge the same way (the surface is not consistently
// oriented), when three or more share an edge, or when a triangle repeats a vertex.
using Hinge = std::array<int, 4>;
std::vector<Hinge> hinges(const std::vector<Triangle>& triangles);

}  // namespace simit::runtime
