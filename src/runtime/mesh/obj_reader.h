// Reader of Wavefront OBJ surface meshes, through tinyobjloader.
#pragma once

#include <string>

#include "runtime/mesh/mesh.h"

namespace simit::runtime {

// Reads vertices (v) into points, faces (f) into triangles (polygons are triangulated, keeping
// their winding), and polylines (l) into edges, one per segment; normals, texture
// coordinates and materials are ignored. Throws MeshError "file:line: expected ..." on
// malformed input, checked before tinyobjloader sees the file since it reports no lines.
Mesh read_obj(const std::string& path);

}  // namespace simit::runtime
