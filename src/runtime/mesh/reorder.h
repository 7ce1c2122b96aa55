// Renumbering a mesh for locality: the vertex graph its elements imply, a vertex order by
// reverse Cuthill-McKee or by a Hilbert curve through the positions, and the elements sorted
// by their smallest new vertex. Pure functions on index arrays.
//
// An order is given as `order[new] = old`; its inverse, `position[old] = new`.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "runtime/mesh/mesh.h"

namespace simit::runtime {

// The vertices adjacent to vertex v are neighbours[offsets[v] .. offsets[v + 1]), ascending,
// without v itself and without repeats.
struct VertexGraph {
  std::vector<int64_t> offsets;  // vertices() + 1 entries
  std::vector<int32_t> neighbours;
  int32_t vertices() const { return static_cast<int32_t>(offsets.size()) - 1; }
  int32_t degree(int32_t v) const { return static_cast<int32_t>(offsets[v + 1] - offsets[v]); }
};

// One list of elements: `arity` vertex indices per element, each in [0, vertices).
struct ElementList {
  std::span<const int32_t> indices;
  int arity = 0;
};

// Every two distinct vertices of an element are adjacent. Throws MeshError on an index out of
// range or an arity below 1.
VertexGraph vertex_graph(int32_t vertices, std::span<const ElementList> lists);

// Reverse Cuthill-McKee: each connected component from a pseudo-peripheral vertex (George and
// Liu's search), in breadth-first order with each vertex's unnumbered neighbours by increasing
// degree (then index), the whole order reversed. Deterministic. The identity for a graph with
// no edges, whose order it could not improve.
std::vector<int32_t> reverse_cuthill_mckee(const VertexGraph& graph);

// The points in the order a 3-D Hilbert curve visits them, the bounding box scaled alike on
// every axis onto a 2^21 lattice; ties (points in one lattice cell) keep their index order.
std::vector<int32_t> hilbert_order(std::span<const Point> points);

// The inverse permutation. Throws MeshError when `order` is not a permutation of 0..n-1.
std::vector<int32_t> invert_permutation(std::span<const int32_t> order);

// The order a scene renumbers `m`'s vertices in for locality: reverse Cuthill-McKee over the
// graph of its tets, triangles and edges, or the Hilbert curve through its points (`hilbert`).
// Empty where the mesh keeps its own order: a mesh of points alone (no neighbours to bring
// together), or an order that is the identity.
std::vector<int32_t> locality_order(const Mesh& m, bool hilbert);

// max |position[u] - position[v]| over the graph's edges (0 for none): the bandwidth of the
// adjacency matrix with the vertices renumbered by `position` (old -> new).
int64_t bandwidth(const VertexGraph& graph, std::span<const int32_t> position);

// The elements of `list` sorted by their smallest vertex under `position` (old -> new), equal
// ones in their old order: the element order (new -> old). Throws MeshError on an index out
// of range.
std::vector<int32_t> element_order(const ElementList& list, std::span<const int32_t> position);

// The elements of `list` in the element order `order` (new -> old), each vertex index `v`
// replaced by position[v] and the vertex order within an element kept. Throws MeshError when
// `order` does not fit the list or an index is out of range.
std::vector<int32_t> renumber_elements(const ElementList& list, std::span<const int32_t> order,
                                       std::span<const int32_t> position);

}  // namespace simit::runtime
