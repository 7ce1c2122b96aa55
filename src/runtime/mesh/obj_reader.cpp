// OBJ reader: a line-numbered validation pass, then tinyobjloader for parsing and polygon
// triangulation.
#include "runtime/mesh/obj_reader.h"

#include <algorithm>
#include <charconv>
#include <sstream>

#include "runtime/mesh/line_reader.h"

// The library's real_t must match the header's: tinyobjloader_double's CMake target defines
// this, and linking the float build by mistake would silently misread every coordinate.
#ifndef TINYOBJLOADER_USE_DOUBLE
#error "link tinyobjloader::tinyobjloader_double, which defines TINYOBJLOADER_USE_DOUBLE"
#endif
#include <tiny_obj_loader.h>

namespace simit::runtime {

namespace {

struct ObjCounts {
  long long v = 0, vt = 0, vn = 0;
};

// What the validation pass learned that the conversion from tinyobjloader's form needs.
struct ObjSummary {
  long long vertices = 0;
  long long triangles = 0;  // sum over faces of (corners - 2)
  int first_large_polygon_line = 0;
};

class ObjValidator {
 public:
  explicit ObjValidator(LineReader& in) : in_(in) {}
  ObjSummary run();

 private:
  void count_attributes();
  void numbers(size_t min, size_t max, const char* what);
  void reference(size_t i, bool face);
  void check_index(std::string_view part, size_t i, long long seen, long long total,
                   const char* noun);

  LineReader& in_;
  ObjCounts totals_;
  ObjCounts seen_;
};

// Totals over the whole file first: a positive index may refer to a later vertex.
void ObjValidator::count_attributes() {
  while (in_.next()) {
    if (in_[0] == "v") ++totals_.v;
    if (in_[0] == "vt") ++totals_.vt;
    if (in_[0] == "vn") ++totals_.vn;
  }
  in_.rewind();
}

ObjSummary ObjValidator::run() {
  count_attributes();
  ObjSummary summary;
  while (in_.next()) {
    std::string_view key = in_[0];
    if (key == "v") {
      numbers(3, 6, "a vertex coordinate");
      if (in_.size() == 6) in_.fail_token(5, "3 coordinates, then w or r g b");
      ++seen_.v;
    } else if (key == "vt") {
      numbers(1, 3, "a texture coordinate");
      ++seen_.vt;
    } else if (key == "vn") {
      numbers(3, 3, "a normal component");
      ++seen_.vn;
    } else if (key == "f" || key == "l") {
      bool face = key == "f";
      if (in_.size() < (face ? 4u : 3u))
        in_.fail_token(in_.size(), face ? "at least 3 face corners" : "at least 2 line points");
      for (size_t i = 1; i < in_.size(); ++i) reference(i, face);
      long long corners = static_cast<long long>(in_.size()) - 1;
      if (face) summary.triangles += corners - 2;
      if (face && corners > 4 && summary.first_large_polygon_line == 0)
        summary.first_large_polygon_line = in_.line();
    }
  }
  summary.vertices = totals_.v;
  return summary;
}

// Tokens 1.. are numbers, at least `min` and at most `max` of them.
void ObjValidator::numbers(size_t min, size_t max, const char* what) {
  for (size_t i = 1; i <= min || i < in_.size(); ++i) {
    if (i > max) in_.expect_end(max + 1, what);
    in_.number(i, what);
  }
}

// A face corner "v", "v/vt", "v//vn" or "v/vt/vn"; a line point "v" or "v/vt".
void ObjValidator::reference(size_t i, bool face) {
  std::string_view token = in_[i];
  size_t first = token.find('/');
  size_t second = first == std::string_view::npos ? first : token.find('/', first + 1);
  std::string_view v = token.substr(0, first);
  std::string_view vt, vn;
  if (first != std::string_view::npos) vt = token.substr(first + 1, second - first - 1);
  if (second != std::string_view::npos) vn = token.substr(second + 1);
  if (vn.find('/') != std::string_view::npos)
    in_.fail_token(i, "a face corner v, v/vt, v//vn or v/vt/vn");
  if (!face && second != std::string_view::npos) in_.fail_token(i, "a line point v or v/vt");
  check_index(v, i, seen_.v, totals_.v, "vertex");
  if (!vt.empty()) check_index(vt, i, seen_.vt, totals_.vt, "texture-coordinate");
  if (second != std::string_view::npos) check_index(vn, i, seen_.vn, totals_.vn, "normal");
}

// 1-based, or negative counting back from the last one defined so far; never 0.
void ObjValidator::check_index(std::string_view part, size_t i, long long seen, long long total,
                               const char* noun) {
  long long value = 0;
  auto [end, ec] = std::from_chars(part.data(), part.data() + part.size(), value);
  bool parsed = ec == std::errc() && end == part.data() + part.size() && !part.empty();
  // Compared without negating `value`: -LLONG_MIN overflows.
  if (parsed && (value > 0 ? value <= total : value < 0 && value >= -seen)) return;
  std::string n = noun;
  if (total == 0) in_.fail_token(i, "no " + n + " index (the file defines no " + n + "s)");
  std::string range = "in 1.." + std::to_string(total);
  if (seen > 0) range += " or -1..-" + std::to_string(seen);
  in_.fail_token(i, "a " + n + " index " + range);
}

void append_shape(const tinyobj::shape_t& shape, Mesh& mesh) {
  const auto& corners = shape.mesh.indices;
  for (size_t i = 0; i + 2 < corners.size(); i += 3)
    mesh.triangles.push_back(
        {corners[i].vertex_index, corners[i + 1].vertex_index, corners[i + 2].vertex_index});
  const auto& points = shape.lines.indices;
  size_t at = 0;
  for (int n : shape.lines.num_line_vertices) {
    for (int k = 0; k + 1 < n; ++k)
      mesh.edges.push_back({points[at + k].vertex_index, points[at + k + 1].vertex_index});
    at += n;
  }
}

// The records the validation pass saw, as tinyobjloader must see them: it reads a '#' after a
// face's corners as a corner, ends a line at a lone '\r' and separates tokens by ' ' and '\t'
// only, where the validation pass takes '\r', '\v' and '\f' for spaces.
std::string as_validated(const std::string& text) {
  std::string out;
  out.reserve(text.size());
  for (size_t pos = 0; pos < text.size();) {
    size_t eol = std::min(text.find('\n', pos), text.size());
    size_t hash = std::min(text.find('#', pos), eol);
    for (size_t i = pos; i < hash; ++i)
      out.push_back(text[i] == '\r' || text[i] == '\v' || text[i] == '\f' ? ' ' : text[i]);
    out.push_back('\n');
    pos = eol + 1;
  }
  return out;
}

Mesh load_with_tinyobj(const std::string& path, const std::string& text) {
  std::istringstream stream(as_validated(text));
  tinyobj::attrib_t attrib;
  std::vector<tinyobj::shape_t> shapes;
  std::vector<tinyobj::material_t> materials;
  std::string warn, err;
  // No material reader: mtllib lines are ignored rather than opening other files.
  if (!tinyobj::LoadObj(&attrib, &shapes, &materials, &warn, &err, &stream, nullptr, true, false))
    throw MeshError(path, 0, "tinyobjloader could not read the file: " + err);
  Mesh mesh;
  const auto& v = attrib.vertices;
  for (size_t i = 0; i + 2 < v.size(); i += 3) mesh.points.push_back({v[i], v[i + 1], v[i + 2]});
  for (const tinyobj::shape_t& shape : shapes) append_shape(shape, mesh);
  // OBJ counts from 1 (triangles counted after polygons are split, lines by segment).
  mesh.point_numbers.first = mesh.triangle_numbers.first = mesh.edge_numbers.first = 1;
  return mesh;
}

}  // namespace

Mesh read_obj(const std::string& path) {
  LineReader in(path, '#');
  ObjSummary summary = ObjValidator(in).run();
  Mesh mesh = load_with_tinyobj(path, in.text());
  if (static_cast<long long>(mesh.points.size()) != summary.vertices)
    throw MeshError(path, 0,
                    "expected " + std::to_string(summary.vertices) +
                        " vertices, tinyobjloader read " + std::to_string(mesh.points.size()));
  long long missing = summary.triangles - static_cast<long long>(mesh.triangles.size());
  if (missing != 0)
    throw MeshError(path, summary.first_large_polygon_line,
                    "expected simple polygons: tinyobjloader could not triangulate them (" +
                        std::to_string(missing) +
                        " triangles missing; this line has the first polygon of over 4 corners)");
  // A backstop: the two passes agree on every record, so no index is out of range here.
  check_indices(mesh);
  return mesh;
}

}  // namespace simit::runtime
