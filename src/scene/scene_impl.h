// What an opened scene holds: its options (with the scene file's executor keys applied), the
// parsed file with its compiled program, and the meshes read once for every run.
#pragma once

#include <memory>

#include "scene/mesh_cache.h"
#include "scene/scene_file.h"
#include "simit/scene.h"

namespace simit::interp {
class Trap;
}

namespace simit::scene {

struct Scene::Impl {
  SceneOptions options;
  std::unique_ptr<SceneFile> file;
  MeshCache meshes;  // read once, shared by every run
  interp::Trap* trap = nullptr;

  // How this run numbers the meshes' elements: the step debugger takes and shows element
  // indices (breakpoints, watches, frames), and some hosts index the sets by mesh numbers,
  // so their runs keep each mesh's own order.
  Reorder reorder() const { return trap || options.keep_mesh_order ? Reorder::Off : file->reorder; }
};

}  // namespace simit::scene
