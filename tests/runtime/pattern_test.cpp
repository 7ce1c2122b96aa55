// Sparsity patterns (LANGUAGE.md §8.5.5, §8.7): construction for every kind of set, the
// assembly index, sharing through the registry, and memory accounting.
#include <gtest/gtest.h>

#include <set>
#include <utility>

#include "runtime/system_matrix.h"
#include "runtime/system_ops.h"
#include "runtime_fixtures.h"

namespace simit::runtime {
namespace {

using testing::build_cube_tets;
using testing::members_of;
using Pairs = std::set<std::pair<int, int>>;

// The pattern straight from the definition: all member pairs of every element.
Pairs expected_pairs(const Set& edges, const Set& rows, const Set& cols) {
  Pairs out;
  for (int e = 0; e < edges.size(); ++e)
    for (int r : members_of(edges, rows))
      for (int c : members_of(edges, cols))
        out.emplace(member_element(edges, e, r), member_element(edges, e, c));
  return out;
}

Pairs pattern_pairs(const MatrixPattern& p) {
  Pairs out;
  for (int r = 0; r < p.rows(); ++r)
    for (int32_t k = p.row_ptr()[r]; k < p.row_ptr()[r + 1]; ++k) out.emplace(r, p.col_idx()[k]);
  return out;
}

// Checks the pattern against the definition and every assembly-index entry against find().
void check_pattern(const Set& edges, const Set& rows, const Set& cols) {
  PatternPtr p = MatrixPattern::assembled(edges, rows, cols);
  ASSERT_EQ(p->rows(), rows.size());
  ASSERT_EQ(p->cols(), cols.size());
  EXPECT_TRUE(p->canonical());
  EXPECT_EQ(pattern_pairs(*p), expected_pairs(edges, rows, cols));
  EXPECT_EQ(static_cast<size_t>(p->nnz()), expected_pairs(edges, rows, cols).size());
  const AssemblyIndex& ix = p->assembly();
  EXPECT_EQ(ix.row_members, members_of(edges, rows));
  EXPECT_EQ(ix.col_members, members_of(edges, cols));
  for (int e = 0; e < edges.size(); ++e)
    for (size_t i = 0; i < ix.row_members.size(); ++i)
      for (size_t j = 0; j < ix.col_members.size(); ++j) {
        const int r = member_element(edges, e, ix.row_members[i]);
        const int c = member_element(edges, e, ix.col_members[j]);
        EXPECT_EQ(ix.position(e, static_cast<int>(i), static_cast<int>(j)), p->find(r, c));
        EXPECT_EQ(p->assembly_position(edges, e, r, c), p->find(r, c));
      }
}

TEST(Pattern, VertexSetGivesTheDiagonal) {
  Set nodes("nodes");
  nodes.add_many(5);
  PatternPtr p = MatrixPattern::assembled(nodes, nodes, nodes);
  EXPECT_EQ(p->nnz(), 5);
  for (int i = 0; i < 5; ++i) {
    EXPECT_EQ(p->find(i, i), i);
    EXPECT_EQ(p->assembly().position(i, 0, 0), i);
  }
  EXPECT_EQ(p->find(0, 1), -1);
  check_pattern(nodes, nodes, nodes);
}

TEST(Pattern, BinaryEdgesOnAPathAreTridiagonal) {
  Set nodes("nodes");
  nodes.add_many(6);
  Set links("links", {&nodes, &nodes});
  for (int i = 0; i + 1 < 6; ++i) links.add({i, i + 1});
  PatternPtr p = MatrixPattern::assembled(links, nodes, nodes);
  EXPECT_EQ(p->nnz(), 3 * 6 - 2);
  EXPECT_EQ(p->row_ptr(), (std::vector<int32_t>{0, 2, 5, 8, 11, 14, 16}));
  EXPECT_EQ(p->col_idx()[2], 0);
  EXPECT_EQ(p->col_idx()[3], 1);
  EXPECT_EQ(p->col_idx()[4], 2);
  check_pattern(links, nodes, nodes);
}

TEST(Pattern, EdgeToVertexAndVertexToEdge) {
  Set nodes("nodes");
  nodes.add_many(4);
  Set links("links", {&nodes, &nodes});
  links.add({0, 1});
  links.add({1, 3});
  links.add({2, 2});  // both endpoints the same node
  PatternPtr ev = MatrixPattern::assembled(links, links, nodes);
  EXPECT_EQ(pattern_pairs(*ev), (Pairs{{0, 0}, {0, 1}, {1, 1}, {1, 3}, {2, 2}}));
  PatternPtr ve = MatrixPattern::assembled(links, nodes, links);
  EXPECT_EQ(pattern_pairs(*ve), (Pairs{{0, 0}, {1, 0}, {1, 1}, {3, 1}, {2, 2}}));
  PatternPtr ee = MatrixPattern::assembled(links, links, links);
  EXPECT_EQ(pattern_pairs(*ee), (Pairs{{0, 0}, {1, 1}, {2, 2}}));
  check_pattern(links, links, nodes);
  check_pattern(links, nodes, links);
  check_pattern(links, nodes, nodes);
}

TEST(Pattern, TernaryEdges) {
  Set verts("verts");
  verts.add_many(5);
  Set tris("tris", {&verts, &verts, &verts});
  tris.add({0, 1, 2});
  tris.add({2, 3, 4});
  tris.add({4, 1, 2});
  PatternPtr p = MatrixPattern::assembled(tris, verts, verts);
  EXPECT_EQ(p->find(0, 3), -1);
  EXPECT_GE(p->find(1, 4), 0);
  EXPECT_EQ(p->assembly().pairs(), 9u);
  check_pattern(tris, verts, verts);
  check_pattern(tris, tris, verts);
}

TEST(Pattern, FourAryEdgesOfATetMesh) {
  Set verts("verts");
  Set tets("tets", {&verts, &verts, &verts, &verts});
  build_cube_tets(2, verts, tets);
  EXPECT_EQ(tets.size(), 48);
  check_pattern(tets, verts, verts);
  check_pattern(tets, tets, verts);
  check_pattern(tets, verts, tets);
  PatternPtr p = MatrixPattern::assembled(tets, verts, verts);
  EXPECT_EQ(p->assembly().pairs(), 16u);
  // Vertex (0,0,0) shares a tet with (1,0,0), (1,1,0), (1,1,1), ... but not (2,0,0).
  EXPECT_GE(p->find(0, 1), 0);
  EXPECT_EQ(p->find(0, 2), -1);
}

TEST(Pattern, HeterogeneousEndpoints) {
  Set sensors("sensors"), cells("cells");
  sensors.add_many(3);
  cells.add_many(4);
  Set probes("probes", {&sensors, &cells});
  probes.add({0, 3});
  probes.add({2, 1});
  probes.add({0, 1});
  EXPECT_EQ(pattern_pairs(*MatrixPattern::assembled(probes, sensors, cells)),
            (Pairs{{0, 3}, {2, 1}, {0, 1}}));
  EXPECT_EQ(pattern_pairs(*MatrixPattern::assembled(probes, cells, sensors)),
            (Pairs{{3, 0}, {1, 2}, {1, 0}}));
  EXPECT_EQ(pattern_pairs(*MatrixPattern::assembled(probes, cells, cells)),
            (Pairs{{3, 3}, {1, 1}}));
  check_pattern(probes, sensors, cells);
  check_pattern(probes, probes, cells);
  check_pattern(probes, sensors, sensors);
}

TEST(Pattern, EndpointsInAnEdgeSet) {
  Set verts("verts");
  verts.add_many(4);
  Set edges("edges", {&verts, &verts});
  edges.add({0, 1});
  edges.add({1, 2});
  edges.add({2, 0});
  Set faces("faces", {&edges, &edges, &edges});
  faces.add({0, 1, 2});
  check_pattern(faces, edges, edges);
  check_pattern(faces, faces, edges);
  EXPECT_EQ(MatrixPattern::assembled(faces, verts, verts)->nnz(), 0);
}

TEST(Pattern, EmptySets) {
  Set verts("verts");
  verts.add_many(3);
  Set none("none", {&verts, &verts});
  PatternPtr p = MatrixPattern::assembled(none, verts, verts);
  EXPECT_EQ(p->nnz(), 0);
  EXPECT_EQ(p->row_ptr(), (std::vector<int32_t>{0, 0, 0, 0}));
  Set empty("empty");
  EXPECT_EQ(MatrixPattern::assembled(empty, empty, empty)->rows(), 0);
}

TEST(Pattern, AssemblyPositionRejectsPairsOutsideTheElement) {
  Set nodes("nodes");
  nodes.add_many(3);
  Set links("links", {&nodes, &nodes});
  links.add({0, 1});
  links.add({1, 2});
  PatternPtr p = MatrixPattern::assembled(links, nodes, nodes);
  EXPECT_EQ(p->assembly_position(links, 0, 1, 2), -1);  // (1, 2) is in the pattern, not in edge 0
  EXPECT_GE(p->assembly_position(links, 1, 1, 2), 0);
  EXPECT_THROW(p->assembly_position(nodes, 0, 0, 0), Fault);
}

TEST(Registry, OnePatternSharedByEveryMatrixThroughAnEdgeSet) {
  Set verts("verts");
  Set tets("tets", {&verts, &verts, &verts, &verts});
  build_cube_tets(2, verts, tets);
  PatternRegistry registry;
  SystemMatrix stiffness(registry.assembled(tets, verts, verts), 3, 3);
  SystemMatrix damping(registry.assembled(tets, verts, verts), 3, 3);
  SystemMatrix scalar(registry.assembled(tets, verts, verts), 1, 1);
  EXPECT_EQ(registry.builds(), 1);
  EXPECT_EQ(&stiffness.pattern(), &damping.pattern());
  EXPECT_EQ(&stiffness.pattern(), &scalar.pattern());
  EXPECT_EQ(stiffness.shared_pattern().use_count(), 4);  // three matrices and the registry
  registry.assembled(tets, tets, verts);
  EXPECT_EQ(registry.builds(), 2);
}

TEST(Registry, RebuildsWhenTheTopologyChanges) {
  Set nodes("nodes");
  nodes.add_many(3);
  Set links("links", {&nodes, &nodes});
  links.add({0, 1});
  PatternRegistry registry;
  SystemMatrix before(registry.assembled(links, nodes, nodes));
  links.add({1, 2});
  PatternPtr after = registry.assembled(links, nodes, nodes);
  EXPECT_EQ(registry.builds(), 2);
  EXPECT_NE(after.get(), &before.pattern());
  EXPECT_EQ(before.pattern().nnz(), 4);  // the old matrix keeps its pattern alive
  EXPECT_EQ(after->nnz(), 7);
  nodes.add();
  EXPECT_EQ(registry.assembled(links, nodes, nodes)->rows(), 4);
  EXPECT_EQ(registry.builds(), 3);
}

TEST(Memory, MatrixBytesAreValuesPlusOnceCountedPattern) {
  Set verts("verts");
  Set tets("tets", {&verts, &verts, &verts, &verts});
  build_cube_tets(3, verts, tets);
  PatternRegistry registry;
  SystemMatrix a(registry.assembled(tets, verts, verts), 3, 3);
  SystemMatrix b(registry.assembled(tets, verts, verts), 3, 3);
  const MatrixPattern& p = a.pattern();
  EXPECT_EQ(a.value_bytes(), static_cast<size_t>(p.nnz()) * 9 * sizeof(double));
  // The CSR index: one int per block and one per row (plus the closing row pointer).
  EXPECT_EQ(p.index_bytes(), (static_cast<size_t>(p.nnz()) + verts.size() + 1) * sizeof(int32_t));
  EXPECT_EQ(p.assembly_bytes(), static_cast<size_t>(tets.size()) * 16 * sizeof(int32_t));
  const SystemMatrix* both[] = {&a, &b};
  EXPECT_EQ(memory_bytes(both), a.value_bytes() + b.value_bytes() + p.bytes());
  const SystemMatrix* one[] = {&a};
  EXPECT_EQ(memory_bytes(one), a.value_bytes() + p.bytes());
  // A matrix object holds its values and a pointer to the pattern, nothing per block besides.
  EXPECT_EQ(a.value_count(), static_cast<size_t>(p.nnz()) * 9);
}

TEST(Pattern, UnionAndTranspose) {
  Set nodes("nodes");
  nodes.add_many(4);
  Set a_links("a", {&nodes, &nodes});
  a_links.add({0, 1});
  Set b_links("b", {&nodes, &nodes});
  b_links.add({2, 3});
  b_links.add({1, 0});
  PatternPtr a = MatrixPattern::assembled(a_links, nodes, nodes);
  PatternPtr b = MatrixPattern::assembled(b_links, nodes, nodes);
  PatternUnion u = unite(*a, *b);
  Pairs both = pattern_pairs(*a);
  for (auto pr : pattern_pairs(*b)) both.insert(pr);
  EXPECT_EQ(pattern_pairs(*u.pattern), both);
  for (int r = 0; r < 4; ++r)
    for (int32_t k = b->row_ptr()[r]; k < b->row_ptr()[r + 1]; ++k)
      EXPECT_EQ(u.from_b[k], u.pattern->find(r, b->col_idx()[k]));
  Set probes_rows("rows");
  probes_rows.add_many(2);
  Set probes("probes", {&probes_rows, &nodes});
  probes.add({1, 3});
  PatternPtr rect = MatrixPattern::assembled(probes, probes_rows, nodes);
  PatternTranspose t = transpose(*rect);
  EXPECT_EQ(t.pattern->rows(), 4);
  EXPECT_EQ(t.pattern->cols(), 2);
  EXPECT_EQ(pattern_pairs(*t.pattern), (Pairs{{3, 1}}));
  EXPECT_THROW(unite(*a, *rect), Fault);
}

TEST(Pattern, StencilKeepsOneEntryPerOffset) {
  Set points("points");
  Set grid("links", points, {3, 2});
  const std::vector<std::vector<int>> offsets = {{0, 0}, {0, 1}, {0, -1}, {1, 0}};
  PatternPtr p = MatrixPattern::stencil(grid, offsets);
  EXPECT_EQ(p->nnz(), 6 * 4);
  EXPECT_FALSE(p->canonical());  // offsets (0, 1) and (0, -1) wrap to one point
  for (int pt = 0; pt < 6; ++pt)
    for (size_t j = 0; j < offsets.size(); ++j)
      EXPECT_EQ(p->col_idx()[p->row_ptr()[pt] + j], grid.grid_point_at(pt, offsets[j]));
  // The spec's example: K(p, P[0,1]) = 2 and K(p, P[0,-1]) = 5 read as 7 at column q.
  SystemMatrix k(p);
  const int pt = 0, q = grid.grid_point_at(0, std::vector<int>{0, 1});
  k.block(p->row_ptr()[pt] + 1)[0] = 2.0;
  k.block(p->row_ptr()[pt] + 2)[0] = 5.0;
  EXPECT_EQ(k.component(pt, q), 7.0);
  PatternUnion u = unite(*p, *p);
  EXPECT_TRUE(u.pattern->canonical());
  EXPECT_EQ(u.from_a[p->row_ptr()[pt] + 1], u.from_a[p->row_ptr()[pt] + 2]);
}

TEST(Registry, StencilPatternsAreCachedPerOffsets) {
  Set points("points");
  Set grid("links", points, {4});
  PatternRegistry registry;
  PatternPtr a = registry.stencil(grid, {{0}, {1}, {-1}});
  PatternPtr b = registry.stencil(grid, {{0}, {1}, {-1}});
  PatternPtr c = registry.stencil(grid, {{0}, {1}});
  EXPECT_EQ(a, b);
  EXPECT_NE(a, c);
  EXPECT_EQ(registry.builds(), 2);
  EXPECT_THROW(registry.stencil(points, {{0}}), Fault);
}

TEST(Pattern, FromCsrValidates) {
  EXPECT_THROW(MatrixPattern::from_csr(2, 2, {0, 1}, {0}), Fault);
  EXPECT_THROW(MatrixPattern::from_csr(2, 2, {0, 1, 2}, {0, 2}), Fault);
  EXPECT_THROW(MatrixPattern::from_csr(2, 2, {0, 2, 1}, {0}), Fault);
  PatternPtr ok = MatrixPattern::from_csr(2, 3, {0, 2, 3}, {0, 2, 1});
  EXPECT_TRUE(ok->canonical());
  EXPECT_EQ(ok->find(0, 2), 1);
  EXPECT_THROW(ok->find(2, 0), Fault);
  EXPECT_FALSE(MatrixPattern::from_csr(1, 3, {0, 2}, {2, 1})->canonical());
}

// Mesh axes: a pattern over a set with mesh numbers keeps them (a copy) for its rows and
// columns; unions, transposes and products pass them on; a set without them gives none.
TEST(MeshAxes, FollowTheRowAndColumnSets) {
  Set verts("verts"), tets("tets", {&verts, &verts, &verts, &verts});
  build_cube_tets(1, verts, tets);  // 8 vertices, 6 tets
  std::vector<int32_t> reversed(8);
  for (int e = 0; e < 8; ++e) reversed[e] = 7 - e;
  PatternRegistry registry;
  const PatternPtr vt = registry.assembled(tets, verts, tets);
  EXPECT_EQ(vt->row_axis(), nullptr);  // no mesh numbers yet
  verts.set_mesh_numbers(reversed);
  const PatternPtr p = MatrixPattern::assembled(tets, verts, tets);
  ASSERT_NE(p->row_axis(), nullptr);
  EXPECT_EQ(p->col_axis(), nullptr);  // tets keep their own numbers
  EXPECT_EQ(p->row_axis()->mesh_numbers, reversed);
  EXPECT_EQ(p->row_axis()->element(2), "element 5 of set 'verts'");
  // The transpose swaps them; the product P Pᵀ has P's rows on both sides.
  const PatternTranspose t = transpose(*p);
  EXPECT_EQ(t.pattern->row_axis(), nullptr);
  EXPECT_EQ(t.pattern->col_axis(), p->row_axis());
  SystemMatrix a(p), at(t.pattern);
  const SystemMatrix product = multiply(a, at);
  EXPECT_EQ(product.pattern().row_axis(), p->row_axis());
  EXPECT_EQ(product.pattern().col_axis(), p->row_axis());
  // A union takes the first operand's, or the second's where the first has none.
  const PatternPtr plain = MatrixPattern::from_csr(8, 8, std::vector<int32_t>(9, 0), {});
  const PatternUnion u = unite(*plain, product.pattern());
  EXPECT_EQ(u.pattern->row_axis(), p->row_axis());
  // An axis of another length is dropped.
  EXPECT_EQ(MatrixPattern::from_csr(2, 2, {0, 0, 0}, {}, p->row_axis())->row_axis(), nullptr);
}

}  // namespace
}  // namespace simit::runtime
