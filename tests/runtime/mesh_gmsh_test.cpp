// Gmsh .msh 2.2 and 4.1 ASCII reading: the two-tetrahedron pyramid in both versions, skipped
// sections and element types, and every malformed-input error with its line.
#include "runtime/mesh/gmsh_reader.h"

#include <gtest/gtest.h>

#include "mesh_test_util.h"
#include "runtime/mesh/mesh_reader.h"

namespace simit::runtime {
namespace {

using testing::mesh_error;
using testing::ScratchDir;

// Node tags are sparse on purpose: they are names, not positions.
const char* const kPyramid22 =
    "$MeshFormat\n"
    "2.2 0 8\n"
    "$EndMeshFormat\n"
    "$PhysicalNames\n"
    "1\n"
    "3 1 \"solid $Nodes\"\n"
    "$EndPhysicalNames\n"
    "$Nodes\n"
    "5\n"
    "10 0 0 0\n"
    "20 1 0 0\n"
    "30 0 1 0\n"
    "40 0.25 0.25 1\n"
    "50 0.25 0.25 -1\n"
    "$EndNodes\n"
    "$Elements\n"
    "6\n"
    "1 15 2 0 1 10\n"
    "2 1 2 0 1 10 20\n"
    "3 2 2 0 1 10 20 40\n"
    "4 4 2 1 1 10 20 30 40\n"
    "5 4 3 1 1 7 10 30 20 50\n"
    "6 3 2 0 1 10 20 30 40\n"
    "$EndElements\n"
    "$NodeData\n"
    "1\n"
    "\"T\"\n"
    "$EndNodeData\n";

const char* const kPyramid41 =
    "$MeshFormat\n"
    "4.1 0 8\n"
    "$EndMeshFormat\n"
    "$Entities\n"
    "1 0 0 1\n"
    "1 0 0 0 0\n"
    "1 0 0 0 1 1 1 0 0\n"
    "$EndEntities\n"
    "$Nodes\n"
    "3 6 1 6\n"
    "0 1 0 1\n"
    "1\n"
    "0 0 0\n"
    "3 1 0 4\n"
    "2\n"
    "3\n"
    "4\n"
    "5\n"
    "1 0 0\n"
    "0 1 0\n"
    "0.25 0.25 1\n"
    "0.25 0.25 -1\n"
    "1 7 1 1\n"
    "6\n"
    "0.5 0 0 0.5\n"
    "$EndNodes\n"
    "$Elements\n"
    "4 5 1 5\n"
    "0 1 15 1\n"
    "1 1\n"
    "1 7 1 1\n"
    "2 1 6\n"
    "2 1 2 1\n"
    "3 1 2 4\n"
    "3 1 4 2\n"
    "4 1 2 3 4\n"
    "5 1 3 2 5\n"
    "$EndElements\n";

void expect_pyramid(const Mesh& m) {
  ASSERT_GE(m.points.size(), 5u);
  EXPECT_EQ(m.points[0], (Point{0, 0, 0}));
  EXPECT_EQ(m.points[4], (Point{0.25, 0.25, -1}));
  ASSERT_EQ(m.tets.size(), 2u);
  EXPECT_EQ(m.tets[0], (Tet{0, 1, 2, 3}));
  EXPECT_EQ(m.tets[1], (Tet{0, 2, 1, 4}));
  ASSERT_EQ(m.triangles.size(), 1u);
  EXPECT_EQ(m.triangles[0], (Triangle{0, 1, 3}));
  for (const Tet& t : m.tets) EXPECT_LT(tet_orientation_det(m, t), 0);
}

TEST(MeshGmsh, Version22Pyramid) {
  ScratchDir dir;
  Mesh m = read_mesh(dir.write("p.msh", kPyramid22));
  EXPECT_EQ(m.points.size(), 5u);
  expect_pyramid(m);
  ASSERT_EQ(m.edges.size(), 1u);
  EXPECT_EQ(m.edges[0], (Edge{0, 1}));
}

TEST(MeshGmsh, Version41Pyramid) {
  ScratchDir dir;
  Mesh m = read_gmsh(dir.write("p.msh", kPyramid41));
  ASSERT_EQ(m.points.size(), 6u);
  EXPECT_EQ(m.points[5], (Point{0.5, 0, 0}));
  expect_pyramid(m);
  ASSERT_EQ(m.edges.size(), 1u);
  EXPECT_EQ(m.edges[0], (Edge{0, 5}));
}

TEST(MeshGmsh, SecondOrderElementsKeepTheirCorners) {
  ScratchDir dir;
  std::string text = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n10\n";
  for (int i = 1; i <= 10; ++i) text += std::to_string(i) + " " + std::to_string(i) + " 0 0\n";
  text += "$EndNodes\n$Elements\n2\n1 11 0 4 3 2 1 5 6 7 8 9 10\n2 9 0 1 2 3 4 5 6\n$EndElements\n";
  Mesh m = read_gmsh(dir.write("q.msh", text));
  ASSERT_EQ(m.tets.size(), 1u);
  EXPECT_EQ(m.tets[0], (Tet{3, 2, 1, 0}));
  ASSERT_EQ(m.triangles.size(), 1u);
  EXPECT_EQ(m.triangles[0], (Triangle{0, 1, 2}));
}

// A 2.2 file with 4 nodes (tags 1-4) and the given elements section body.
std::string small22(const std::string& nodes, const std::string& elements) {
  return "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n" + nodes + "$EndNodes\n$Elements\n" +
         elements + "$EndElements\n";
}

const std::string kNodes = "4\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n";

struct BadCase {
  const char* label;
  std::string text;
  const char* expected;  // after "FILE:"
};

TEST(MeshGmsh, MalformedInputNamesFileAndLine) {
  const BadCase cases[] = {
      {"empty file", "", "1: expected $MeshFormat, found end of file"},
      {"no format", "$Nodes\n0\n$EndNodes\n",
       "1: expected $MeshFormat on the first line, got '$Nodes'"},
      {"binary", "$MeshFormat\n2.2 1 8\n",
       "2: expected file-type 0 (ASCII; binary .msh files are not supported), got '1'"},
      {"version 3", "$MeshFormat\n3.0 0 8\n$EndMeshFormat\n",
       "2: expected format version 2.2 or 4.1, got '3.0'"},
      {"unterminated format", "$MeshFormat\n2.2 0 8\n$Nodes\n",
       "3: expected $EndMeshFormat, got '$Nodes'"},
      {"no nodes", "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n",
       "4: expected a $Nodes section, found end of file"},
      {"stray line", "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n4\n",
       "4: expected a section such as $Nodes or $Elements, got '4'"},
      {"unterminated section", "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Comments\nhi\n",
       "6: expected $EndComments, found end of file"},
      {"elements first", "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Elements\n0\n$EndElements\n",
       "4: expected the $Nodes section before $Elements"},
      {"too few nodes", small22("5\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n", "0\n"),
       "10: expected 5 node records (the section's count), found $EndNodes after 4"},
      {"too many nodes", small22("3\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n", "0\n"),
       "9: expected $EndNodes after 3 nodes (the section's count), got '4'"},
      {"short node", small22("4\n1 0 0 0\n2 1 0\n3 0 1 0\n4 0 0 1\n", "0\n"),
       "7: expected z coordinate, found end of line"},
      {"bad coordinate", small22("4\n1 0 0 0\n2 1 0 0\n3 0 1e 0\n4 0 0 1\n", "0\n"),
       "8: expected y coordinate (a finite number), got '1e'"},
      {"duplicate node tag", small22("4\n1 0 0 0\n2 1 0 0\n2 0 1 0\n4 0 0 1\n", "0\n"),
       "8: expected a node tag not used by an earlier node, got '2'"},
      {"unknown node tag", small22(kNodes, "1\n1 4 2 0 0 1 2 3 99\n"),
       "13: expected a node tag defined in $Nodes, got '99'"},
      {"short tet", small22(kNodes, "1\n1 4 2 0 0 1 2 3\n"),
       "13: expected a node tag, found end of line"},
      {"long tet", small22(kNodes, "1\n1 4 0 1 2 3 4 4\n"),
       "13: expected end of line after an element record, got '4'"},
      {"bad tag count", small22(kNodes, "1\n1 4 x 1 2 3 4\n"),
       "13: expected the element's tag count, got 'x'"},
      {"too few elements", small22(kNodes, "2\n1 4 0 1 2 3 4\n"),
       "14: expected 2 element records (the section's count), found $EndElements after 1"},
      {"missing end", "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n" + kNodes,
       "10: expected $EndNodes after 4 nodes (the section's count), found end of file"},
      {"second nodes", small22(kNodes, "0\n") + "$Nodes\n0\n$EndNodes\n",
       "14: expected one $Nodes section, found a second"},
      {"v4 block beyond count",
       "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 1 1 2\n0 1 0 2\n1\n2\n0 0 0\n1 0 0\n"
       "$EndNodes\n",
       "6: expected at most 1 more nodes (the section's count), got '2'"},
      {"v4 node total short",
       "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 2 1 2\n0 1 0 1\n1\n0 0 0\n$EndNodes\n",
       "8: expected 2 nodes (the header's count), found 1"},
      {"v4 parametric flag",
       "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 1 1 1\n0 1 2 1\n1\n0 0 0\n$EndNodes\n",
       "6: expected the parametric flag, 0 or 1, got '2'"},
      {"v4 parametric coordinates missing",
       "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 1 1 1\n2 1 1 1\n1\n0 0 0\n$EndNodes\n",
       "8: expected a parametric coordinate, found end of line"},
      {"v4 element total",
       "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 1 1 1\n0 1 0 1\n1\n0 0 0\n$EndNodes\n"
       "$Elements\n1 2 1 2\n0 1 15 1\n1 1\n$EndElements\n",
       "13: expected 2 elements (the header's count), found 1"},
      {"v4 short block header", "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 1 1 1\n0 1 0\n",
       "6: expected the block's record count, found end of line"},
  };
  for (const BadCase& c : cases) {
    ScratchDir dir;
    std::string path = dir.write("b.msh", c.text);
    EXPECT_EQ(mesh_error([&] { read_gmsh(path); }), path + ":" + c.expected) << c.label;
  }
}

}  // namespace
}  // namespace simit::runtime
