// A small scatter/line plot of two CSV columns into a PNG (log or linear axes, one series per
// value of a third column, tick labels and a legend): bench/fem_accuracy.py's plotter where
// gnuplot is not installed.
//
// Usage: plot_png CSV PNG --x COL --y COL [--series COL] [--title TEXT] [--xlabel TEXT]
//                 [--ylabel TEXT] [--linear-x] [--linear-y] [--size WxH]
// Axes are logarithmic unless --linear-x / --linear-y; points that a log axis cannot show
// (<= 0) or that do not parse are left out, with a count on stderr. Within a series the points
// are joined in the order of the file.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "runtime/image.h"

using simit::runtime::Image;
using simit::runtime::Rgb;

namespace {

struct Series {
  std::string name;
  std::vector<double> x, y;
};

struct Axis {
  double lo = 0, hi = 1;
  bool log = true;
  double unit(double v) const {  // 0 at lo, 1 at hi
    return log ? (std::log10(v) - std::log10(lo)) / (std::log10(hi) - std::log10(lo))
               : (v - lo) / (hi - lo);
  }
};

[[noreturn]] void usage(const std::string& why) {
  std::fprintf(stderr,
               "plot_png: %s\nusage: plot_png CSV PNG --x COL --y COL [--series COL] "
               "[--title TEXT] [--xlabel TEXT] [--ylabel TEXT] [--linear-x] [--linear-y] "
               "[--size WxH]\n",
               why.c_str());
  std::exit(2);
}

std::vector<std::string> split(const std::string& line) {
  std::vector<std::string> out;
  std::stringstream s(line);
  std::string cell;
  while (std::getline(s, cell, ',')) {
    while (!cell.empty() && (cell.back() == '\r' || cell.back() == ' ')) cell.pop_back();
    out.push_back(cell);
  }
  return out;
}

bool parse(const std::string& s, double& v) {
  char* end = nullptr;
  v = std::strtod(s.c_str(), &end);
  return !s.empty() && end == s.c_str() + s.size() && std::isfinite(v);
}

// The data range, widened by a margin so that no point sits on the frame.
void fit(Axis& a, const std::vector<double>& values) {
  a.lo = *std::min_element(values.begin(), values.end());
  a.hi = *std::max_element(values.begin(), values.end());
  if (a.log) {
    double l = std::log10(a.lo), h = std::log10(a.hi);
    if (h - l < 1e-9) l -= 0.5, h += 0.5;
    const double pad = 0.06 * (h - l);
    a.lo = std::pow(10.0, l - pad);
    a.hi = std::pow(10.0, h + pad);
  } else {
    if (a.hi - a.lo < 1e-12 * std::max(1.0, std::fabs(a.hi))) a.lo -= 0.5, a.hi += 0.5;
    const double pad = 0.06 * (a.hi - a.lo);
    a.lo -= pad;
    a.hi += pad;
  }
}

// 1, 2 or 5 times a power of ten, near `raw`.
double nice_step(double raw) {
  const double p = std::pow(10.0, std::floor(std::log10(raw)));
  const double m = raw / p;
  return (m < 1.5 ? 1 : m < 3.5 ? 2 : m < 7.5 ? 5 : 10) * p;
}

// Tick values inside the axis: whole decades when a log axis spans two or more of them
// (every k-th, at most about 8), otherwise evenly spaced round numbers.
std::vector<double> ticks(const Axis& a, bool& decades) {
  std::vector<double> out;
  decades = a.log && std::log10(a.hi) - std::log10(a.lo) >= 2.0;
  if (decades) {
    const int first = static_cast<int>(std::ceil(std::log10(a.lo) - 1e-9));
    const int last = static_cast<int>(std::floor(std::log10(a.hi) + 1e-9));
    const int every = std::max(1, (last - first + 8) / 8);
    for (int k = first; k <= last; ++k)
      if ((k - first) % every == 0) out.push_back(std::pow(10.0, k));
    return out;
  }
  const double step = nice_step((a.hi - a.lo) / 5.0);
  for (double v = std::ceil(a.lo / step) * step; v <= a.hi + 1e-9 * step; v += step)
    if (!a.log || v > 0) out.push_back(std::fabs(v) < 1e-12 * step ? 0.0 : v);
  return out;
}

std::string label(double v, bool decade) {
  char buf[32];
  if (decade) std::snprintf(buf, sizeof buf, "1e%d", static_cast<int>(std::lround(std::log10(v))));
  else std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

// A rectangle's outline. Axis-parallel strokes are filled rectangles: Image::line samples
// along the line and can skip a pixel where a sample lands just below a pixel boundary.
void frame(Image& img, int x0, int y0, int x1, int y1, Rgb c) {
  img.fill_rect(x0, y0, x1, y0, c);
  img.fill_rect(x0, y1, x1, y1, c);
  img.fill_rect(x0, y0, x0, y1, c);
  img.fill_rect(x1, y0, x1, y1, c);
}

// Marker shapes by series: square, triangle, diamond, cross.
void marker(Image& img, int shape, double x, double y, Rgb c) {
  const double r = 5;
  const double z[3] = {0, 0, 0};
  switch (shape % 4) {
    case 0: img.fill_rect(int(x - r + 1), int(y - r + 1), int(x + r - 1), int(y + r - 1), c); break;
    case 1: {
      const double px[3] = {x - r, x + r, x}, py[3] = {y + r - 1, y + r - 1, y - r};
      img.triangle(px, py, z, c);
      break;
    }
    case 2: {
      const double ax[3] = {x - r, x + r, x}, ay[3] = {y, y, y - r};
      const double bx[3] = {x - r, x + r, x}, by[3] = {y, y, y + r};
      img.triangle(ax, ay, z, c);
      img.triangle(bx, by, z, c);
      break;
    }
    default:
      img.line(x - r, y - r, x + r, y + r, c, 2);
      img.line(x - r, y + r, x + r, y - r, c, 2);
  }
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> positional;
  std::string xcol, ycol, scol, title, xlabel, ylabel;
  Axis ax, ay;
  int width = 820, height = 580;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) usage(a + " needs a value");
      return argv[++i];
    };
    if (a == "--x") xcol = value();
    else if (a == "--y") ycol = value();
    else if (a == "--series") scol = value();
    else if (a == "--title") title = value();
    else if (a == "--xlabel") xlabel = value();
    else if (a == "--ylabel") ylabel = value();
    else if (a == "--linear-x") ax.log = false;
    else if (a == "--linear-y") ay.log = false;
    else if (a == "--size") {
      if (std::sscanf(value().c_str(), "%dx%d", &width, &height) != 2 || width < 200 ||
          height < 150)
        usage("--size needs WxH, at least 200x150");
    } else if (a.starts_with("--")) usage("unknown option " + a);
    else positional.push_back(a);
  }
  if (positional.size() != 2) usage("expected CSV and PNG");
  if (xcol.empty() || ycol.empty()) usage("--x and --y are required");

  std::ifstream in(positional[0]);
  if (!in) usage("cannot read " + positional[0]);
  std::string line;
  std::getline(in, line);
  const std::vector<std::string> header = split(line);
  auto column = [&](const std::string& name) {
    const auto it = std::find(header.begin(), header.end(), name);
    if (it == header.end()) usage(positional[0] + " has no column '" + name + "'");
    return static_cast<size_t>(it - header.begin());
  };
  const size_t xi = column(xcol), yi = column(ycol);
  const size_t si = scol.empty() ? header.size() : column(scol);
  std::vector<Series> series;
  std::vector<double> all_x, all_y;
  int skipped = 0;
  while (std::getline(in, line)) {
    if (line.empty()) continue;
    const std::vector<std::string> cells = split(line);
    double x, y;
    if (cells.size() <= std::max(xi, yi) || !parse(cells[xi], x) || !parse(cells[yi], y) ||
        (ax.log && x <= 0) || (ay.log && y <= 0)) {
      ++skipped;
      continue;
    }
    const std::string name = si < cells.size() ? cells[si] : ycol;
    auto it = std::find_if(series.begin(), series.end(),
                           [&](const Series& s) { return s.name == name; });
    if (it == series.end()) it = series.insert(series.end(), Series{name, {}, {}});
    it->x.push_back(x);
    it->y.push_back(y);
    all_x.push_back(x);
    all_y.push_back(y);
  }
  if (skipped)
    std::fprintf(stderr, "plot_png: left out %d row(s) without a plottable point\n", skipped);
  if (all_x.empty()) usage("no points to plot in " + positional[0]);
  fit(ax, all_x);
  fit(ay, all_y);

  const Rgb white{255, 255, 255}, black{0, 0, 0}, grid{225, 225, 225};
  const Rgb palette[] = {{31, 119, 180}, {214, 39, 40}, {44, 160, 44},
                         {148, 103, 189}, {255, 127, 14}, {23, 190, 207}};
  Image img(width, height, white);
  const int left = 100, right = width - 24, top = title.empty() ? 40 : 56, bottom = height - 64;
  auto px = [&](double x) { return left + ax.unit(x) * (right - left); };
  auto py = [&](double y) { return bottom - ay.unit(y) * (bottom - top); };

  bool xdec = false, ydec = false;
  for (double t : ticks(ax, xdec)) {
    const double x = px(t);
    img.fill_rect(int(x), top, int(x), bottom, grid);
    img.fill_rect(int(x), bottom, int(x), bottom + 5, black);
    const std::string s = label(t, xdec);
    img.text(int(x) - img.text_width(s, 2) / 2, bottom + 10, s, black, 2);
  }
  for (double t : ticks(ay, ydec)) {
    const double y = py(t);
    img.fill_rect(left, int(y), right, int(y), grid);
    img.fill_rect(left - 5, int(y), left, int(y), black);
    const std::string s = label(t, ydec);
    img.text(left - 10 - img.text_width(s, 2), int(y) - Image::text_height(2) / 2, s, black, 2);
  }
  frame(img, left, top, right, bottom, black);
  if (!title.empty()) img.text((width - img.text_width(title, 2)) / 2, 14, title, black, 2);
  if (!xlabel.empty())
    img.text((left + right - img.text_width(xlabel, 2)) / 2, height - 26, xlabel, black, 2);
  // No rotated text: the y label sits above the axis.
  if (!ylabel.empty()) img.text(8, top - 20, ylabel, black, 2);

  for (size_t k = 0; k < series.size(); ++k) {
    const Series& s = series[k];
    const Rgb c = palette[k % 6];
    for (size_t i = 1; i < s.x.size(); ++i)
      img.line(px(s.x[i - 1]), py(s.y[i - 1]), px(s.x[i]), py(s.y[i]), c, 1);
    for (size_t i = 0; i < s.x.size(); ++i)
      marker(img, static_cast<int>(k), px(s.x[i]), py(s.y[i]), c);
  }
  // Legend: in the corner of the frame that covers the fewest points (top right on a tie).
  int legend_w = 0;
  for (const Series& s : series) legend_w = std::max(legend_w, img.text_width(s.name, 2));
  legend_w += 60;
  const int row_h = 22, legend_h = row_h * int(series.size()) + 8;
  int lx = right - legend_w - 10, ly = top + 10, covered = -1;
  for (int corner = 0; corner < 4; ++corner) {
    const int cx = corner % 2 == 0 ? right - legend_w - 10 : left + 10;
    const int cy = corner < 2 ? top + 10 : bottom - legend_h - 10;
    int n = 0;
    for (const Series& s : series)
      for (size_t i = 0; i < s.x.size(); ++i) {
        const double x = px(s.x[i]), y = py(s.y[i]);
        n += x > cx - 8 && x < cx + legend_w + 8 && y > cy - 8 && y < cy + legend_h + 8;
      }
    if (covered < 0 || n < covered) covered = n, lx = cx, ly = cy;
  }
  img.fill_rect(lx, ly, lx + legend_w, ly + legend_h, white);
  frame(img, lx, ly, lx + legend_w, ly + legend_h, black);
  for (size_t k = 0; k < series.size(); ++k) {
    const int y = ly + 14 + row_h * int(k);
    const Rgb c = palette[k % 6];
    img.fill_rect(lx + 8, y - 1, lx + 40, y, c);
    marker(img, static_cast<int>(k), lx + 24, y, c);
    img.text(lx + 50, y - Image::text_height(2) / 2, series[k].name, black, 2);
  }

  std::string error;
  if (!simit::runtime::write_png(img, positional[1], error)) {
    std::fprintf(stderr, "plot_png: %s\n", error.c_str());
    return 1;
  }
  return 0;
}
