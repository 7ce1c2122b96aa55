// Mesh renumbering for locality (runtime/mesh/reorder.h): the vertex graph, reverse
// Cuthill-McKee on shuffled paths and grids, the Hilbert order of a lattice, inverse
// permutations, bandwidths and the elements sorted by their smallest new vertex.
#include "runtime/mesh/reorder.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <numeric>
#include <random>
#include <vector>

#include "runtime/set.h"

namespace simit::runtime {
namespace {

std::vector<int32_t> identity(int32_t n) {
  std::vector<int32_t> v(static_cast<size_t>(n));
  std::iota(v.begin(), v.end(), 0);
  return v;
}

// A random relabelling of 0..n-1 (fixed seed).
std::vector<int32_t> shuffled(int32_t n, unsigned seed) {
  std::vector<int32_t> v = identity(n);
  std::mt19937 rng(seed);
  std::shuffle(v.begin(), v.end(), rng);
  return v;
}

// The edges of an nx x ny grid of vertices (vertex i + nx j), each vertex relabelled by
// `label`: two indices per edge.
std::vector<int32_t> grid_edges(int nx, int ny, const std::vector<int32_t>& label) {
  std::vector<int32_t> e;
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const int v = i + nx * j;
      if (i + 1 < nx) e.insert(e.end(), {label[v], label[v + 1]});
      if (j + 1 < ny) e.insert(e.end(), {label[v], label[v + nx]});
    }
  return e;
}

VertexGraph graph_of(int32_t n, const std::vector<int32_t>& flat, int arity) {
  const ElementList lists[] = {{flat, arity}};
  return vertex_graph(n, lists);
}

std::vector<int32_t> neighbours(const VertexGraph& g, int32_t v) {
  return {g.neighbours.begin() + g.offsets[v], g.neighbours.begin() + g.offsets[v + 1]};
}

TEST(MeshReorder, TheVertexGraphJoinsTheVerticesOfEachElement) {
  // Two tets sharing the face 1 2 3, a triangle repeating a vertex, and vertex 6 alone.
  const std::vector<int32_t> tets = {0, 1, 2, 3, 1, 2, 3, 4};
  const std::vector<int32_t> triangles = {4, 5, 5};
  const ElementList lists[] = {{tets, 4}, {triangles, 3}};
  const VertexGraph g = vertex_graph(7, lists);
  ASSERT_EQ(g.vertices(), 7);
  EXPECT_EQ(neighbours(g, 0), (std::vector<int32_t>{1, 2, 3}));
  EXPECT_EQ(neighbours(g, 1), (std::vector<int32_t>{0, 2, 3, 4}));
  EXPECT_EQ(neighbours(g, 3), (std::vector<int32_t>{0, 1, 2, 4}));
  EXPECT_EQ(neighbours(g, 4), (std::vector<int32_t>{1, 2, 3, 5}));
  EXPECT_EQ(neighbours(g, 5), (std::vector<int32_t>{4}));
  EXPECT_TRUE(neighbours(g, 6).empty());
  EXPECT_EQ(g.degree(1), 4);
}

TEST(MeshReorder, BadElementListsAreErrors) {
  const std::vector<int32_t> out_of_range = {0, 1, 2, 9};
  EXPECT_THROW(graph_of(4, out_of_range, 4), MeshError);
  const std::vector<int32_t> negative = {0, -1};
  EXPECT_THROW(graph_of(4, negative, 2), MeshError);
  const std::vector<int32_t> ragged = {0, 1, 2};
  EXPECT_THROW(graph_of(4, ragged, 2), MeshError);
  EXPECT_THROW(graph_of(4, ragged, 0), MeshError);
  const std::vector<int32_t> position = {0, 1};
  EXPECT_THROW(element_order({out_of_range, 4}, position), MeshError);
  const std::vector<int32_t> bad_order = {1};
  const std::vector<int32_t> one_edge = {0, 1};
  EXPECT_THROW(renumber_elements({one_edge, 2}, bad_order, position), MeshError);
}

TEST(MeshReorder, InversePermutations) {
  const std::vector<int32_t> order = shuffled(50, 7);
  const std::vector<int32_t> position = invert_permutation(order);
  for (int32_t i = 0; i < 50; ++i) {
    EXPECT_EQ(position[order[i]], i);
    EXPECT_EQ(order[position[i]], i);
  }
  EXPECT_THROW(invert_permutation(std::vector<int32_t>{0, 2, 2}), MeshError);
  EXPECT_THROW(invert_permutation(std::vector<int32_t>{0, 3, 1}), MeshError);
  EXPECT_THROW(invert_permutation(std::vector<int32_t>{-1, 0}), MeshError);
  EXPECT_TRUE(invert_permutation(std::vector<int32_t>{}).empty());
}

TEST(MeshReorder, BandwidthIsTheLongestEdgeInTheNewNumbers) {
  // The path 0-1-2-3 numbered 0 3 1 2: the edges span 3, 2 and 1.
  const std::vector<int32_t> path = {0, 1, 1, 2, 2, 3};
  const VertexGraph g = graph_of(4, path, 2);
  EXPECT_EQ(bandwidth(g, identity(4)), 1);
  EXPECT_EQ(bandwidth(g, std::vector<int32_t>{0, 3, 1, 2}), 3);
  EXPECT_EQ(bandwidth(graph_of(3, {}, 2), identity(3)), 0);
}

TEST(MeshReorder, RcmNumbersAShuffledPathInARow) {
  const int32_t n = 200;
  const std::vector<int32_t> label = shuffled(n, 11);
  std::vector<int32_t> edges;
  for (int32_t i = 0; i + 1 < n; ++i) edges.insert(edges.end(), {label[i], label[i + 1]});
  const VertexGraph g = graph_of(n, edges, 2);
  ASSERT_GT(bandwidth(g, identity(n)), 100);
  const std::vector<int32_t> order = reverse_cuthill_mckee(g);
  ASSERT_EQ(order.size(), static_cast<size_t>(n));
  const std::vector<int32_t> position = invert_permutation(order);  // throws unless a permutation
  EXPECT_EQ(bandwidth(g, position), 1);
  // It starts at an end of the path (a peripheral vertex): label[0] or label[n - 1].
  EXPECT_TRUE(order.front() == label[0] || order.front() == label[n - 1]) << order.front();
}

TEST(MeshReorder, RcmReducesTheBandwidthOfAShuffledGrid) {
  const int nx = 20, ny = 30, n = nx * ny;
  const std::vector<int32_t> edges = grid_edges(nx, ny, shuffled(n, 3));
  const VertexGraph g = graph_of(n, edges, 2);
  const int64_t before = bandwidth(g, identity(n));
  const std::vector<int32_t> position = invert_permutation(reverse_cuthill_mckee(g));
  const int64_t after = bandwidth(g, position);
  // The grid's own row-by-row numbering has bandwidth nx = 20; Cuthill-McKee's level sets
  // (anti-diagonals from a corner, at most 20 wide) bound it by 2 * 20 - 1.
  EXPECT_GT(before, 400);
  EXPECT_LE(after, 2 * nx - 1);
  EXPECT_GE(after, nx);  // no numbering of a 20 x 30 grid does better than 20
}

TEST(MeshReorder, RcmKeepsEachComponentTogether) {
  // Two shuffled paths of 30 vertices and three isolated vertices.
  const int32_t n = 63;
  const std::vector<int32_t> label = shuffled(n, 5);
  std::vector<int32_t> edges;
  for (int32_t i = 0; i + 1 < 30; ++i) {
    edges.insert(edges.end(), {label[i], label[i + 1]});
    edges.insert(edges.end(), {label[30 + i], label[31 + i]});
  }
  const VertexGraph g = graph_of(n, edges, 2);
  const std::vector<int32_t> order = reverse_cuthill_mckee(g);
  const std::vector<int32_t> position = invert_permutation(order);
  EXPECT_EQ(bandwidth(g, position), 1);
  std::vector<int32_t> first(label.begin(), label.begin() + 30);
  std::vector<int32_t> where;
  for (int32_t v : first) where.push_back(position[v]);
  std::sort(where.begin(), where.end());
  EXPECT_EQ(where.back() - where.front(), 29);  // one run of 30 consecutive numbers
}

TEST(MeshReorder, WithoutEdgesTheOrderIsKept) {
  EXPECT_EQ(reverse_cuthill_mckee(graph_of(5, {}, 2)), identity(5));
  EXPECT_TRUE(reverse_cuthill_mckee(graph_of(0, {}, 2)).empty());
}

TEST(MeshReorder, TheHilbertOrderStepsBetweenNeighbouringLatticePoints) {
  // An 8 x 8 x 8 lattice (spacing 0.5), listed in a shuffled order: each lattice point lies in
  // its own cell of the curve's level-3 subdivision, whose order moves to a face neighbour
  // at every step.
  const int side = 8, n = side * side * side;
  const std::vector<int32_t> label = shuffled(n, 9);
  std::vector<Point> points(n);
  for (int k = 0; k < side; ++k)
    for (int j = 0; j < side; ++j)
      for (int i = 0; i < side; ++i)
        points[label[i + side * (j + side * k)]] = {0.5 * i, 0.5 * j, 0.5 * k};
  const std::vector<int32_t> order = hilbert_order(points);
  invert_permutation(order);  // throws unless a permutation
  ASSERT_EQ(order.size(), static_cast<size_t>(n));
  for (int s = 0; s + 1 < n; ++s) {
    const Point& a = points[order[s]];
    const Point& b = points[order[s + 1]];
    const double steps =
        (std::abs(a[0] - b[0]) + std::abs(a[1] - b[1]) + std::abs(a[2] - b[2])) / 0.5;
    EXPECT_EQ(steps, 1.0) << "step " << s;
  }
  // A lattice corner starts the curve.
  EXPECT_EQ(points[order.front()], (Point{0, 0, 0}));
}

TEST(MeshReorder, TheHilbertOrderOfCoincidentPointsIsTheirs) {
  const std::vector<Point> same(4, Point{1, 2, 3});
  EXPECT_EQ(hilbert_order(same), identity(4));
  EXPECT_TRUE(hilbert_order(std::vector<Point>{}).empty());
}

TEST(MeshReorder, ElementsBySmallestNewVertexStable) {
  // New numbers of the old vertices 0..5.
  const std::vector<int32_t> position = {5, 3, 0, 4, 1, 2};
  // Smallest new vertex of each triangle: 0 (via 2), 3, 1, 0, 2, 1.
  const std::vector<int32_t> triangles = {0, 1, 2, 1, 3, 0, 4, 0, 3, 2, 5, 4, 5, 1, 3, 3, 4, 1};
  const ElementList list{triangles, 3};
  const std::vector<int32_t> order = element_order(list, position);
  EXPECT_EQ(order, (std::vector<int32_t>{0, 3, 2, 5, 4, 1}));
  const std::vector<int32_t> renumbered = renumber_elements(list, order, position);
  EXPECT_EQ(renumbered,
            (std::vector<int32_t>{5, 3, 0, 0, 2, 1, 1, 5, 4, 4, 1, 3, 2, 3, 4, 3, 4, 5}));
}

TEST(MeshReorder, SetsKeepTheirMeshNumbers) {
  Set verts("verts");
  verts.add_many(4);
  EXPECT_FALSE(verts.has_mesh_numbers());
  EXPECT_EQ(verts.mesh_number(3), 3);
  verts.set_mesh_numbers({2, 0, 3, 1});
  EXPECT_TRUE(verts.has_mesh_numbers());
  EXPECT_EQ(verts.mesh_number(0), 2);
  EXPECT_EQ(verts.mesh_number(3), 1);
  EXPECT_EQ(verts.add(), 4);  // added later: its own number
  EXPECT_EQ(verts.mesh_number(4), 4);
  Set other("other");
  other.add_many(3);
  EXPECT_THROW(other.set_mesh_numbers({0, 1}), Fault);
  EXPECT_THROW(other.set_mesh_numbers({0, 1, 1}), Fault);
  EXPECT_THROW(other.set_mesh_numbers({0, 1, 3}), Fault);
  EXPECT_FALSE(other.has_mesh_numbers());
}

}  // namespace
}  // namespace simit::runtime
