// simit::read_mesh: a mesh file read and checked the way a scene reads its meshes.
#include <filesystem>

#include "runtime/mesh/mesh.h"
#include "runtime/mesh/mesh_reader.h"
#include "simit/mesh.h"

namespace simit {

MeshData read_mesh(const std::string& path) {
  if (!std::filesystem::exists(path)) throw Error(path + ": no such file");
  try {
    runtime::Mesh m = runtime::read_mesh(path);
    runtime::check_mesh(m, path);
    runtime::orient_tets(m);
    return MeshData{std::move(m.points), std::move(m.tets), std::move(m.triangles),
                    std::move(m.edges)};
  } catch (const runtime::MeshError& e) {
    throw Error(e.what());
  }
}

}  // namespace simit
