// Derived element sets, each built by sorting element sub-faces so that equal ones meet.
#include "runtime/mesh/topology.h"

#include <algorithm>
#include <string>
#include <tuple>

namespace simit::runtime {

namespace {

template <size_t N>
std::vector<Edge> unique_edges(const std::vector<std::array<int, N>>& elements) {
  std::vector<Edge> edges;
  edges.reserve(elements.size() * N * (N - 1) / 2);
  for (const auto& e : elements)
    for (size_t i = 0; i < N; ++i)
      for (size_t j = i + 1; j < N; ++j)
        if (e[i] != e[j]) edges.push_back({std::min(e[i], e[j]), std::max(e[i], e[j])});
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  return edges;
}

// The faces of a tet in TetGen's orientation, each wound outward.
constexpr int kOutwardFaces[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};

struct FaceRef {
  Triangle key;  // sorted vertices
  int tet;
  int local;
  bool operator<(const FaceRef& o) const {
    return std::tie(key, tet, local) < std::tie(o.key, o.tet, o.local);
  }
};

std::vector<FaceRef> all_faces(const std::vector<Tet>& tets) {
  std::vector<FaceRef> faces;
  faces.reserve(tets.size() * 4);
  for (size_t t = 0; t < tets.size(); ++t) {
    for (int f = 0; f < 4; ++f) {
      Triangle key{tets[t][kOutwardFaces[f][0]], tets[t][kOutwardFaces[f][1]],
                   tets[t][kOutwardFaces[f][2]]};
      std::sort(key.begin(), key.end());
      faces.push_back({key, static_cast<int>(t), f});
    }
  }
  std::sort(faces.begin(), faces.end());
  return faces;
}

Triangle outward_face(const Mesh& mesh, int tet, int local) {
  const Tet& t = mesh.tets[tet];
  const int* f = kOutwardFaces[local];
  Triangle tri{t[f[0]], t[f[1]], t[f[2]]};
  if (tet_orientation_det(mesh, t) > 0) std::swap(tri[1], tri[2]);
  return tri;
}

// A triangle's directed edge from corner `from` to the next corner.
struct HalfEdge {
  int lo, hi;
  int triangle;
  int from;
  bool operator<(const HalfEdge& o) const {
    return std::tie(lo, hi, triangle, from) < std::tie(o.lo, o.hi, o.triangle, o.from);
  }
};

std::vector<HalfEdge> all_half_edges(const std::vector<Triangle>& triangles) {
  std::vector<HalfEdge> half;
  half.reserve(triangles.size() * 3);
  for (size_t t = 0; t < triangles.size(); ++t) {
    for (int k = 0; k < 3; ++k) {
      int a = triangles[t][k], b = triangles[t][(k + 1) % 3];
      if (a == b)
        throw MeshError("triangle " + std::to_string(t) + " repeats vertex " + std::to_string(a));
      half.push_back({std::min(a, b), std::max(a, b), static_cast<int>(t), k});
    }
  }
  std::sort(half.begin(), half.end());
  return half;
}

std::string edge_name(const HalfEdge& h) {
  return "edge (" + std::to_string(h.lo) + " " + std::to_string(h.hi) + ")";
}

Hinge make_hinge(const std::vector<Triangle>& triangles, const HalfEdge& h1, const HalfEdge& h2) {
  const Triangle& t1 = triangles[h1.triangle];
  const Triangle& t2 = triangles[h2.triangle];
  int a = t1[h1.from], b = t1[(h1.from + 1) % 3], c = t1[(h1.from + 2) % 3];
  if (t2[h2.from] != b)
    throw MeshError("triangles " + std::to_string(h1.triangle) + " and " +
                    std::to_string(h2.triangle) + " traverse their shared " + edge_name(h1) +
                    " in the same direction: the surface is not consistently oriented");
  return {a, b, c, t2[(h2.from + 2) % 3]};
}

}  // namespace

std::vector<Edge> tet_edges(const std::vector<Tet>& tets) { return unique_edges(tets); }

std::vector<Edge> triangle_edges(const std::vector<Triangle>& triangles) {
  return unique_edges(triangles);
}

std::vector<Triangle> boundary_triangles(const Mesh& mesh) {
  check_indices(mesh);
  std::vector<FaceRef> faces = all_faces(mesh.tets);
  std::vector<FaceRef> boundary;
  for (size_t i = 0; i < faces.size();) {
    size_t j = i;
    while (j < faces.size() && faces[j].key == faces[i].key) ++j;
    if (j - i > 2)
      throw MeshError("tets " + std::to_string(faces[i].tet) + ", " +
                      std::to_string(faces[i + 1].tet) + " and " +
                      std::to_string(faces[i + 2].tet) + " share a face: not a manifold mesh");
    if (j - i == 1) boundary.push_back(faces[i]);
    i = j;
  }
  std::sort(boundary.begin(), boundary.end(), [](const FaceRef& x, const FaceRef& y) {
    return std::tie(x.tet, x.local) < std::tie(y.tet, y.local);
  });
  std::vector<Triangle> out;
  out.reserve(boundary.size());
  for (const FaceRef& f : boundary) out.push_back(outward_face(mesh, f.tet, f.local));
  return out;
}

std::vector<Hinge> hinges(const std::vector<Triangle>& triangles) {
  std::vector<HalfEdge> half = all_half_edges(triangles);
  std::vector<Hinge> out;
  for (size_t i = 0; i < half.size();) {
    size_t j = i;
    while (j < half.size() && half[j].lo == half[i].lo && half[j].hi == half[i].hi) ++j;
    if (j - i > 2)
      throw MeshError(std::to_string(j - i) + " triangles share " + edge_name(half[i]) +
                      " (triangles " + std::to_string(half[i].triangle) + ", " +
                      std::to_string(half[i + 1].triangle) + ", " +
                      std::to_string(half[i + 2].triangle) + "): not a manifold surface");
    if (j - i == 2) out.push_back(make_hinge(triangles, half[i], half[i + 1]));
    i = j;
  }
  return out;
}

}  // namespace simit::runtime
