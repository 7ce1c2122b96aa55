// The meshes a scene's sets are built from, each read (or generated) and checked once and
// kept for every later run of the scene.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "runtime/mesh/mesh.h"
#include "scene/scene_file.h"

namespace simit::scene {

// A mesh's vertices renumbered for locality. Empty orders stand for the identity (a mesh with
// no elements, or a renumbering that changed nothing).
struct MeshOrder {
  std::vector<int32_t> vertex_order;     // new -> old
  std::vector<int32_t> vertex_position;  // old -> new
  runtime::Mesh renumbered;              // the points in the new order, no elements
  bool identity() const { return vertex_order.empty(); }
};

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
  // The vertex order of the mesh at `path` (read or generated before), made on first use:
  // `how` on the vertex graph of all its elements (tets, triangles and edges).
  const MeshOrder& order(const std::string& path, Reorder how);

 private:
  std::map<std::string, runtime::Mesh> meshes_;
  std::map<std::pair<std::string, Reorder>, MeshOrder> orders_;
};

}  // namespace simit::scene
