// An RGB raster canvas (lines, rectangles, depth-tested triangles, 5x7 bitmap text) and an
// atomic 8-bit PNG writer: the drawing surface of quick-look pictures and plots.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace simit::runtime {

struct Rgb {
  uint8_t r, g, b;
  friend bool operator==(const Rgb&, const Rgb&) = default;
};

// Pixel (x, y) covers [x, x + 1) x [y, y + 1) with its centre at (x + 0.5, y + 0.5); (0, 0)
// is the top-left corner and y grows downwards. Drawing is clipped to the canvas.
class Image {
 public:
  // A width x height canvas (each clamped to >= 0) filled with `background`.
  Image(int width, int height, Rgb background);

  int width() const { return width_; }
  int height() const { return height_; }
  // The pixel at (x, y); a point outside the canvas reads as the background.
  Rgb at(int x, int y) const;
  // Sets one pixel; out of range is ignored. Does not touch the depth buffer.
  void set(int x, int y, Rgb c);

  // A line from (x0, y0) to (x1, y1) in pixel coordinates, 8-connected, both end pixels
  // (floor of the coordinates) included; `thickness` > 1 stamps a thickness x thickness square
  // centred on each pixel of the line.
  void line(double x0, double y0, double x1, double y1, Rgb c, int thickness = 1);
  // Fills the pixels from (x0, y0) to (x1, y1), both corners included, in either order.
  void fill_rect(int x0, int y0, int x1, int y1, Rgb c);
  // Filled triangle with a depth test (smaller z is nearer); the z-buffer is lazily created.
  // Covers the pixels whose centres lie inside or on its edges (either winding), with z
  // interpolated linearly at the centre; a pixel is written when its z is strictly smaller
  // than the z-buffer's, so the picture does not depend on the drawing order of triangles at
  // different depths. A triangle of zero area draws nothing.
  void triangle(const double x[3], const double y[3], const double z[3], Rgb c);
  // Text in a built-in 5x7 bitmap font (digits, letters, . - + e : / ( ) , = % and space),
  // scale >= 1; also _ [ ] < > * ' ? ! ; and any other character draws as '?'. (x, y) is the
  // top-left corner of the first character cell; each character advances 6 * scale pixels.
  void text(int x, int y, const std::string& s, Rgb c, int scale = 1);
  // The width in pixels of `s` as drawn by text(): 6 * scale per character, less the one
  // blank column after the last (0 for an empty string).
  int text_width(const std::string& s, int scale = 1) const;
  static int text_height(int scale = 1) { return 7 * scale; }

  // The pixels, row by row from the top, 3 bytes (r, g, b) per pixel.
  const std::vector<uint8_t>& rgb_bytes() const { return pixels_; }

 private:
  int width_, height_;
  Rgb background_;
  std::vector<uint8_t> pixels_;
  std::vector<double> depth_;  // empty until the first triangle
};

// Writes an 8-bit RGB PNG atomically (temporary name, then rename). Returns false and sets `error`
// on failure.
bool write_png(const Image& image, const std::string& path, std::string& error);

}  // namespace simit::runtime
