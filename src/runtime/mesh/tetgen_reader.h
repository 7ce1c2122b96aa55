// Reader of TetGen's mesh files: .node (vertices), .ele (tets), .face (triangles), .edge.
#pragma once

#include <string>

#include "runtime/mesh/mesh.h"

namespace simit::runtime {

// Reads BASE.node and, where they exist, BASE.ele, BASE.face and BASE.edge; `path` is BASE
// or any one of those four files. As in TetGen, the first vertex index of the .node file (0
// or 1) fixes the base of every index; the mesh returned is 0-based. Quadratic (10-node)
// tets keep their 4 corners. Throws MeshError "file:line: expected ..." on malformed input.
Mesh read_tetgen(const std::string& path);

}  // namespace simit::runtime
