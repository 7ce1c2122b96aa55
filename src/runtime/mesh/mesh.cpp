// Index, orientation and degeneracy checks of plain meshes.
#include "runtime/mesh/mesh.h"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace simit::runtime {

namespace {

Point sub(const Point& a, const Point& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }

Point cross(const Point& a, const Point& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}

double dot(const Point& a, const Point& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

double norm(const Point& a) { return std::sqrt(dot(a, a)); }

template <size_t N>
bool repeats_vertex(const std::array<int, N>& e) {
  for (size_t i = 0; i < N; ++i)
    for (size_t j = i + 1; j < N; ++j)
      if (e[i] == e[j]) return true;
  return false;
}

template <size_t N>
double longest_edge(const Mesh& mesh, const std::array<int, N>& e) {
  double longest = 0;
  for (size_t i = 0; i < N; ++i)
    for (size_t j = i + 1; j < N; ++j)
      longest = std::max(longest, norm(sub(mesh.points[e[i]], mesh.points[e[j]])));
  return longest;
}

template <size_t N>
void check_element_indices(const std::vector<std::array<int, N>>& elements, ElementKind kind,
                           size_t vertex_count) {
  for (size_t i = 0; i < elements.size(); ++i) {
    for (int v : elements[i]) {
      if (v >= 0 && static_cast<size_t>(v) < vertex_count) continue;
      std::ostringstream msg;
      msg << element_kind_name(kind) << " " << i << ": vertex index " << v;
      if (v < 0)
        msg << " is negative";
      else
        msg << " is beyond the vertex count " << vertex_count;
      throw MeshError(msg.str());
    }
  }
}

double bounding_box_diagonal(const Mesh& mesh) {
  if (mesh.points.empty()) return 0;
  Point lo = mesh.points[0], hi = mesh.points[0];
  for (const Point& p : mesh.points) {
    for (int k = 0; k < 3; ++k) {
      lo[k] = std::min(lo[k], p[k]);
      hi[k] = std::max(hi[k], p[k]);
    }
  }
  return norm(sub(hi, lo));
}

// Dividing by the element's own size makes the test independent of the mesh's units. A
// volume or area that overflows (coordinates near 1e300) is NaN: the program could not compute
// it either, so such an element fails the check instead of slipping past a comparison.
double tet_measure(const Mesh& mesh, const Tet& t) {
  double l = longest_edge(mesh, t);
  if (repeats_vertex(t) || l == 0) return 0;
  const double det = tet_orientation_det(mesh, t);
  if (!std::isfinite(det) || !std::isfinite(l * l * l)) return NAN;
  return std::abs(det) / 6 / (l * l * l);
}

double triangle_measure(const Mesh& mesh, const Triangle& t) {
  double l = longest_edge(mesh, t);
  if (repeats_vertex(t) || l == 0) return 0;
  const Point& a = mesh.points[t[0]];
  const double twice_area = norm(cross(sub(mesh.points[t[1]], a), sub(mesh.points[t[2]], a)));
  if (!std::isfinite(twice_area) || !std::isfinite(l * l)) return NAN;
  return twice_area / 2 / (l * l);
}

// In the file's own numbering of elements and vertices.
std::string describe(const Mesh& mesh, const Degenerate& d) {
  std::ostringstream msg;
  const Numbering& numbers = d.kind == ElementKind::Tet        ? mesh.tet_numbers
                             : d.kind == ElementKind::Triangle ? mesh.triangle_numbers
                                                               : mesh.edge_numbers;
  msg << element_kind_name(d.kind) << " " << numbers.of(static_cast<size_t>(d.index))
      << " (vertices";
  auto list = [&](const auto& e) {
    for (int v : e) msg << " " << mesh.point_numbers.of(static_cast<size_t>(v));
  };
  if (d.kind == ElementKind::Tet) list(mesh.tets[d.index]);
  if (d.kind == ElementKind::Triangle) list(mesh.triangles[d.index]);
  if (d.kind == ElementKind::Edge) list(mesh.edges[d.index]);
  const char* what = d.kind == ElementKind::Tet        ? "volume"
                     : d.kind == ElementKind::Triangle ? "area"
                                                       : "length";
  if (std::isnan(d.measure)) {
    msg << ") has " << (d.kind == ElementKind::Triangle ? "an " : "a ") << what
        << " beyond the range of double precision (coordinates too large)";
    return msg.str();
  }
  msg << ") has " << (d.measure == 0 ? "zero " : "near-zero ") << what << " (relative size "
      << d.measure << ")";
  return msg.str();
}

}  // namespace

MeshError::MeshError(const std::string& file, int line, const std::string& message)
    : std::runtime_error(file + (line > 0 ? ":" + std::to_string(line) : "") + ": " + message),
      file_(file),
      line_(line) {}

const char* element_kind_name(ElementKind kind) {
  switch (kind) {
    case ElementKind::Tet: return "tet";
    case ElementKind::Triangle: return "triangle";
    case ElementKind::Edge: return "edge";
  }
  return "element";
}

void check_indices(const Mesh& mesh) {
  check_element_indices(mesh.tets, ElementKind::Tet, mesh.points.size());
  check_element_indices(mesh.triangles, ElementKind::Triangle, mesh.points.size());
  check_element_indices(mesh.edges, ElementKind::Edge, mesh.points.size());
}

double tet_orientation_det(const Mesh& mesh, const Tet& t) {
  const Point& x3 = mesh.points[t[3]];
  Point a = sub(mesh.points[t[0]], x3), b = sub(mesh.points[t[1]], x3),
        c = sub(mesh.points[t[2]], x3);
  return dot(a, cross(b, c));
}

int orient_tets(Mesh& mesh) {
  int flipped = 0;
  for (Tet& t : mesh.tets) {
    if (tet_orientation_det(mesh, t) > 0) {
      std::swap(t[0], t[1]);
      ++flipped;
    }
  }
  return flipped;
}

std::vector<Degenerate> find_degenerate(const Mesh& mesh, double tolerance) {
  std::vector<Degenerate> found;
  for (size_t i = 0; i < mesh.tets.size(); ++i) {
    double m = tet_measure(mesh, mesh.tets[i]);
    if (!(m > tolerance)) found.push_back({ElementKind::Tet, static_cast<int>(i), m});
  }
  for (size_t i = 0; i < mesh.triangles.size(); ++i) {
    double m = triangle_measure(mesh, mesh.triangles[i]);
    if (!(m > tolerance)) found.push_back({ElementKind::Triangle, static_cast<int>(i), m});
  }
  double diagonal = bounding_box_diagonal(mesh);
  for (size_t i = 0; i < mesh.edges.size(); ++i) {
    const Edge& e = mesh.edges[i];
    double l = norm(sub(mesh.points[e[0]], mesh.points[e[1]]));
    double m = (e[0] == e[1] || diagonal == 0) ? 0 : l / diagonal;
    if (!std::isfinite(l) || !std::isfinite(diagonal)) m = NAN;
    if (!(m > tolerance)) found.push_back({ElementKind::Edge, static_cast<int>(i), m});
  }
  return found;
}

void check_mesh(const Mesh& mesh, const std::string& name, double tolerance) {
  try {
    check_indices(mesh);
  } catch (const MeshError& e) {
    throw MeshError(name, 0, e.what());
  }
  for (size_t i = 0; i < mesh.points.size(); ++i)
    for (double c : mesh.points[i])
      if (!std::isfinite(c))
        throw MeshError(
            name, 0,
            "vertex " + std::to_string(i) + " has a coordinate that is not a finite number");
  std::vector<Degenerate> bad = find_degenerate(mesh, tolerance);
  if (bad.empty()) return;
  std::string more = bad.size() > 1
                         ? " (and " + std::to_string(bad.size() - 1) + " more degenerate elements)"
                         : "";
  throw MeshError(name, 0, describe(mesh, bad.front()) + more);
}

}  // namespace simit::runtime
