// Mesh files as plain arrays: the readers `simit run` uses (TetGen, Gmsh, Wavefront OBJ),
// with their checks, for hosts that build sets themselves.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "simit/element.h"

namespace simit {

// Vertex indices are 0-based positions in `points`, whatever base the file used; tets follow
// TetGen's orientation (the FEM examples' rest volume assumes it), flipped where a file had
// the other one. Lists the file does not have are empty.
struct MeshData {
  std::vector<std::array<double, 3>> points;
  std::vector<std::array<int, 4>> tets;
  std::vector<std::array<int, 3>> triangles;
  std::vector<std::array<int, 2>> edges;
};

// TetGen for .node, .ele, .face and .edge (the whole BASE.* family is read), Gmsh for .msh,
// Wavefront for .obj. Throws Error naming the file (and line) for an unreadable or malformed
// file, another extension, or an element with a vertex index out of range.
MeshData read_mesh(const std::string& path);

}  // namespace simit
