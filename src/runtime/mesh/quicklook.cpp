// Quick-look rendering: project, fit, draw shaded triangles on a canvas of twice the size and
// average 2 x 2 blocks down for smooth edges; or depth-cued lines or points, drawn directly
// in a few shades (dense wireframes smoothed or finely shaded compress badly as PNG).
#include "runtime/mesh/quicklook.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "runtime/mesh/topology.h"

namespace simit::runtime {

namespace {

constexpr int kSupersample = 2;  // for surfaces
constexpr int kDepthShades = 8;  // for lines and points
constexpr Rgb kBackground{248, 248, 245};
constexpr double kAmbient = 0.3;

struct Vec3 {
  double x, y, z;
};
Vec3 sub(const Point& a, const Point& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
Vec3 cross(Vec3 a, Vec3 b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
double dot(Vec3 a, Vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
Vec3 normalized(Vec3 a) {
  const double n = std::sqrt(dot(a, a));
  return n > 0 ? Vec3{a.x / n, a.y / n, a.z / n} : a;
}

const double kInvSqrt3 = 1.0 / std::sqrt(3.0);
const Vec3 kRight{QuicklookView::kRight[0], QuicklookView::kRight[1], QuicklookView::kRight[2]};
const Vec3 kUp{QuicklookView::kUp[0], QuicklookView::kUp[1], QuicklookView::kUp[2]};
const Vec3 kTowardViewer{kInvSqrt3, kInvSqrt3, kInvSqrt3};
// Light from the upper left, somewhat behind the viewer.
const Vec3 kLight = normalized({kTowardViewer.x + 0.6 * kUp.x - 0.4 * kRight.x,
                                kTowardViewer.y + 0.6 * kUp.y - 0.4 * kRight.y,
                                kTowardViewer.z + 0.6 * kUp.z - 0.4 * kRight.z});

bool finite(const Point& p) {
  return std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]);
}

Rgb scaled(Rgb c, double f) {
  auto ch = [f](uint8_t v) { return static_cast<uint8_t>(std::clamp(v * f, 0.0, 255.0) + 0.5); };
  return Rgb{ch(c.r), ch(c.g), ch(c.b)};
}

Rgb mix(Rgb a, Rgb b, double t) {
  auto ch = [t](uint8_t x, uint8_t y) { return static_cast<uint8_t>(x + (y - x) * t + 0.5); };
  return Rgb{ch(a.r, b.r), ch(a.g, b.g), ch(a.b, b.b)};
}

// Screen positions (supersampled pixels) and depths of the mesh's points.
struct Projection {
  std::vector<double> x, y, depth;
  double depth_min = 0, depth_max = 0;
};

Projection project(const Mesh& mesh, int width, int height, int margin) {
  Projection p;
  const size_t n = mesh.points.size();
  p.x.resize(n);
  p.y.resize(n);
  p.depth.resize(n);
  double u0 = std::numeric_limits<double>::infinity(), u1 = -u0, v0 = u0, v1 = -u0;
  p.depth_min = u0;
  p.depth_max = -u0;
  for (size_t i = 0; i < n; ++i) {
    const Point& q = mesh.points[i];
    const Vec3 v{q[0], q[1], q[2]};
    p.x[i] = dot(v, kRight);
    p.y[i] = dot(v, kUp);
    p.depth[i] = -dot(v, kTowardViewer);
    if (!finite(q)) continue;
    u0 = std::min(u0, p.x[i]), u1 = std::max(u1, p.x[i]);
    v0 = std::min(v0, p.y[i]), v1 = std::max(v1, p.y[i]);
    p.depth_min = std::min(p.depth_min, p.depth[i]);
    p.depth_max = std::max(p.depth_max, p.depth[i]);
  }
  if (!(u0 <= u1)) return p;  // no finite point
  const double du = u1 - u0, dv = v1 - v0;
  const double room_x = std::max(width - 2.0 * margin, 1.0);
  const double room_y = std::max(height - 2.0 * margin, 1.0);
  double s = std::min(du > 0 ? room_x / du : INFINITY, dv > 0 ? room_y / dv : INFINITY);
  if (!std::isfinite(s)) s = 1.0;  // a single point
  const double uc = (u0 + u1) / 2, vc = (v0 + v1) / 2;
  for (size_t i = 0; i < n; ++i) {
    p.x[i] = width / 2.0 + (p.x[i] - uc) * s;
    p.y[i] = height / 2.0 - (p.y[i] - vc) * s;  // v grows upwards, pixel rows downwards
  }
  return p;
}

// Triangles shaded on both sides: the normal is turned toward the viewer before lighting.
void draw_triangles(Image& canvas, const Mesh& mesh, const Projection& p,
                    const std::vector<Triangle>& triangles, Rgb base) {
  for (const Triangle& t : triangles) {
    const Point &a = mesh.points[t[0]], &b = mesh.points[t[1]], &c = mesh.points[t[2]];
    if (!finite(a) || !finite(b) || !finite(c)) continue;
    Vec3 n = normalized(cross(sub(b, a), sub(c, a)));
    if (dot(n, kTowardViewer) < 0) n = {-n.x, -n.y, -n.z};
    const double light = kAmbient + (1.0 - kAmbient) * std::max(0.0, dot(n, kLight));
    const double x[3] = {p.x[t[0]], p.x[t[1]], p.x[t[2]]};
    const double y[3] = {p.y[t[0]], p.y[t[1]], p.y[t[2]]};
    const double z[3] = {p.depth[t[0]], p.depth[t[1]], p.depth[t[2]]};
    canvas.triangle(x, y, z, scaled(base, light));
  }
}

// `near` faded toward the background with depth, in kDepthShades steps.
Rgb depth_cue(Rgb near, double depth, const Projection& p) {
  const double range = p.depth_max - p.depth_min;
  const double far = range > 0 ? (depth - p.depth_min) / range : 0.0;
  const double step = std::floor(std::clamp(far, 0.0, 1.0) * (kDepthShades - 1) + 0.5);
  return mix(near, kBackground, 0.65 * step / (kDepthShades - 1));
}

// Lines drawn far to near, the far ones faded toward the background (depth cueing).
void draw_edges(Image& canvas, const Mesh& mesh, const Projection& p) {
  const Rgb near{40, 60, 110};
  std::vector<size_t> order;
  std::vector<double> depth(mesh.edges.size());
  for (size_t e = 0; e < mesh.edges.size(); ++e) {
    const Edge& ed = mesh.edges[e];
    if (!finite(mesh.points[ed[0]]) || !finite(mesh.points[ed[1]])) continue;
    depth[e] = (p.depth[ed[0]] + p.depth[ed[1]]) / 2;
    order.push_back(e);
  }
  std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return depth[a] > depth[b]; });
  for (size_t e : order) {
    const Edge& ed = mesh.edges[e];
    canvas.line(p.x[ed[0]], p.y[ed[0]], p.x[ed[1]], p.y[ed[1]], depth_cue(near, depth[e], p));
  }
}

void draw_points(Image& canvas, const Mesh& mesh, const Projection& p) {
  const Rgb near{40, 60, 110};
  std::vector<size_t> order;
  for (size_t i = 0; i < mesh.points.size(); ++i)
    if (finite(mesh.points[i])) order.push_back(i);
  std::sort(order.begin(), order.end(),
            [&](size_t a, size_t b) { return p.depth[a] > p.depth[b]; });
  for (size_t i : order) {
    const int x = static_cast<int>(std::floor(p.x[i])), y = static_cast<int>(std::floor(p.y[i]));
    canvas.fill_rect(x, y, x + 1, y + 1, depth_cue(near, p.depth[i], p));
  }
}

// Averages each k x k block of `big` into one pixel.
Image downsample(const Image& big, int width, int height, int k) {
  Image out(width, height, kBackground);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      int r = 0, g = 0, b = 0;
      for (int dy = 0; dy < k; ++dy)
        for (int dx = 0; dx < k; ++dx) {
          const Rgb c = big.at(x * k + dx, y * k + dy);
          r += c.r, g += c.g, b += c.b;
        }
      const int n = k * k;
      out.set(x, y,
              Rgb{uint8_t((r + n / 2) / n), uint8_t((g + n / 2) / n), uint8_t((b + n / 2) / n)});
    }
  return out;
}

}  // namespace

Image render_quicklook(const Mesh& mesh, const QuicklookOptions& options) {
  const int width = std::max(options.width, 1), height = std::max(options.height, 1);
  const int margin = std::max(options.margin, 0);
  if (mesh.tets.empty() && mesh.triangles.empty()) {
    Image canvas(width, height, kBackground);
    const Projection p = project(mesh, width, height, margin);
    if (!mesh.edges.empty())
      draw_edges(canvas, mesh, p);
    else
      draw_points(canvas, mesh, p);
    return canvas;
  }
  const int k = kSupersample;
  Image canvas(width * k, height * k, kBackground);
  const Projection p = project(mesh, width * k, height * k, margin * k);
  if (!mesh.tets.empty())
    draw_triangles(canvas, mesh, p, boundary_triangles(mesh), Rgb{214, 172, 112});
  else
    draw_triangles(canvas, mesh, p, mesh.triangles, Rgb{112, 152, 212});
  return downsample(canvas, width, height, k);
}

bool write_quicklook(const Mesh& mesh, const std::string& path, std::string& error,
                     const QuicklookOptions& options) {
  Image image(0, 0, kBackground);
  try {
    image = render_quicklook(mesh, options);
  } catch (const MeshError& e) {
    error = e.what();
    return false;
  }
  return write_png(image, path, error);
}

}  // namespace simit::runtime
