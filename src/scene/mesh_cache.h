// The meshes a scene's sets are built from, each read (or generated) and checked once and
// kept for every later run of the scene.
#pragma once

#include <map>
#include <string>

#include "runtime/mesh/mesh.h"
#include "scene/scene_file.h"

namespace simit::scene {

class MeshCache {
 public:
  // The mesh file `path` (resolved), read and checked on first use; problems are reported at
  // `at` under `key`.
  const runtime::Mesh& read(const SceneFile& file, const std::string& path, const toml::node* at,
                            const std::string& key);
  // `generate = "square_cloth"`, `n = N` of the set table `t`: the key that stands for the
  // generated mesh's path (sets generated with the same n share one mesh).
  std::string generate(const SceneFile& file, const toml::table& t, const std::string& tname);
  const runtime::Mesh& at(const std::string& path) const { return meshes_.at(path); }

 private:
  std::map<std::string, runtime::Mesh> meshes_;
};

}  // namespace simit::scene
