// Dispatch of read_mesh on the file extension.
#include "runtime/mesh/mesh_reader.h"

#include "runtime/mesh/gmsh_reader.h"
#include "runtime/mesh/obj_reader.h"
#include "runtime/mesh/tetgen_reader.h"

namespace simit::runtime {

Mesh read_mesh(const std::string& path) {
  auto has = [&](const char* ext) { return path.ends_with(ext); };
  if (has(".node") || has(".ele") || has(".face") || has(".edge")) return read_tetgen(path);
  if (has(".msh")) return read_gmsh(path);
  if (has(".obj")) return read_obj(path);
  throw MeshError(path, 0,
                  "expected a mesh file ending in .node, .ele, .face, .edge, .msh or .obj");
}

}  // namespace simit::runtime
