// The quick-look renderer: the mesh is fitted to the picture less its margin, triangles are
// lit the same from both sides, lines and points draw, and broken input draws nothing.
#include "runtime/mesh/quicklook.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "mesh_test_util.h"

namespace simit::runtime {
namespace {

const Rgb kBackground{248, 248, 245};

struct Box {
  int x0 = 1 << 30, y0 = 1 << 30, x1 = -1, y1 = -1;
  int count = 0;
};

Box ink_box(const Image& image) {
  Box b;
  for (int y = 0; y < image.height(); ++y)
    for (int x = 0; x < image.width(); ++x)
      if (!(image.at(x, y) == kBackground)) {
        b.x0 = std::min(b.x0, x), b.y0 = std::min(b.y0, y);
        b.x1 = std::max(b.x1, x), b.y1 = std::max(b.y1, y);
        ++b.count;
      }
  return b;
}

// A unit tet at the origin, in TetGen's orientation.
Mesh unit_tet() {
  Mesh m;
  m.points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  m.tets = {{1, 0, 2, 3}};
  return m;
}

TEST(Quicklook, FitsTheProjectedBoundingBoxIntoThePicture) {
  Mesh m = unit_tet();
  // The projected extents, from the documented view: u = p . (1, 0, -1) / sqrt 2 spans
  // [-1/sqrt 2, 1/sqrt 2] and v = p . (-1, 2, -1) / sqrt 6 spans [-1/sqrt 6, 2/sqrt 6].
  const double du = std::sqrt(2.0), dv = 3 / std::sqrt(6.0);
  QuicklookOptions o;
  o.width = 200, o.height = 100, o.margin = 10;
  Image image = render_quicklook(m, o);
  ASSERT_EQ(image.width(), 200);
  ASSERT_EQ(image.height(), 100);
  Box b = ink_box(image);
  // Height limits: 80 pixels for dv, so the width is 80 du / dv, centred.
  const double w = 80 * du / dv;
  EXPECT_NEAR(b.y0, 10, 1);
  EXPECT_NEAR(b.y1 + 1, 90, 1);
  EXPECT_NEAR(b.x0, 100 - w / 2, 1.5);
  EXPECT_NEAR(b.x1 + 1, 100 + w / 2, 1.5);
  EXPECT_GT(b.count, 0.3 * w * 80);  // the silhouette fills a good part of its box
}

TEST(Quicklook, TrianglesAreLitTheSameFromBothSides) {
  Mesh front, back;
  front.points = back.points = {{0, 0, 0}, {1, 0, 0}, {0, 0, 1}};
  front.triangles = {{0, 1, 2}};
  back.triangles = {{0, 2, 1}};
  Image a = render_quicklook(front), b = render_quicklook(back);
  EXPECT_EQ(a.rgb_bytes(), b.rgb_bytes());
  Box box = ink_box(a);
  ASSERT_GT(box.count, 0);
  // The centre of the triangle is lit: clearly darker than the background, not black.
  const Rgb c = a.at((box.x0 + box.x1) / 2, (2 * box.y0 + box.y1) / 3);
  EXPECT_LT(c.r + c.g + c.b, 3 * 230);
  EXPECT_GT(c.r + c.g + c.b, 3 * 40);
}

TEST(Quicklook, EdgesAndPointsDraw) {
  Mesh lines;
  lines.points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  lines.edges = {{0, 1}, {1, 2}};
  Box b = ink_box(render_quicklook(lines));
  EXPECT_GT(b.count, 300);  // two lines across a 456 x 336 fitted box
  Mesh points;
  points.points = lines.points;
  EXPECT_GT(ink_box(render_quicklook(points)).count, 3);
}

TEST(Quicklook, EmptyAndNonFiniteMeshesDrawNothing) {
  EXPECT_EQ(ink_box(render_quicklook(Mesh{})).count, 0);
  Mesh m = unit_tet();
  m.points[3][1] = std::numeric_limits<double>::quiet_NaN();
  Image image = render_quicklook(m);  // every boundary face touches the NaN point but one
  Box b = ink_box(image);
  EXPECT_GT(b.count, 0);
  Mesh all_nan;
  all_nan.points = {{NAN, 0, 0}, {0, NAN, 0}};
  all_nan.edges = {{0, 1}};
  EXPECT_EQ(ink_box(render_quicklook(all_nan)).count, 0);
}

TEST(Quicklook, WritesAPngOrSaysWhyNot) {
  testing::ScratchDir dir;
  std::string error;
  EXPECT_TRUE(write_quicklook(unit_tet(), dir.path("tet.png"), error)) << error;
  EXPECT_EQ(dir.files(), std::vector<std::string>{"tet.png"});
  EXPECT_FALSE(write_quicklook(unit_tet(), dir.path("missing/tet.png"), error));
  EXPECT_NE(error.find("missing/tet.png"), std::string::npos) << error;
}

}  // namespace
}  // namespace simit::runtime
