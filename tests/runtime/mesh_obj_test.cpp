// Wavefront OBJ reading through tinyobjloader: triangulated polygons keep their winding,
// corner formats, relative indices, polylines, and every malformed-input error with its line.
#include "runtime/mesh/obj_reader.h"

#include <gtest/gtest.h>

#include "mesh_test_util.h"
#include "runtime/mesh/mesh_reader.h"

namespace simit::runtime {
namespace {

using testing::mesh_error;
using testing::ScratchDir;

double normal_z(const Mesh& m, const Triangle& t) {
  const Point &a = m.points[t[0]], &b = m.points[t[1]], &c = m.points[t[2]];
  return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
}

TEST(MeshObj, QuadBecomesTwoTrianglesWithItsWinding) {
  ScratchDir dir;
  Mesh m = read_mesh(dir.write("q.obj",
                               "# a unit square\nmtllib missing.mtl\no square\n"
                               "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nusemtl none\ns off\n"
                               "f 1 2 3 4\n"));
  ASSERT_EQ(m.points.size(), 4u);
  ASSERT_EQ(m.triangles.size(), 2u);
  // tinyobjloader splits a quad along its shorter diagonal, 1-3 on a tie.
  EXPECT_EQ(m.triangles[0], (Triangle{0, 1, 3}));
  EXPECT_EQ(m.triangles[1], (Triangle{1, 2, 3}));
  for (const Triangle& t : m.triangles) EXPECT_GT(normal_z(m, t), 0);
}

TEST(MeshObj, ConvexPentagonIsCoveredWithItsWinding) {
  ScratchDir dir;
  Mesh m =
      read_obj(dir.write("p.obj", "v 0 0 0\nv 2 0 0\nv 3 1 0\nv 1 2 0\nv -1 1 0\nf 1 2 3 4 5\n"));
  ASSERT_EQ(m.triangles.size(), 3u);
  double area = 0;
  for (const Triangle& t : m.triangles) {
    EXPECT_GT(normal_z(m, t), 0);
    area += normal_z(m, t) / 2;
  }
  EXPECT_DOUBLE_EQ(area, 5.0);  // shoelace area of the pentagon
}

TEST(MeshObj, CornerFormatsRelativeIndicesAndPolylines) {
  ScratchDir dir;
  Mesh m = read_obj(dir.write("c.obj",
                              "v 0.123456789012345678 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n"
                              "vt 0 0\nvt 1 0\nvt 0 1\nvn 0 0 1\n"
                              "f 1/1/1 2/2/1 3/3/1\n"
                              "f 1//1 3//1 4//1\n"
                              "f -4/-3 -2/-1 -3/-2\n"
                              "l 1 2 3\n"));
  ASSERT_EQ(m.points.size(), 4u);
  EXPECT_EQ(m.points[0][0], 0.123456789012345678);  // read as double, not float
  ASSERT_EQ(m.triangles.size(), 3u);
  EXPECT_EQ(m.triangles[0], (Triangle{0, 1, 2}));
  EXPECT_EQ(m.triangles[1], (Triangle{0, 2, 3}));
  EXPECT_EQ(m.triangles[2], (Triangle{0, 2, 1}));
  ASSERT_EQ(m.edges.size(), 2u);
  EXPECT_EQ(m.edges[0], (Edge{0, 1}));
  EXPECT_EQ(m.edges[1], (Edge{1, 2}));
}

TEST(MeshObj, TrailingCommentsAreIgnored) {
  ScratchDir dir;
  Mesh m = read_obj(dir.write("t.obj", "v 0 0 0 # origin\nv 1 0 0\nv 0 1 0\nf 1 2 3 # face\n"));
  EXPECT_EQ(m.points.size(), 3u);
  ASSERT_EQ(m.triangles.size(), 1u);
  EXPECT_EQ(m.triangles[0], (Triangle{0, 1, 2}));
}

// tinyobjloader ends a line at a lone '\r' and does not take '\v' for a space; the reader reads
// the records its validation pass checked, in which both are spaces (found by obj_fuzz: an
// unchecked "l 1 5" after a '\r' gave an edge to a vertex that does not exist).
TEST(MeshObj, CarriageReturnsAndVerticalTabsAreSpaces) {
  ScratchDir dir;
  Mesh m = read_obj(dir.write("r.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nx\rl 1 5\n\vf 1 2 3\r\n"));
  EXPECT_EQ(m.points.size(), 3u);
  EXPECT_TRUE(m.edges.empty());
  ASSERT_EQ(m.triangles.size(), 1u);
  EXPECT_EQ(m.triangles[0], (Triangle{0, 1, 2}));
}

TEST(MeshObj, MalformedInputNamesFileAndLine) {
  const std::string v3 = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
  const struct {
    const char* label;
    std::string text;
    const char* expected;  // after "FILE:"
  } cases[] = {
      {"short vertex", "v 0 0 0\nv 1 0\n", "2: expected a vertex coordinate, found end of line"},
      {"bad vertex", "v 0 x 0\n", "1: expected a vertex coordinate (a finite number), got 'x'"},
      {"five numbers", "v 0 0 0 1 2\n", "1: expected 3 coordinates, then w or r g b, got '2'"},
      {"eight numbers", "v 0 0 0 1 2 3 4\n",
       "1: expected end of line after a vertex coordinate, got '4'"},
      {"short normal", "vn 0 0\n", "1: expected a normal component, found end of line"},
      {"two corners", v3 + "f 1 2\n", "4: expected at least 3 face corners, found end of line"},
      {"index zero", v3 + "f 1 2 0\n", "4: expected a vertex index in 1..3 or -1..-3, got '0'"},
      {"index beyond", v3 + "# c\nf 1 2 4\n",
       "5: expected a vertex index in 1..3 or -1..-3, got '4'"},
      {"relative beyond", "v 0 0 0\nv 1 0 0\nf 1 2 -3\nv 0 1 0\n",
       "3: expected a vertex index in 1..3 or -1..-2, got '-3'"},
      {"not an index", v3 + "f 1 2 c\n", "4: expected a vertex index in 1..3 or -1..-3, got 'c'"},
      {"most negative index", v3 + "f 1 2 -9223372036854775808\n",
       "4: expected a vertex index in 1..3 or -1..-3, got '-9223372036854775808'"},
      {"index past long long", v3 + "f 1 2 9223372036854775808\n",
       "4: expected a vertex index in 1..3 or -1..-3, got '9223372036854775808'"},
      {"no texture coordinates", v3 + "f 1/1 2/1 3/1\n",
       "4: expected no texture-coordinate index (the file defines no texture-coordinates), got "
       "'1/1'"},
      {"four parts", v3 + "vn 0 0 1\nf 1//1/1 2 3\n",
       "5: expected a face corner v, v/vt, v//vn or v/vt/vn, got '1//1/1'"},
      {"one-point line", v3 + "l 1\n", "4: expected at least 2 line points, found end of line"},
      {"line with normal", v3 + "vn 0 0 1\nl 1//1 2\n",
       "5: expected a line point v or v/vt, got '1//1'"},
  };
  for (const auto& c : cases) {
    ScratchDir dir;
    std::string path = dir.write("b.obj", c.text);
    EXPECT_EQ(mesh_error([&] { read_obj(path); }), path + ":" + c.expected) << c.label;
  }
}

TEST(MeshObj, DegenerateElementsInTheFilesNumbering) {
  ScratchDir dir;
  std::string path = dir.write("d.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 3 3\n");
  EXPECT_EQ(mesh_error([&] { check_mesh(read_obj(path), path); }),
            path + ": triangle 2 (vertices 1 3 3) has zero area (relative size 0)");
}

TEST(MeshObj, UnknownExtensionAndMissingFile) {
  ScratchDir dir;
  std::string path = dir.write("m.ply", "ply\n");
  EXPECT_EQ(mesh_error([&] { read_mesh(path); }),
            path + ": expected a mesh file ending in .node, .ele, .face, .edge, .msh or .obj");
  std::string missing = dir.path("none.obj");
  EXPECT_EQ(mesh_error([&] { read_obj(missing); }).rfind(missing + ": cannot open file", 0), 0u);
  EXPECT_EQ(mesh_error([&] { read_obj(dir.path("")); }),
            dir.path("") + ": expected a mesh file, found a directory");
}

}  // namespace
}  // namespace simit::runtime
