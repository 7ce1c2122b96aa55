// Reader of Gmsh's ASCII .msh files, format versions 2.2 and 4.1.
#pragma once

#include <string>

#include "runtime/mesh/mesh.h"

namespace simit::runtime {

// Reads every node (in file order; node tags become 0-based positions) and the elements
// Simit uses: tetrahedra (type 4) into tets, triangles (type 2) into triangles, lines (type
// 1) into edges, keeping the corners of their second-order forms (11, 9, 8). Other element
// types and other sections are skipped. Gmsh's positive tets follow TetGen's orientation.
// Throws MeshError "file:line: expected ..." on malformed input, and for binary files.
Mesh read_gmsh(const std::string& path);

}  // namespace simit::runtime
