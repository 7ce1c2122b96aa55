// Plain mesh data as read from mesh files (points and element vertex lists), its error type,
// and the checks a mesh must pass before sets are built from it.
#pragma once

#include <array>
#include <stdexcept>
#include <string>
#include <vector>

namespace simit::runtime {

using Point = std::array<double, 3>;
using Tet = std::array<int, 4>;
using Triangle = std::array<int, 3>;
using Edge = std::array<int, 2>;

// Vertex indices are 0-based positions in `points`, whatever base the file used. Readers keep
// the element order and the vertex order within each element exactly as in the file. TetGen
// and Gmsh write tets with det[x0-x3 | x1-x3 | x2-x3] < 0 ("TetGen's orientation", the one the
// FEM rest volume -det/6 assumes); orient_tets brings any other mesh to it.
// How a file numbers its vertices or elements, for messages: a number per item (Gmsh tags),
// or, with `ids` empty, consecutive numbers from `first` (TetGen's 0 or 1, OBJ's 1).
struct Numbering {
  long long first = 0;
  std::vector<long long> ids;
  long long of(size_t i) const { return ids.empty() ? first + static_cast<long long>(i) : ids[i]; }
};

struct Mesh {
  std::vector<Point> points;
  std::vector<Tet> tets;
  std::vector<Triangle> triangles;
  std::vector<Edge> edges;
  // Defaulted, so that a mesh written as {points, tets, ...} needs no numbering.
  Numbering point_numbers = {}, tet_numbers = {}, triangle_numbers = {}, edge_numbers = {};
};

// A mesh file that cannot be read or written, or a mesh that fails a check. The message is
// "file:line: expected ..." when a line is known, "file: ..." when only the file is.
class MeshError : public std::runtime_error {
 public:
  explicit MeshError(const std::string& message) : std::runtime_error(message) {}
  MeshError(const std::string& file, int line, const std::string& message);

  const std::string& file() const { return file_; }
  int line() const { return line_; }  // 0 when the error has no line

 private:
  std::string file_;
  int line_ = 0;
};

enum class ElementKind { Tet, Triangle, Edge };
const char* element_kind_name(ElementKind kind);  // "tet", "triangle", "edge"

// Throws MeshError naming the first element (kind and index) that has a vertex index outside
// [0, points.size()).
void check_indices(const Mesh& mesh);

// det[x0-x3 | x1-x3 | x2-x3] of tet `t`: negative for TetGen's orientation, six times the
// signed volume up to sign.
double tet_orientation_det(const Mesh& mesh, const Tet& t);

// Swaps the first two vertices of every tet with a positive orientation determinant so that
// all tets follow TetGen's orientation; returns how many were flipped.
int orient_tets(Mesh& mesh);

// An element whose size is (near) zero relative to its own longest edge: measure is
// |volume| / L^3 for tets, area / L^2 for triangles, length / (bounding-box diagonal) for
// edges, and 0 when the element repeats a vertex; NaN when its volume (area, length)
// overflows double precision.
struct Degenerate {
  ElementKind kind;
  int index;
  double measure;
};

// A regular tet has measure 0.118 and a regular triangle 0.433; the default tolerance only
// flags elements that are flat to rounding error. Indices must be valid (check_indices).
std::vector<Degenerate> find_degenerate(const Mesh& mesh, double tolerance = 1e-12);

// check_indices, finite coordinates, then find_degenerate; throws MeshError "NAME: tet 12 (vertices
// ...) has zero volume" for the first problem, where NAME says which mesh (usually its file).
void check_mesh(const Mesh& mesh, const std::string& name, double tolerance = 1e-12);

}  // namespace simit::runtime
