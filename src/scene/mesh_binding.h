// [sets]: each extern set of the program bound to the vertices or elements of a mesh, built
// as a runtime set with every field its element type declares (zero until [sets.S.fields] or
// `init` sets it). Endpoint sets must be the vertices of the same mesh.
#pragma once

#include <map>
#include <memory>
#include <string>
#include <vector>

#include "runtime/set.h"
#include "scene/mesh_cache.h"
#include "scene/scene_file.h"

namespace simit::scene {

// How the elements of a set come from its mesh.
enum class Elements { Vertices, Tets, Triangles, Edges, TetEdges, BoundaryTriangles, Hinges };

struct SceneSet {
  std::string name;
  std::string mesh_path;  // resolved, or the generated mesh's key
  Elements elements = Elements::Vertices;
  const toml::table* table = nullptr;            // [sets.NAME]
  const frontend::ast::Variable* var = nullptr;  // the program's extern
  // Built in the mesh's renumbered order (MeshCache::order) when the scene reorders; the set's
  // mesh numbers (runtime::Set::mesh_number) give each element's number in the mesh.
  std::unique_ptr<runtime::Set> set;
  std::vector<int32_t> connectivity;  // arity indices per element (not for vertices), as the set
  int arity = 0;
};

struct BoundSets {
  std::vector<std::unique_ptr<SceneSet>> sets;  // in the scene's order
  std::map<std::string, SceneSet*> by_name;
};

// Builds every set of [sets] (vertex sets first) and initialises its fields, each mesh
// renumbered as `reorder` says. Throws SceneError: an extern the scene leaves unbound or does
// not know, a bad mesh or elements, a field value that does not fit.
BoundSets build_sets(const SceneFile& file, MeshCache& meshes, bool float32, Reorder reorder);
// The sets of [sets] declared (names, externs, meshes, kinds of elements) but not built: a
// distributed run's ranks other than 0, which receive their parts from rank 0 instead.
BoundSets declared_sets(const SceneFile& file, MeshCache& meshes);

}  // namespace simit::scene
