// The raster canvas (scan conversion by edge functions at pixel centres, DDA lines, a 5x7
// font) and PNG encoding through libpng's simplified API into memory, then an AtomicFile.
#include "runtime/image.h"

#include <png.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "runtime/mesh/atomic_file.h"
#include "runtime/mesh/mesh.h"

namespace simit::runtime {

namespace {

// One character of the font: 7 rows of 5 columns, bit 4 the leftmost column.
struct Glyph {
  char c;
  uint8_t rows[7];
};

// clang-format off
constexpr Glyph kFont[] = {
  {' ', {0b00000, 0b00000, 0b00000, 0b00000, 0b00000, 0b00000, 0b00000}},
  {'0', {0b01110, 0b10001, 0b10011, 0b10101, 0b11001, 0b10001, 0b01110}},
  {'1', {0b00100, 0b01100, 0b00100, 0b00100, 0b00100, 0b00100, 0b01110}},
  {'2', {0b01110, 0b10001, 0b00001, 0b00010, 0b00100, 0b01000, 0b11111}},
  {'3', {0b11111, 0b00010, 0b00100, 0b00010, 0b00001, 0b10001, 0b01110}},
  {'4', {0b00010, 0b00110, 0b01010, 0b10010, 0b11111, 0b00010, 0b00010}},
  {'5', {0b11111, 0b10000, 0b11110, 0b00001, 0b00001, 0b10001, 0b01110}},
  {'6', {0b00110, 0b01000, 0b10000, 0b11110, 0b10001, 0b10001, 0b01110}},
  {'7', {0b11111, 0b00001, 0b00010, 0b00100, 0b01000, 0b01000, 0b01000}},
  {'8', {0b01110, 0b10001, 0b10001, 0b01110, 0b10001, 0b10001, 0b01110}},
  {'9', {0b01110, 0b10001, 0b10001, 0b01111, 0b00001, 0b00010, 0b01100}},
  {'A', {0b01110, 0b10001, 0b10001, 0b11111, 0b10001, 0b10001, 0b10001}},
  {'B', {0b11110, 0b10001, 0b10001, 0b11110, 0b10001, 0b10001, 0b11110}},
  {'C', {0b01110, 0b10001, 0b10000, 0b10000, 0b10000, 0b10001, 0b01110}},
  {'D', {0b11110, 0b10001, 0b10001, 0b10001, 0b10001, 0b10001, 0b11110}},
  {'E', {0b11111, 0b10000, 0b10000, 0b11110, 0b10000, 0b10000, 0b11111}},
  {'F', {0b11111, 0b10000, 0b10000, 0b11110, 0b10000, 0b10000, 0b10000}},
  {'G', {0b01110, 0b10001, 0b10000, 0b10111, 0b10001, 0b10001, 0b01111}},
  {'H', {0b10001, 0b10001, 0b10001, 0b11111, 0b10001, 0b10001, 0b10001}},
  {'I', {0b01110, 0b00100, 0b00100, 0b00100, 0b00100, 0b00100, 0b01110}},
  {'J', {0b00111, 0b00010, 0b00010, 0b00010, 0b00010, 0b10010, 0b01100}},
  {'K', {0b10001, 0b10010, 0b10100, 0b11000, 0b10100, 0b10010, 0b10001}},
  {'L', {0b10000, 0b10000, 0b10000, 0b10000, 0b10000, 0b10000, 0b11111}},
  {'M', {0b10001, 0b11011, 0b10101, 0b10101, 0b10001, 0b10001, 0b10001}},
  {'N', {0b10001, 0b10001, 0b11001, 0b10101, 0b10011, 0b10001, 0b10001}},
  {'O', {0b01110, 0b10001, 0b10001, 0b10001, 0b10001, 0b10001, 0b01110}},
  {'P', {0b11110, 0b10001, 0b10001, 0b11110, 0b10000, 0b10000, 0b10000}},
  {'Q', {0b01110, 0b10001, 0b10001, 0b10001, 0b10101, 0b10010, 0b01101}},
  {'R', {0b11110, 0b10001, 0b10001, 0b11110, 0b10100, 0b10010, 0b10001}},
  {'S', {0b01111, 0b10000, 0b10000, 0b01110, 0b00001, 0b00001, 0b11110}},
  {'T', {0b11111, 0b00100, 0b00100, 0b00100, 0b00100, 0b00100, 0b00100}},
  {'U', {0b10001, 0b10001, 0b10001, 0b10001, 0b10001, 0b10001, 0b01110}},
  {'V', {0b10001, 0b10001, 0b10001, 0b10001, 0b10001, 0b01010, 0b00100}},
  {'W', {0b10001, 0b10001, 0b10001, 0b10101, 0b10101, 0b10101, 0b01010}},
  {'X', {0b10001, 0b10001, 0b01010, 0b00100, 0b01010, 0b10001, 0b10001}},
  {'Y', {0b10001, 0b10001, 0b01010, 0b00100, 0b00100, 0b00100, 0b00100}},
  {'Z', {0b11111, 0b00001, 0b00010, 0b00100, 0b01000, 0b10000, 0b11111}},
  {'a', {0b00000, 0b00000, 0b01110, 0b00001, 0b01111, 0b10001, 0b01111}},
  {'b', {0b10000, 0b10000, 0b10110, 0b11001, 0b10001, 0b10001, 0b11110}},
  {'c', {0b00000, 0b00000, 0b01110, 0b10000, 0b10000, 0b10001, 0b01110}},
  {'d', {0b00001, 0b00001, 0b01101, 0b10011, 0b10001, 0b10001, 0b01111}},
  {'e', {0b00000, 0b00000, 0b01110, 0b10001, 0b11111, 0b10000, 0b01110}},
  {'f', {0b00110, 0b01001, 0b01000, 0b11100, 0b01000, 0b01000, 0b01000}},
  {'g', {0b00000, 0b01111, 0b10001, 0b10001, 0b01111, 0b00001, 0b01110}},
  {'h', {0b10000, 0b10000, 0b10110, 0b11001, 0b10001, 0b10001, 0b10001}},
  {'i', {0b00100, 0b00000, 0b01100, 0b00100, 0b00100, 0b00100, 0b01110}},
  {'j', {0b00010, 0b00000, 0b00110, 0b00010, 0b00010, 0b10010, 0b01100}},
  {'k', {0b10000, 0b10000, 0b10010, 0b10100, 0b11000, 0b10100, 0b10010}},
  {'l', {0b01100, 0b00100, 0b00100, 0b00100, 0b00100, 0b00100, 0b01110}},
  {'m', {0b00000, 0b00000, 0b11010, 0b10101, 0b10101, 0b10001, 0b10001}},
  {'n', {0b00000, 0b00000, 0b10110, 0b11001, 0b10001, 0b10001, 0b10001}},
  {'o', {0b00000, 0b00000, 0b01110, 0b10001, 0b10001, 0b10001, 0b01110}},
  {'p', {0b00000, 0b00000, 0b11110, 0b10001, 0b11110, 0b10000, 0b10000}},
  {'q', {0b00000, 0b00000, 0b01101, 0b10011, 0b01111, 0b00001, 0b00001}},
  {'r', {0b00000, 0b00000, 0b10110, 0b11001, 0b10000, 0b10000, 0b10000}},
  {'s', {0b00000, 0b00000, 0b01110, 0b10000, 0b01110, 0b00001, 0b11110}},
  {'t', {0b01000, 0b01000, 0b11100, 0b01000, 0b01000, 0b01001, 0b00110}},
  {'u', {0b00000, 0b00000, 0b10001, 0b10001, 0b10001, 0b10011, 0b01101}},
  {'v', {0b00000, 0b00000, 0b10001, 0b10001, 0b10001, 0b01010, 0b00100}},
  {'w', {0b00000, 0b00000, 0b10001, 0b10001, 0b10101, 0b10101, 0b01010}},
  {'x', {0b00000, 0b00000, 0b10001, 0b01010, 0b00100, 0b01010, 0b10001}},
  {'y', {0b00000, 0b00000, 0b10001, 0b10001, 0b01111, 0b00001, 0b01110}},
  {'z', {0b00000, 0b00000, 0b11111, 0b00010, 0b00100, 0b01000, 0b11111}},
  {'.', {0b00000, 0b00000, 0b00000, 0b00000, 0b00000, 0b01100, 0b01100}},
  {'-', {0b00000, 0b00000, 0b00000, 0b11111, 0b00000, 0b00000, 0b00000}},
  {'+', {0b00000, 0b00100, 0b00100, 0b11111, 0b00100, 0b00100, 0b00000}},
  {':', {0b00000, 0b01100, 0b01100, 0b00000, 0b01100, 0b01100, 0b00000}},
  {'/', {0b00000, 0b00001, 0b00010, 0b00100, 0b01000, 0b10000, 0b00000}},
  {'(', {0b00010, 0b00100, 0b01000, 0b01000, 0b01000, 0b00100, 0b00010}},
  {')', {0b01000, 0b00100, 0b00010, 0b00010, 0b00010, 0b00100, 0b01000}},
  {',', {0b00000, 0b00000, 0b00000, 0b00000, 0b01100, 0b00100, 0b01000}},
  {'=', {0b00000, 0b00000, 0b11111, 0b00000, 0b11111, 0b00000, 0b00000}},
  {'%', {0b11000, 0b11001, 0b00010, 0b00100, 0b01000, 0b10011, 0b00011}},
  {'_', {0b00000, 0b00000, 0b00000, 0b00000, 0b00000, 0b00000, 0b11111}},
  {'[', {0b01110, 0b01000, 0b01000, 0b01000, 0b01000, 0b01000, 0b01110}},
  {']', {0b01110, 0b00010, 0b00010, 0b00010, 0b00010, 0b00010, 0b01110}},
  {'<', {0b00010, 0b00100, 0b01000, 0b10000, 0b01000, 0b00100, 0b00010}},
  {'>', {0b01000, 0b00100, 0b00010, 0b00001, 0b00010, 0b00100, 0b01000}},
  {'*', {0b00000, 0b00100, 0b10101, 0b01110, 0b10101, 0b00100, 0b00000}},
  {'\'', {0b01100, 0b00100, 0b01000, 0b00000, 0b00000, 0b00000, 0b00000}},
  {'?', {0b01110, 0b10001, 0b00001, 0b00010, 0b00100, 0b00000, 0b00100}},
  {'!', {0b00100, 0b00100, 0b00100, 0b00100, 0b00100, 0b00000, 0b00100}},
  {';', {0b00000, 0b01100, 0b01100, 0b00000, 0b01100, 0b00100, 0b01000}},
};
// clang-format on

const Glyph& glyph(char c) {
  const Glyph* question = nullptr;
  for (const Glyph& g : kFont) {
    if (g.c == c) return g;
    if (g.c == '?') question = &g;
  }
  return *question;  // '?' is in the table, so the loop has passed it
}

// Twice the signed area of the triangle (a, b, p): the edge function of the rasterizer, with
// the same sign for every point on the same side of the line a-b.
double edge(double ax, double ay, double bx, double by, double px, double py) {
  return (bx - ax) * (py - ay) - (by - ay) * (px - ax);
}

}  // namespace

Image::Image(int width, int height, Rgb background)
    : width_(std::max(width, 0)),
      height_(std::max(height, 0)),
      background_(background),
      pixels_(size_t(width_) * height_ * 3) {
  for (size_t i = 0; i < pixels_.size(); i += 3) {
    pixels_[i] = background.r;
    pixels_[i + 1] = background.g;
    pixels_[i + 2] = background.b;
  }
}

Rgb Image::at(int x, int y) const {
  if (x < 0 || y < 0 || x >= width_ || y >= height_) return background_;
  const uint8_t* p = &pixels_[(size_t(y) * width_ + x) * 3];
  return Rgb{p[0], p[1], p[2]};
}

void Image::set(int x, int y, Rgb c) {
  if (x < 0 || y < 0 || x >= width_ || y >= height_) return;
  uint8_t* p = &pixels_[(size_t(y) * width_ + x) * 3];
  p[0] = c.r;
  p[1] = c.g;
  p[2] = c.b;
}

void Image::line(double x0, double y0, double x1, double y1, Rgb c, int thickness) {
  if (!std::isfinite(x0) || !std::isfinite(y0) || !std::isfinite(x1) || !std::isfinite(y1)) return;
  thickness = std::max(thickness, 1);
  const int lo = -(thickness - 1) / 2, hi = thickness / 2;
  auto stamp = [&](double x, double y) {
    const int px = static_cast<int>(std::floor(x)), py = static_cast<int>(std::floor(y));
    for (int dy = lo; dy <= hi; ++dy)
      for (int dx = lo; dx <= hi; ++dx) set(px + dx, py + dy, c);
  };
  // Samples less than a pixel apart along each axis give a connected line. Far-off lines
  // are clipped coarsely to a margin around the canvas first, so the loop stays short.
  const double margin = thickness + 2.0;
  const double xmin = -margin, xmax = width_ + margin, ymin = -margin, ymax = height_ + margin;
  double t0 = 0.0, t1 = 1.0;
  const double dx = x1 - x0, dy = y1 - y0;
  auto clip = [&](double p, double q) {  // Liang-Barsky: keep p t <= q
    if (p == 0.0) return q >= 0.0;
    const double r = q / p;
    if (p < 0.0)
      t0 = std::max(t0, r);
    else
      t1 = std::min(t1, r);
    return t0 <= t1;
  };
  if (!clip(-dx, x0 - xmin) || !clip(dx, xmax - x0) || !clip(-dy, y0 - ymin) ||
      !clip(dy, ymax - y0))
    return;
  const double ax = x0 + t0 * dx, ay = y0 + t0 * dy, bx = x0 + t1 * dx, by = y0 + t1 * dy;
  // Half a pixel apart: samples a whole pixel apart can round to k - 0.000001 and k + 1
  // and skip the pixel between.
  const int steps = std::max(
      1, static_cast<int>(std::ceil(2.0 * std::max(std::abs(bx - ax), std::abs(by - ay)))));
  for (int k = 0; k <= steps; ++k) {
    const double t = double(k) / steps;
    stamp(ax + t * (bx - ax), ay + t * (by - ay));
  }
}

void Image::fill_rect(int x0, int y0, int x1, int y1, Rgb c) {
  if (x0 > x1) std::swap(x0, x1);
  if (y0 > y1) std::swap(y0, y1);
  x0 = std::max(x0, 0);
  y0 = std::max(y0, 0);
  x1 = std::min(x1, width_ - 1);
  y1 = std::min(y1, height_ - 1);
  for (int y = y0; y <= y1; ++y)
    for (int x = x0; x <= x1; ++x) set(x, y, c);
}

void Image::triangle(const double x[3], const double y[3], const double z[3], Rgb c) {
  const double area = edge(x[0], y[0], x[1], y[1], x[2], y[2]);
  if (!(area != 0.0) || !std::isfinite(area)) return;
  const double fx0 = std::floor(std::min({x[0], x[1], x[2]}));
  const double fx1 = std::ceil(std::max({x[0], x[1], x[2]}));
  const double fy0 = std::floor(std::min({y[0], y[1], y[2]}));
  const double fy1 = std::ceil(std::max({y[0], y[1], y[2]}));
  const int ix0 = static_cast<int>(std::max(fx0, 0.0));
  const int iy0 = static_cast<int>(std::max(fy0, 0.0));
  const int ix1 = static_cast<int>(std::min(fx1, double(width_ - 1)));
  const int iy1 = static_cast<int>(std::min(fy1, double(height_ - 1)));
  if (ix0 > ix1 || iy0 > iy1) return;
  if (depth_.empty())
    depth_.assign(size_t(width_) * height_, std::numeric_limits<double>::infinity());
  const double inv = 1.0 / area;
  for (int py = iy0; py <= iy1; ++py) {
    const double cy = py + 0.5;
    for (int px = ix0; px <= ix1; ++px) {
      const double cx = px + 0.5;
      // Barycentric weights of the centre; all >= 0 inside whatever the winding.
      const double w0 = edge(x[1], y[1], x[2], y[2], cx, cy) * inv;
      const double w1 = edge(x[2], y[2], x[0], y[0], cx, cy) * inv;
      const double w2 = edge(x[0], y[0], x[1], y[1], cx, cy) * inv;
      if (w0 < 0.0 || w1 < 0.0 || w2 < 0.0) continue;
      const double depth = w0 * z[0] + w1 * z[1] + w2 * z[2];
      double& d = depth_[size_t(py) * width_ + px];
      if (!(depth < d)) continue;
      d = depth;
      set(px, py, c);
    }
  }
}

void Image::text(int x, int y, const std::string& s, Rgb c, int scale) {
  scale = std::max(scale, 1);
  for (size_t i = 0; i < s.size(); ++i) {
    const Glyph& g = glyph(s[i]);
    const int left = x + static_cast<int>(i) * 6 * scale;
    for (int row = 0; row < 7; ++row)
      for (int col = 0; col < 5; ++col)
        if (g.rows[row] & (0b10000 >> col))
          fill_rect(left + col * scale, y + row * scale, left + (col + 1) * scale - 1,
                    y + (row + 1) * scale - 1, c);
  }
}

int Image::text_width(const std::string& s, int scale) const {
  scale = std::max(scale, 1);
  return s.empty() ? 0 : (6 * static_cast<int>(s.size()) - 1) * scale;
}

bool write_png(const Image& image, const std::string& path, std::string& error) {
  if (image.width() <= 0 || image.height() <= 0) {
    error = path + ": cannot write an empty image";
    return false;
  }
  png_image info{};
  info.version = PNG_IMAGE_VERSION;
  info.width = static_cast<png_uint_32>(image.width());
  info.height = static_cast<png_uint_32>(image.height());
  info.format = PNG_FORMAT_RGB;
  const void* pixels = image.rgb_bytes().data();
  const png_int_32 stride = image.width() * 3;
  png_alloc_size_t bytes = 0;
  // The first call measures, the second encodes.
  if (!png_image_write_to_memory(&info, nullptr, &bytes, 0, pixels, stride, nullptr)) {
    error = path + ": cannot encode the PNG: " + info.message;
    png_image_free(&info);
    return false;
  }
  std::vector<uint8_t> encoded(bytes);
  if (!png_image_write_to_memory(&info, encoded.data(), &bytes, 0, pixels, stride, nullptr)) {
    error = path + ": cannot encode the PNG: " + info.message;
    png_image_free(&info);
    return false;
  }
  try {
    AtomicFile out(path);
    out.write(encoded.data(), bytes);
    out.commit();
  } catch (const MeshError& e) {
    error = e.what();
    return false;
  }
  return true;
}

}  // namespace simit::runtime
