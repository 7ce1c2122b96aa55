// Host sets through the public API: elements, endpoints, grids and field round trips.
#include <gtest/gtest.h>

#include <sstream>

#include "api/set_access.h"
#include "api_test_util.h"
#include "simit/simit.h"

namespace {

using simit::testing::contains;

TEST(ApiSet, VertexSetElementsAndScalarFields) {
  simit::Set nodes("nodes");
  auto mass = nodes.add_field<double>("mass");
  auto id = nodes.add_field<int>("id");
  auto pinned = nodes.add_field<bool>("pinned");
  simit::ElementRef a = nodes.add(), b = nodes.add();
  EXPECT_EQ(nodes.size(), 2);
  EXPECT_EQ(nodes.cardinality(), 0);
  EXPECT_EQ(a.ident(), 0);
  EXPECT_EQ(b.ident(), 1);
  EXPECT_EQ(double(mass.get(a)), 0.0);  // fields start at zero
  mass.set(a, 2.5);
  mass(b) = 4.0;
  id.set(b, 7);
  pinned.set(a, true);
  EXPECT_EQ(double(mass(a)), 2.5);
  EXPECT_EQ(double(mass.get(b)), 4.0);
  EXPECT_EQ(int(id(b)), 7);
  EXPECT_TRUE(bool(pinned(a)));
  EXPECT_FALSE(bool(pinned(b)));
  // The handle reads and writes the set's own storage.
  EXPECT_EQ(static_cast<double*>(nodes.field_data("mass"))[1], 4.0);
  EXPECT_EQ(simit::api::SetAccess::of(nodes).field("mass").data<double>()[0], 2.5);
}

TEST(ApiSet, VectorAndMatrixFieldsAreRowMajorViews) {
  simit::Set s;
  auto pos = s.add_field<double, 3>("pos");
  auto m = s.add_field<double, 2, 3>("m");
  simit::ElementRef e = s.add();
  pos(e) = {1.0, 2.0, 3.0};
  EXPECT_EQ(pos(e)(0), 1.0);
  EXPECT_EQ(pos(e)(2), 3.0);
  pos(e)(1) = -5.0;
  EXPECT_EQ(pos.get(e)(1), -5.0);
  m.set(e, {1.0, 2.0, 3.0, 4.0, 5.0, 6.0});
  EXPECT_EQ(m(e)(0, 2), 3.0);
  EXPECT_EQ(m(e)(1, 0), 4.0);
  m(e)(1, 2) = 60.0;
  EXPECT_EQ(simit::api::SetAccess::of(s).field("m").data<double>()[5], 60.0);
  std::vector<double> values = {9, 8, 7};
  pos.set(e, values);
  EXPECT_EQ(pos(e)(2), 7.0);
  EXPECT_THROW(pos.set(e, std::vector<double>{1, 2}), simit::Error);
  EXPECT_THROW(pos(e) = {1.0}, simit::Error);
  EXPECT_THROW(m(e)(2, 0), simit::Error);
}

TEST(ApiSet, FieldRefsSurviveGrowthAndLateFieldsStartAtZero) {
  simit::Set s;
  auto x = s.add_field<double, 3>("x");
  simit::ElementRef first = s.add();
  x(first) = {1.0, 2.0, 3.0};
  for (int i = 0; i < 1000; ++i) s.add();
  EXPECT_EQ(x(first)(2), 3.0);
  auto late = s.add_field<float>("late");
  EXPECT_EQ(float(late(simit::ElementRef(999))), 0.0f);
  simit::ElementRange more = s.add_many(3);
  EXPECT_EQ(more.size(), 3);
  EXPECT_EQ(more[0].ident(), 1001);
  EXPECT_EQ(s.size(), 1004);
  int n = 0;
  for (simit::ElementRef e : s) n += e.defined();
  EXPECT_EQ(n, 1004);
}

TEST(ApiSet, ComplexFieldsRoundTrip) {
  simit::Set s;
  auto z = s.add_field<simit::double_complex, 2>("z");
  simit::ElementRef e = s.add();
  z(e) = {{1.0, 2.0}, {3.0, -4.0}};
  EXPECT_EQ(z(e)(1), simit::double_complex(3.0, -4.0));
}

TEST(ApiSet, GetFieldChecksTheComponentTypeAndShape) {
  simit::Set s;
  s.add_field<double, 3>("x");
  s.add();
  auto x = s.get_field<double, 3>("x");
  x(simit::ElementRef(0)) = {4.0, 5.0, 6.0};
  EXPECT_EQ((s.getField<double, 3>("x")(simit::ElementRef(0))(1)), 5.0);
  EXPECT_THROW((s.get_field<double, 2>("x")), simit::Error);
  EXPECT_THROW((s.get_field<int, 3>("x")), simit::Error);
  EXPECT_THROW((s.get_field<double>("nope")), simit::Error);
  EXPECT_THROW(x(simit::ElementRef(1)), simit::Error);  // no element 1
}

TEST(ApiSet, EdgeSetsHoldEndpoints) {
  simit::Set nodes("nodes"), cells("cells");
  simit::ElementRef a = nodes.add(), b = nodes.add(), c = cells.add();
  simit::Set bars("bars", nodes, nodes);
  simit::Set ties(nodes, cells);
  simit::ElementRef s = bars.add(a, b);
  simit::ElementRef t = ties.add(b, c);
  EXPECT_EQ(bars.cardinality(), 2);
  EXPECT_TRUE(bars.is_homogeneous());
  EXPECT_FALSE(ties.is_homogeneous());
  EXPECT_EQ(bars.endpoint(s, 1), b);
  EXPECT_EQ(ties.getEndpoint(t, 1), c);
  EXPECT_EQ(ties.endpoint_set(1), &cells);
  EXPECT_EQ(bars.endpoints(s), (std::vector<simit::ElementRef>{a, b}));
  EXPECT_EQ(bars.endpoints_data()[1], 1);
  EXPECT_THROW(bars.add(a), simit::Error);                        // wrong arity
  EXPECT_THROW(bars.add(a, simit::ElementRef(5)), simit::Error);  // not in nodes
  EXPECT_THROW(nodes.add(a), simit::Error);                       // vertex sets take none
}

TEST(ApiSet, GridSetsFillTheirPointSet) {
  simit::Set points("points");
  simit::Set grid("grid", points, {3, 2});
  EXPECT_EQ(points.size(), 6);
  EXPECT_EQ(grid.size(), 12);
  EXPECT_EQ(grid.kind(), simit::Set::Grid);
  EXPECT_EQ((grid.grid_point({1, 1}).ident()), 4);
  EXPECT_EQ(grid.grid_point_coords(simit::ElementRef(5)), std::vector<int>({2, 1}));
}

TEST(ApiSet, PrintsASummary) {
  simit::Set s("nodes");
  s.add_field<double, 3>("x");
  s.add();
  std::ostringstream os;
  os << s;
  EXPECT_TRUE(contains(os.str(), "nodes"));
  EXPECT_TRUE(contains(os.str(), "x (float 3)"));
}

// A field described at run time (simit::FieldType) is the same field a typed handle reaches.
TEST(ApiSet, FieldsDescribedAtRunTime) {
  simit::Set s("points");
  s.add_many(2);
  s.add_field("x", simit::FieldType{simit::ComponentKind::Float, {3}, false});
  simit::FieldRef<double, 3> x = s.get_field<double, 3>("x");
  x.set(simit::ElementRef(1), {1.0, 2.0, 3.0});
  EXPECT_EQ(x(simit::ElementRef(1))(2), 3.0);
  EXPECT_EQ(x.data()[5], 3.0);
  EXPECT_THROW((s.get_field<float, 3>("x")), simit::Error);
  EXPECT_THROW(x.get(simit::ElementRef(2)), simit::Error);
}

}  // namespace
