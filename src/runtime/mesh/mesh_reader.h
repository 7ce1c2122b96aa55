// One entry point for every mesh file format, chosen by the file's extension.
#pragma once

#include <string>

#include "runtime/mesh/mesh.h"

namespace simit::runtime {

// TetGen for .node, .ele, .face and .edge (the whole BASE.* family is read), Gmsh for .msh,
// Wavefront for .obj. Throws MeshError for other extensions and for malformed files.
Mesh read_mesh(const std::string& path);

}  // namespace simit::runtime
