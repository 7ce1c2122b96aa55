// Sets: elements, struct-of-arrays fields, endpoints, grid numbering and the errors for misuse.
#include "runtime/set.h"

#include <gtest/gtest.h>

namespace simit::runtime {
namespace {

FieldType float_field(std::vector<int> dims = {}) { return {ComponentKind::Float, dims, false}; }

Tensor vec3(double a, double b, double c) {
  Tensor t(ComponentKind::Float, Shape{3});
  t.mutable_floats()[0] = a;
  t.mutable_floats()[1] = b;
  t.mutable_floats()[2] = c;
  return t;
}

template <class F>
std::string fault_message(F f) {
  try {
    f();
  } catch (const Fault& e) {
    return e.what();
  }
  return "(no fault)";
}

TEST(Set, AddsElementsInOrder) {
  Set nodes("nodes");
  EXPECT_EQ(nodes.kind(), SetKind::Vertex);
  EXPECT_EQ(nodes.add(), 0);
  EXPECT_EQ(nodes.add(), 1);
  EXPECT_EQ(nodes.add_many(3), 2);
  EXPECT_EQ(nodes.size(), 5);
  EXPECT_EQ(nodes.arity(), 0);
}

TEST(Set, FieldsAreContiguousPerField) {
  Set nodes("nodes");
  const int x = nodes.add_field("x", float_field({3}));
  const int m = nodes.add_field("m", float_field());
  nodes.add_many(3);
  nodes.set(x, 1, vec3(1.0, 2.0, 3.0));
  nodes.field(m).data<double>()[2] = 7.5;
  const double* xs = nodes.field("x").data<double>();
  EXPECT_EQ(xs[0], 0.0);
  EXPECT_EQ(xs[3], 1.0);
  EXPECT_EQ(xs[4], 2.0);
  EXPECT_EQ(xs[5], 3.0);
  EXPECT_EQ(nodes.get(m, 2).floats()[0], 7.5);
  EXPECT_EQ(nodes.get(x, 1), vec3(1.0, 2.0, 3.0));
  EXPECT_EQ(nodes.field(x).at<double>(1)[2], 3.0);
  EXPECT_EQ(nodes.field_index("m"), m);
  EXPECT_EQ(nodes.field_index("nope"), -1);
}

TEST(Set, MatrixFieldsAreRowMajorPerElement) {
  Set cells("cells");
  const int f = cells.add_field("F", float_field({2, 3}));
  cells.add_many(2);
  Tensor v(ComponentKind::Float, Shape{2, 3});
  for (int i = 0; i < 6; ++i) v.mutable_floats()[i] = i + 1;
  cells.set(f, 1, v);
  const double* data = cells.field(f).data<double>();
  for (int i = 0; i < 6; ++i) EXPECT_EQ(data[6 + i], i + 1);
  EXPECT_EQ(cells.field(f).element_bytes(), 6 * sizeof(double));
}

TEST(Set, FieldAddedLaterStartsAtZeroAndGrows) {
  Set nodes("nodes");
  nodes.add_many(4);
  const int k = nodes.add_field("k", {ComponentKind::Int, {}, false});
  for (int i = 0; i < 4; ++i) EXPECT_EQ(nodes.field(k).data<int32_t>()[i], 0);
  nodes.field(k).data<int32_t>()[3] = 9;
  nodes.add_many(100);
  EXPECT_EQ(nodes.field(k).data<int32_t>()[3], 9);
  EXPECT_EQ(nodes.field(k).data<int32_t>()[103], 0);
}

TEST(Set, OtherComponentKinds) {
  Set s("s");
  const int b = s.add_field("b", {ComponentKind::Bool, {2}, false});
  const int c = s.add_field("c", {ComponentKind::Complex, {}, false});
  s.add();
  Tensor bv(ComponentKind::Bool, Shape{2});
  bv.mutable_bools()[1] = true;
  s.set(b, 0, bv);
  EXPECT_EQ(s.get(b, 0), bv);
  Tensor cv(ComponentKind::Complex, Shape());
  cv.mutable_complexes()[0] = Complex(1.0, -2.0);
  s.set(c, 0, cv);
  EXPECT_EQ(s.field(c).data<std::complex<double>>()[0], Complex(1.0, -2.0));
}

TEST(Set, Float32StorageRoundsAndReadsBackAsFloat) {
  Set s("s");
  const int f = s.add_field("f", {ComponentKind::Float, {3}, true});
  s.add();
  EXPECT_EQ(s.field(f).element_bytes(), 3 * sizeof(float));
  s.set(f, 0, vec3(0.1, 1.0, 2.5));
  EXPECT_EQ(s.field(f).data<float>()[0], 0.1f);
  const Tensor back = s.get(f, 0);
  EXPECT_EQ(back.kind(), ComponentKind::Float);
  EXPECT_EQ(back.floats()[0], static_cast<double>(0.1f));
  EXPECT_EQ(back.floats()[2], 2.5);
  EXPECT_NE(fault_message([&] { s.field(f).data<double>(); }).find("float32 3"), std::string::npos);
}

TEST(Set, FieldErrorsNameSetElementAndField) {
  Set nodes("nodes");
  const int x = nodes.add_field("x", float_field({3}));
  nodes.add_many(2);
  const std::string wrong_shape = fault_message([&] {
    nodes.set(x, 1, Tensor(ComponentKind::Float, Shape{2, 2}));
  });
  EXPECT_NE(wrong_shape.find("set 'nodes', element 1, field 'x'"), std::string::npos)
      << wrong_shape;
  EXPECT_NE(wrong_shape.find("float 3"), std::string::npos) << wrong_shape;
  const std::string wrong_kind =
      fault_message([&] { nodes.set(x, 0, Tensor(ComponentKind::Int, Shape{3})); });
  EXPECT_NE(wrong_kind.find("int 3"), std::string::npos) << wrong_kind;
  const std::string bad_element = fault_message([&] { nodes.get(x, 2); });
  EXPECT_NE(bad_element.find("set 'nodes' has no element 2"), std::string::npos) << bad_element;
  EXPECT_NE(bad_element.find("'x'"), std::string::npos) << bad_element;
  EXPECT_NE(fault_message([&] { nodes.field("v"); }).find("no field 'v'"), std::string::npos);
  EXPECT_NE(fault_message([&] { nodes.add_field("x", float_field()); }).find("already"),
            std::string::npos);
  EXPECT_NE(fault_message([&] { nodes.field(x).data<int32_t>(); }).find("'x'"), std::string::npos);
}

TEST(Set, RequireFieldChecksTypeByName) {
  Set nodes("nodes");
  nodes.add_field("x", float_field({3}));
  EXPECT_EQ(nodes.require_field("x", float_field({3})), 0);
  const std::string msg = fault_message([&] { nodes.require_field("x", float_field({2})); });
  EXPECT_NE(msg.find("field 'x' holds float 3 but float 2 is required"), std::string::npos) << msg;
  EXPECT_NE(fault_message([&] { nodes.require_field("y", float_field()); }).find("no field 'y'"),
            std::string::npos);
}

TEST(Set, EdgeEndpointsAreOneArray) {
  Set nodes("nodes");
  nodes.add_many(4);
  Set bars("bars", {&nodes, &nodes});
  EXPECT_EQ(bars.kind(), SetKind::Edge);
  EXPECT_EQ(bars.add({0, 1}), 0);
  EXPECT_EQ(bars.add({2, 1}), 1);
  const int32_t more[] = {3, 0, 3, 3};
  EXPECT_EQ(bars.add_edges(more), 2);
  EXPECT_EQ(bars.size(), 4);
  EXPECT_TRUE(bars.homogeneous());
  const int32_t expected[] = {0, 1, 2, 1, 3, 0, 3, 3};
  for (int i = 0; i < 8; ++i) EXPECT_EQ(bars.endpoints()[i], expected[i]);
  EXPECT_EQ(bars.endpoint(1, 0), 2);
  EXPECT_EQ(bars.endpoints_of(2)[1], 0);
}

TEST(Set, HeterogeneousAndNestedEndpoints) {
  Set sensors("sensors"), cells("cells");
  sensors.add_many(2);
  cells.add_many(3);
  Set probes("probes", {&sensors, &cells});
  probes.add({1, 2});
  EXPECT_FALSE(probes.homogeneous());
  EXPECT_EQ(&probes.endpoint_set(0), &sensors);
  EXPECT_EQ(&probes.endpoint_set(1), &cells);
  Set pairs("pairs", {&probes, &cells});  // endpoints in an edge set
  pairs.add({0, 0});
  EXPECT_EQ(pairs.endpoint(0, 0), 0);
  EXPECT_NE(fault_message([&] {
              pairs.add({1, 0});
            }).find("set 'probes' has 1 elements"),
            std::string::npos);
}

TEST(Set, EndpointErrorsNameSetElementAndEndpoint) {
  Set nodes("nodes");
  nodes.add_many(3);
  Set bars("bars", {&nodes, &nodes});
  bars.add({0, 1});
  const std::string msg = fault_message([&] { bars.add({2, 5}); });
  EXPECT_NE(msg.find("set 'bars', element 1: endpoint 1 is 5, but set 'nodes' has 3 elements"),
            std::string::npos)
      << msg;
  EXPECT_EQ(bars.size(), 1);  // nothing added
  EXPECT_NE(fault_message([&] { bars.add({0}); }).find("needs 2 endpoints"), std::string::npos);
  EXPECT_NE(fault_message([&] { bars.add(); }).find("edge set"), std::string::npos);
  const int32_t ragged[] = {0, 1, 2};
  EXPECT_NE(fault_message([&] { bars.add_edges(ragged); }).find("whole number"), std::string::npos);
  EXPECT_NE(fault_message([&] { nodes.add({1}); }).find("vertex set"), std::string::npos);
}

TEST(Set, TopologyVersionChangesOnGrowth) {
  Set a("a"), b("b");
  EXPECT_NE(a.id(), b.id());
  const uint64_t v = a.topology_version();
  a.add();
  EXPECT_NE(a.topology_version(), v);
  const uint64_t w = a.topology_version();
  a.add_field("f", float_field());
  EXPECT_EQ(a.topology_version(), w);
}

TEST(Grid, PointsAndLinksFollowTheNumbering) {
  Set points("points");
  Set grid("links", points, {3, 2});
  EXPECT_TRUE(grid.is_grid());
  EXPECT_EQ(points.size(), 6);
  EXPECT_EQ(grid.size(), 12);
  EXPECT_EQ(grid.dimensions(), 2);
  // Point k = c0 + 3 c1; link k belongs to point k / 2 along axis k % 2, running +1.
  for (int p = 0; p < 6; ++p) {
    const int c0 = p % 3, c1 = p / 3;
    EXPECT_EQ(grid.grid_coords(p), (std::vector<int>{c0, c1}));
    EXPECT_EQ(grid.endpoint(2 * p, 0), p);
    EXPECT_EQ(grid.endpoint(2 * p, 1), (c0 + 1) % 3 + 3 * c1);
    EXPECT_EQ(grid.endpoint(2 * p + 1, 0), p);
    EXPECT_EQ(grid.endpoint(2 * p + 1, 1), c0 + 3 * ((c1 + 1) % 2));
    EXPECT_EQ(grid.grid_link(p, 1), 2 * p + 1);
  }
}

TEST(Grid, OffsetsWrapPeriodically) {
  Set points("points");
  Set grid("links", points, {3, 2});
  const int p = grid.grid_point(std::vector<int>{0, 1});  // 3
  EXPECT_EQ(p, 3);
  EXPECT_EQ(grid.grid_point_at(p, std::vector<int>{-1, 0}), 5);
  EXPECT_EQ(grid.grid_point_at(p, std::vector<int>{1, 1}), 1);
  EXPECT_EQ(grid.grid_point_at(p, std::vector<int>{0, -1}),
            grid.grid_point_at(p, std::vector<int>{0, 1}));
  EXPECT_EQ(grid.grid_point(std::vector<int>{-4, 7}), 2 + 3 * 1);
}

TEST(Grid, LinkBetweenOffsetsStartsAtTheSmallerOne) {
  Set points("points");
  Set grid("links", points, {3, 2});
  const int p = 4;  // (1, 1)
  using V = std::vector<int>;
  EXPECT_EQ(grid.grid_link_between(p, V{0, 0}, V{1, 0}), 2 * 4 + 0);
  EXPECT_EQ(grid.grid_link_between(p, V{1, 0}, V{0, 0}), 2 * 4 + 0);
  EXPECT_EQ(grid.grid_link_between(p, V{0, 0}, V{-1, 0}), 2 * 3 + 0);  // owned by (0, 1)
  EXPECT_EQ(grid.grid_link_between(p, V{-1, 0}, V{0, 0}), 2 * 3 + 0);
  // Extent 2: g[0;1] and g[0;-1] join the same points but are different links.
  EXPECT_EQ(grid.grid_link_between(p, V{0, 0}, V{0, 1}), 2 * 4 + 1);
  EXPECT_EQ(grid.grid_link_between(p, V{0, 0}, V{0, -1}), 2 * 1 + 1);
  EXPECT_EQ(grid.grid_link_between(p, V{2, 0}, V{2, 1}), 2 * grid.grid_point(V{3, 1}) + 1);
  EXPECT_NE(fault_message([&] {
              grid.grid_link_between(p, V{0, 0}, V{1, 1});
            }).find("exactly one"),
            std::string::npos);
  EXPECT_NE(fault_message([&] {
              grid.grid_link_between(p, V{0, 0}, V{2, 0});
            }).find("by 1"),
            std::string::npos);
}

TEST(Grid, OneDimensionalAndThreeDimensional) {
  Set line_points("line");
  Set line("faces", line_points, {4});
  EXPECT_EQ(line.size(), 4);
  EXPECT_EQ(line.endpoint(3, 1), 0);
  Set cube_points("cube");
  Set cube("links", cube_points, {2, 3, 4});
  EXPECT_EQ(cube_points.size(), 24);
  EXPECT_EQ(cube.size(), 72);
  const int p = cube.grid_point(std::vector<int>{1, 2, 3});
  EXPECT_EQ(p, 1 + 2 * 2 + 6 * 3);
  EXPECT_EQ(cube.endpoint(3 * p + 2, 1), cube.grid_point(std::vector<int>{1, 2, 0}));
}

TEST(Grid, Misuse) {
  Set points("points");
  points.add();
  EXPECT_NE(fault_message([&] { Set g("g", points, {2}); }).find("empty vertex set"),
            std::string::npos);
  Set empty("empty");
  EXPECT_NE(fault_message([&] {
              Set g("g", empty, {2, 0});
            }).find("not positive"),
            std::string::npos);
  Set ok_points("ok");
  Set g("g", ok_points, {2, 2});
  EXPECT_NE(fault_message([&] { g.add({0, 1}); }).find("grid"), std::string::npos);
  Set plain("plain");
  EXPECT_NE(fault_message([&] { plain.grid_point(std::vector<int>{0}); }).find("not a grid"),
            std::string::npos);
}

}  // namespace
}  // namespace simit::runtime
