// The raster canvas and PNG writer: triangle coverage against an independent inside test,
// depth-test order independence, line end pixels and connectivity, text metrics against the
// ink actually drawn, and a PNG written and decoded back with libpng.
#include "runtime/image.h"

#include <gtest/gtest.h>
#include <png.h>

#include <cmath>
#include <queue>
#include <set>
#include <utility>

#include "mesh_test_util.h"

namespace simit::runtime {
namespace {

const Rgb kWhite{255, 255, 255};
const Rgb kRed{200, 0, 0};
const Rgb kBlue{0, 0, 200};

// The pixels of `image` that are not `background`.
std::set<std::pair<int, int>> ink(const Image& image, Rgb background) {
  std::set<std::pair<int, int>> out;
  for (int y = 0; y < image.height(); ++y)
    for (int x = 0; x < image.width(); ++x)
      if (!(image.at(x, y) == background)) out.insert({x, y});
  return out;
}

TEST(Image, StartsAsBackgroundAndIgnoresOutOfRangeSets) {
  Image image(4, 3, kWhite);
  EXPECT_EQ(image.width(), 4);
  EXPECT_EQ(image.height(), 3);
  image.set(-1, 0, kRed);
  image.set(4, 0, kRed);
  image.set(0, 3, kRed);
  EXPECT_TRUE(ink(image, kWhite).empty());
  image.set(3, 2, kRed);
  EXPECT_EQ(image.at(3, 2), kRed);
  EXPECT_EQ(ink(image, kWhite).size(), 1u);
}

// The right triangle with legs on x = 2 and y = 2 and hypotenuse from (18, 2) to (2, 12):
// a centre (i + 0.5, j + 0.5) is inside when 10 (cx - 2) + 16 (cy - 2) <= 160, which is never
// an equality for half-integer centres, so the expected set has no ties.
TEST(Image, TriangleCoversExactlyThePixelCentresInside) {
  const double x[3] = {2, 18, 2}, y[3] = {2, 2, 12}, z[3] = {0, 0, 0};
  const double xr[3] = {2, 2, 18}, yr[3] = {2, 12, 2};  // the other winding
  Image a(24, 16, kWhite), b(24, 16, kWhite);
  a.triangle(x, y, z, kRed);
  b.triangle(xr, yr, z, kRed);
  std::set<std::pair<int, int>> expected;
  for (int j = 0; j < 16; ++j)
    for (int i = 0; i < 24; ++i) {
      const double cx = i + 0.5, cy = j + 0.5;
      if (cx > 2 && cy > 2 && 10 * (cx - 2) + 16 * (cy - 2) <= 160) expected.insert({i, j});
    }
  EXPECT_EQ(expected.size(), 80u);  // the area is 16 * 10 / 2 = 80 pixels
  EXPECT_EQ(ink(a, kWhite), expected);
  EXPECT_EQ(ink(b, kWhite), expected);
  EXPECT_EQ(a.at(3, 3), kRed);
  EXPECT_EQ(a.at(12, 10), kWhite);
}

TEST(Image, DegenerateAndOffCanvasTrianglesDrawNothing) {
  Image image(10, 10, kWhite);
  const double x[3] = {1, 5, 9}, y[3] = {1, 5, 9}, z[3] = {0, 0, 0};
  image.triangle(x, y, z, kRed);  // collinear
  const double fx[3] = {-30, -20, -25}, fy[3] = {1, 1, 8};
  image.triangle(fx, fy, z, kRed);
  EXPECT_TRUE(ink(image, kWhite).empty());
}

// Red is tilted in depth (z from 0 at x = 0 to 1 at x = 20), blue flat at z = 0.5: where they
// overlap, red is nearer left of x = 10 and blue right of it, whatever the drawing order.
TEST(Image, DepthTestDoesNotDependOnDrawingOrder) {
  const double rx[3] = {0, 20, 0}, ry[3] = {0, 0, 20}, rz[3] = {0, 1, 0};
  const double bx[3] = {0, 20, 20}, by[3] = {0, 0, 20}, bz[3] = {0.5, 0.5, 0.5};
  Image first(20, 20, kWhite), second(20, 20, kWhite);
  first.triangle(rx, ry, rz, kRed);
  first.triangle(bx, by, bz, kBlue);
  second.triangle(bx, by, bz, kBlue);
  second.triangle(rx, ry, rz, kRed);
  EXPECT_EQ(first.rgb_bytes(), second.rgb_bytes());
  EXPECT_EQ(first.at(6, 2), kRed);     // both cover it; red z = 0.325
  EXPECT_EQ(first.at(14, 2), kBlue);   // both cover it; red z = 0.725
  EXPECT_EQ(first.at(2, 14), kRed);    // red only
  EXPECT_EQ(first.at(18, 14), kBlue);  // blue only
  // set() paints over without touching the depth buffer.
  first.set(6, 2, kWhite);
  EXPECT_EQ(first.at(6, 2), kWhite);
}

// 8-connected: every ink pixel is reachable from `from` through 8-neighbours.
bool connected(const std::set<std::pair<int, int>>& pixels, std::pair<int, int> from) {
  std::set<std::pair<int, int>> seen{from};
  std::queue<std::pair<int, int>> todo;
  todo.push(from);
  while (!todo.empty()) {
    auto [x, y] = todo.front();
    todo.pop();
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        std::pair<int, int> n{x + dx, y + dy};
        if (pixels.count(n) && seen.insert(n).second) todo.push(n);
      }
  }
  return seen.size() == pixels.size();
}

TEST(Image, LineIncludesBothEndPixelsAndIsConnected) {
  Image image(20, 20, kWhite);
  image.line(3.2, 4.7, 15.9, 9.1, kRed);
  auto pixels = ink(image, kWhite);
  EXPECT_TRUE(pixels.count({3, 4}));
  EXPECT_TRUE(pixels.count({15, 9}));
  EXPECT_TRUE(connected(pixels, {3, 4}));
  // Every pixel touches the ideal line: its centre is within sqrt(2) / 2 + 0.5 of it.
  const double dx = 15.9 - 3.2, dy = 9.1 - 4.7, len = std::hypot(dx, dy);
  for (auto [x, y] : pixels) {
    const double d = std::abs((x + 0.5 - 3.2) * dy - (y + 0.5 - 4.7) * dx) / len;
    EXPECT_LE(d, 1.21) << x << "," << y;
  }
  // A shallow line has one to two pixels per column over its 13 columns.
  EXPECT_GE(pixels.size(), 13u);
  EXPECT_LE(pixels.size(), 26u);
}

// A long line whose samples fall on whole pixels must still set every pixel it crosses.
TEST(Image, LongLineSkipsNoPixel) {
  Image image(800, 10, kWhite);
  image.line(100.0, 5.5, 796.0, 5.5, kRed);
  for (int x = 100; x <= 796; ++x) EXPECT_TRUE(image.at(x, 5) == kRed) << "pixel " << x;
  EXPECT_TRUE(image.at(99, 5) == kWhite);
  EXPECT_TRUE(image.at(797, 5) == kWhite);
}

TEST(Image, ThickLineAndClipping) {
  Image image(20, 20, kWhite);
  image.line(10.5, 2.5, 10.5, 12.5, kRed, 3);
  auto pixels = ink(image, kWhite);
  // The 3 x 3 square stamped on each of the rows 2..12 covers columns 9..11, rows 1..13.
  EXPECT_EQ(pixels.size(), 3u * 13u);
  EXPECT_TRUE(pixels.count({9, 1}) && pixels.count({11, 13}));
  Image far(20, 20, kWhite);
  far.line(-1e9, 5.5, 1e9, 5.5, kBlue);  // clipped: one full row
  EXPECT_EQ(ink(far, kWhite).size(), 20u);
  far.line(-1e9, -1e9, -2e9, 3e9, kBlue);  // entirely off the canvas
  EXPECT_EQ(ink(far, kWhite).size(), 20u);
}

TEST(Image, FillRectIncludesBothCornersInEitherOrder) {
  Image image(10, 10, kWhite);
  image.fill_rect(7, 6, 2, 3, kRed);
  EXPECT_EQ(ink(image, kWhite).size(), 6u * 4u);
  EXPECT_EQ(image.at(2, 3), kRed);
  EXPECT_EQ(image.at(7, 6), kRed);
  image.fill_rect(-5, -5, 100, 0, kBlue);  // clipped to row 0
  EXPECT_EQ(image.at(9, 0), kBlue);
}

// "E=3" starts and ends with glyphs whose ink reaches both outer columns, so its ink spans
// exactly text_width x text_height.
TEST(Image, TextWidthMatchesTheInk) {
  Image image(60, 30, kWhite);
  EXPECT_EQ(image.text_width("", 2), 0);
  EXPECT_EQ(image.text_width("E=3", 1), 17);
  EXPECT_EQ(image.text_width("1.5e-3 ms/frame (max)", 2), (6 * 21 - 1) * 2);
  image.text(4, 5, "E=3", kRed, 2);
  auto pixels = ink(image, kWhite);
  ASSERT_FALSE(pixels.empty());
  int x0 = 1000, y0 = 1000, x1 = -1, y1 = -1;
  for (auto [x, y] : pixels) {
    x0 = std::min(x0, x), y0 = std::min(y0, y), x1 = std::max(x1, x), y1 = std::max(y1, y);
  }
  EXPECT_EQ(x0, 4);
  EXPECT_EQ(y0, 5);
  EXPECT_EQ(x1 - x0 + 1, image.text_width("E=3", 2));
  EXPECT_EQ(y1 - y0 + 1, Image::text_height(2));
  // Every listed character has a glyph distinct from the '?' of unknown characters.
  auto drawn = [](char c) {
    Image one(6, 7, kWhite);
    one.text(0, 0, std::string(1, c), kRed);
    return one.rgb_bytes();
  };
  const std::string chars =
      "0123456789ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz.-+e:/(),=%";
  for (char c : chars) EXPECT_NE(drawn(c), drawn('?')) << c;
  EXPECT_EQ(drawn('~'), drawn('?'));
  EXPECT_EQ(drawn(' '), Image(6, 7, kWhite).rgb_bytes());
}

// Decodes a PNG with libpng into 8-bit RGB.
bool read_png(const std::string& path, int& width, int& height, std::vector<uint8_t>& rgb) {
  png_image info{};
  info.version = PNG_IMAGE_VERSION;
  if (!png_image_begin_read_from_file(&info, path.c_str())) return false;
  info.format = PNG_FORMAT_RGB;
  width = static_cast<int>(info.width);
  height = static_cast<int>(info.height);
  rgb.assign(PNG_IMAGE_SIZE(info), 0);
  bool ok = png_image_finish_read(&info, nullptr, rgb.data(), 0, nullptr) != 0;
  png_image_free(&info);
  return ok;
}

TEST(Image, PngRoundTrip) {
  testing::ScratchDir dir;
  Image image(37, 23, Rgb{250, 250, 245});
  for (int y = 0; y < 23; ++y)
    for (int x = 0; x < 37; ++x)
      if ((x * 7 + y * 3) % 5 == 0)
        image.set(x, y, Rgb{uint8_t(x * 6), uint8_t(y * 11), uint8_t((x * y) % 256)});
  image.text(1, 1, "ok", kBlue);
  std::string error;
  ASSERT_TRUE(write_png(image, dir.path("a.png"), error)) << error;
  EXPECT_EQ(dir.files(), std::vector<std::string>{"a.png"});  // no temporary left behind
  int width = 0, height = 0;
  std::vector<uint8_t> rgb;
  ASSERT_TRUE(read_png(dir.path("a.png"), width, height, rgb));
  EXPECT_EQ(width, 37);
  EXPECT_EQ(height, 23);
  EXPECT_EQ(rgb, image.rgb_bytes());
}

TEST(Image, PngToAnUnwritablePlaceFailsWithTheReason) {
  testing::ScratchDir dir;
  Image image(4, 4, kWhite);
  std::string error;
  const std::string path = dir.path("no-such-folder/a.png");
  EXPECT_FALSE(write_png(image, path, error));
  EXPECT_NE(error.find(path), std::string::npos) << error;
  EXPECT_NE(error.find("No such file"), std::string::npos) << error;
  EXPECT_TRUE(dir.files().empty());
  EXPECT_FALSE(write_png(Image(0, 5, kWhite), dir.path("empty.png"), error));
  EXPECT_TRUE(dir.files().empty());
}

}  // namespace
}  // namespace simit::runtime
