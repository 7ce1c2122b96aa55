// Derived sets (edges, boundary triangles, hinges) on small meshes with hand-computed results
// and on bar2k, plus the index, orientation and degeneracy checks.
#include "runtime/mesh/topology.h"

#include <gtest/gtest.h>

#include <cmath>

#include "mesh_test_util.h"
#include "runtime/mesh/tetgen_reader.h"

namespace simit::runtime {
namespace {

using testing::mesh_error;

Point sub(const Point& a, const Point& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
Point cross(const Point& a, const Point& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
double dot(const Point& a, const Point& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

Point normal(const Mesh& m, const Triangle& t) {
  return cross(sub(m.points[t[1]], m.points[t[0]]), sub(m.points[t[2]], m.points[t[0]]));
}

Mesh single_tet() { return {{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}}, {{0, 1, 2, 3}}, {}, {}}; }

// Two tets sharing the face (0 1 2), apexes above and below.
Mesh pyramid() {
  return {{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0.25, 0.25, 1}, {0.25, 0.25, -1}},
          {{0, 1, 2, 3}, {0, 2, 1, 4}},
          {},
          {}};
}

Point centroid(const Mesh& m) {
  Point c{0, 0, 0};
  for (const Point& p : m.points)
    for (int k = 0; k < 3; ++k) c[k] += p[k] / m.points.size();
  return c;
}

// For a convex mesh, outward means pointing away from the centroid.
void expect_outward(const Mesh& m, const std::vector<Triangle>& faces) {
  Point c = centroid(m);
  for (const Triangle& f : faces) EXPECT_GT(dot(normal(m, f), sub(m.points[f[0]], c)), 0);
}

TEST(MeshTopology, EdgesAreUniqueAndSorted) {
  EXPECT_EQ(tet_edges(single_tet().tets),
            (std::vector<Edge>{{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}}));
  EXPECT_EQ(
      tet_edges(pyramid().tets),
      (std::vector<Edge>{{0, 1}, {0, 2}, {0, 3}, {0, 4}, {1, 2}, {1, 3}, {1, 4}, {2, 3}, {2, 4}}));
  EXPECT_EQ(triangle_edges({{0, 1, 2}, {2, 1, 3}}),
            (std::vector<Edge>{{0, 1}, {0, 2}, {1, 2}, {1, 3}, {2, 3}}));
}

TEST(MeshTopology, BoundaryOfOneTetIsOutward) {
  Mesh m = single_tet();
  std::vector<Triangle> faces = boundary_triangles(m);
  EXPECT_EQ(faces, (std::vector<Triangle>{{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}}));
  expect_outward(m, faces);
  // The same tet with the other orientation still gets outward faces.
  m.tets[0] = {1, 0, 2, 3};
  faces = boundary_triangles(m);
  EXPECT_EQ(faces, (std::vector<Triangle>{{0, 3, 2}, {1, 2, 3}, {1, 3, 0}, {1, 0, 2}}));
  expect_outward(m, faces);
}

TEST(MeshTopology, BoundaryOfThePyramidSkipsTheSharedFace) {
  Mesh m = pyramid();
  std::vector<Triangle> faces = boundary_triangles(m);
  EXPECT_EQ(faces, (std::vector<Triangle>{
                       {1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {2, 1, 4}, {0, 4, 1}, {0, 2, 4}}));
  expect_outward(m, faces);
}

TEST(MeshTopology, ThreeTetsOnOneFaceAreRejected) {
  Mesh m = pyramid();
  m.points.push_back({0.3, 0.3, 2});
  m.tets.push_back({0, 1, 2, 5});
  EXPECT_EQ(mesh_error([&] { boundary_triangles(m); }),
            "tets 0, 1 and 2 share a face: not a manifold mesh");
}

TEST(MeshTopology, HingeOfTwoTriangles) {
  // The unit square split along 0-2; both triangles counter-clockwise seen from +z.
  EXPECT_EQ(hinges({{0, 1, 2}, {0, 2, 3}}), (std::vector<Hinge>{{2, 0, 1, 3}}));
}

TEST(MeshTopology, HingesOfThePyramidSurface) {
  Mesh m = pyramid();
  std::vector<Triangle> faces = boundary_triangles(m);
  std::vector<Hinge> h = hinges(faces);
  EXPECT_EQ(h, (std::vector<Hinge>{{0, 1, 3, 4},
                                   {2, 0, 3, 4},
                                   {0, 3, 2, 1},
                                   {0, 4, 1, 2},
                                   {1, 2, 3, 4},
                                   {3, 1, 2, 0},
                                   {1, 4, 2, 0},
                                   {2, 3, 1, 0},
                                   {4, 2, 1, 0}}));
  // On a convex outward surface the far vertex d lies behind the first triangle's plane, and
  // the second triangle (b, a, d) faces outward too.
  Point c = centroid(m);
  for (const Hinge& x : h) {
    Triangle first{x[0], x[1], x[2]}, second{x[1], x[0], x[3]};
    EXPECT_LT(dot(normal(m, first), sub(m.points[x[3]], m.points[x[0]])), 0);
    EXPECT_GT(dot(normal(m, second), sub(m.points[x[0]], c)), 0);
  }
}

TEST(MeshTopology, HingeErrors) {
  EXPECT_EQ(mesh_error([] {
              hinges({{0, 1, 2}, {0, 1, 3}});
            }),
            "triangles 0 and 1 traverse their shared edge (0 1) in the same direction: the "
            "surface is not consistently oriented");
  EXPECT_EQ(mesh_error([] {
              hinges({{0, 1, 2}, {1, 0, 3}, {0, 1, 4}});
            }),
            "3 triangles share edge (0 1) (triangles 0, 1, 2): not a manifold surface");
  EXPECT_EQ(mesh_error([] { hinges({{0, 1, 2}, {3, 3, 1}}); }), "triangle 1 repeats vertex 3");
  EXPECT_TRUE(hinges({{0, 1, 2}}).empty());
}

TEST(MeshTopology, IndexCheck) {
  Mesh m = single_tet();
  EXPECT_EQ(mesh_error([&] { check_indices(m); }), "no error");
  m.triangles.push_back({0, 1, 2});
  m.triangles.push_back({0, 4, 2});
  EXPECT_EQ(mesh_error([&] { check_indices(m); }),
            "triangle 1: vertex index 4 is beyond the vertex count 4");
  m.triangles.pop_back();
  m.edges.push_back({-1, 2});
  EXPECT_EQ(mesh_error([&] { check_indices(m); }), "edge 0: vertex index -1 is negative");
  EXPECT_EQ(mesh_error([&] { check_mesh(m, "bad.msh"); }),
            "bad.msh: edge 0: vertex index -1 is negative");
  EXPECT_EQ(mesh_error([&] { boundary_triangles(m); }), "edge 0: vertex index -1 is negative");
}

TEST(MeshTopology, OrientTets) {
  Mesh m = pyramid();
  m.tets[1] = {2, 0, 1, 4};
  EXPECT_GT(tet_orientation_det(m, m.tets[1]), 0);
  EXPECT_EQ(orient_tets(m), 1);
  EXPECT_EQ(m.tets[1], (Tet{0, 2, 1, 4}));
  EXPECT_EQ(orient_tets(m), 0);
}

TEST(MeshTopology, DegenerateElementsAreFoundWithTheirIndex) {
  Mesh m = pyramid();
  m.points.push_back({0.5, 0.5, 0});        // 5: on the plane of 0 1 2
  m.points.push_back({0.25, 0.25, 1e-14});  // 6: a hair above it
  m.tets.push_back({0, 1, 2, 5});           // 2: flat
  m.tets.push_back({0, 1, 2, 6});           // 3: near-flat
  m.tets.push_back({0, 1, 1, 3});           // 4: repeated vertex
  m.triangles = {{0, 1, 2}, {0, 1, 5}, {0, 3, 3}};
  m.points.push_back({1, 0, 0});  // 7: on top of 1
  m.edges = {{0, 1}, {1, 7}};
  std::vector<Degenerate> d = find_degenerate(m);
  ASSERT_EQ(d.size(), 5u);
  EXPECT_EQ(d[0].kind, ElementKind::Tet);
  EXPECT_EQ(d[0].index, 2);
  EXPECT_EQ(d[0].measure, 0);
  EXPECT_EQ(d[1].index, 3);
  EXPECT_GT(d[1].measure, 0);
  EXPECT_LT(d[1].measure, 1e-13);
  EXPECT_EQ(d[2].index, 4);
  EXPECT_EQ(d[3].kind, ElementKind::Triangle);
  EXPECT_EQ(d[3].index, 2);
  EXPECT_EQ(d[4].kind, ElementKind::Edge);
  EXPECT_EQ(d[4].index, 1);
  EXPECT_EQ(mesh_error([&] { check_mesh(m, "m.node"); }),
            "m.node: tet 2 (vertices 0 1 2 5) has zero volume (relative size 0) (and 4 more "
            "degenerate elements)");
  EXPECT_TRUE(find_degenerate(pyramid()).empty());
}

// Coordinates near 1e300: the volume (area, length) overflows, so the element cannot pass the
// relative-size test by a NaN comparison; a coordinate that is not finite is refused first.
TEST(MeshTopology, OverflowingElementsFailTheCheck) {
  Mesh m = single_tet();
  for (Point& p : m.points)
    for (double& c : p) c *= 1e300;
  std::vector<Degenerate> d = find_degenerate(m);
  ASSERT_EQ(d.size(), 1u);
  EXPECT_TRUE(std::isnan(d[0].measure));
  EXPECT_EQ(mesh_error([&] { check_mesh(m, "big.node"); }),
            "big.node: tet 0 (vertices 0 1 2 3) has a volume beyond the range of double precision "
            "(coordinates too large)");
  m.tets.clear();
  m.triangles = {{0, 1, 2}};
  m.edges = {{0, 1}};
  d = find_degenerate(m);
  ASSERT_EQ(d.size(), 2u);
  EXPECT_EQ(d[0].kind, ElementKind::Triangle);
  EXPECT_EQ(d[1].kind, ElementKind::Edge);
  EXPECT_EQ(mesh_error([&] { check_mesh(m, "big.obj"); }),
            "big.obj: triangle 0 (vertices 0 1 2) has an area beyond the range of double precision "
            "(coordinates too large) (and 1 more degenerate elements)");
  Mesh scaled = single_tet();  // 1e150 keeps the volume (1e450) out of range too
  for (Point& p : scaled.points)
    for (double& c : p) c *= 1e150;
  EXPECT_EQ(find_degenerate(scaled).size(), 1u);
  Mesh fine = single_tet();  // 1e100: volume 1e300, in range
  for (Point& p : fine.points)
    for (double& c : p) c *= 1e100;
  EXPECT_TRUE(find_degenerate(fine).empty());
  fine.points[2][1] = INFINITY;
  EXPECT_EQ(mesh_error([&] { check_mesh(fine, "inf.node"); }),
            "inf.node: vertex 2 has a coordinate that is not a finite number");
}

TEST(MeshTopology, Bar2kDerivedSetsAreConsistent) {
  Mesh m = read_tetgen(std::string(SIMIT_SOURCE_DIR) + "/tests/data/bar2k");
  std::vector<Edge> edges = tet_edges(m.tets);
  std::vector<Triangle> surface = boundary_triangles(m);
  long long v = m.points.size(), e = edges.size(), t = m.tets.size();
  long long fb = surface.size(), f = (4 * t + fb) / 2;
  EXPECT_EQ(v - e + f - t, 1);  // Euler characteristic of a solid bar
  // A closed surface: every surface edge is one hinge.
  std::vector<Hinge> h = hinges(surface);
  EXPECT_EQ(static_cast<long long>(h.size()), 3 * fb / 2);
  EXPECT_EQ(h.size(), triangle_edges(surface).size());
  // Divergence theorem: outward faces enclose the tets' total volume.
  double enclosed = 0, volume = 0;
  for (const Triangle& s : surface)
    enclosed += dot(m.points[s[0]], cross(m.points[s[1]], m.points[s[2]])) / 6;
  for (const Tet& x : m.tets) volume += -tet_orientation_det(m, x) / 6;
  EXPECT_GT(volume, 0);
  EXPECT_NEAR(enclosed, volume, 1e-12 * volume);
}

}  // namespace
}  // namespace simit::runtime
