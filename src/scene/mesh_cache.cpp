// Reading, checking and generating the meshes of a scene, once each.
#include "scene/mesh_cache.h"

#include <filesystem>
#include <span>

#include "runtime/mesh/mesh_reader.h"
#include "runtime/mesh/reorder.h"

namespace simit::scene {

namespace fs = std::filesystem;

namespace {

// An N x N grid of points on the unit square in the xz-plane (y = 0, point i + N j at
// (i, 0, j) / (N - 1)), each cell split into the triangles (p, p+1, p+N+1) and (p, p+N+1,
// p+N) -- the cloth of bench/baselines/cloth_baseline.cpp.
runtime::Mesh square_cloth(int side) {
  runtime::Mesh m;
  m.points.resize(size_t(side) * side);
  for (int j = 0; j < side; ++j)
    for (int i = 0; i < side; ++i)
      m.points[size_t(i) + size_t(side) * j] = {double(i) / (side - 1), 0.0,
                                                double(j) / (side - 1)};
  for (int j = 0; j + 1 < side; ++j)
    for (int i = 0; i + 1 < side; ++i) {
      const int p = i + side * j;
      m.triangles.push_back({p, p + 1, p + side + 1});
      m.triangles.push_back({p, p + side + 1, p + side});
    }
  return m;
}

}  // namespace

std::string MeshCache::generate(const SceneFile& file, const toml::table& t,
                                const std::string& tname) {
  std::string kind = file.required_string(t, tname, "generate");
  if (kind != "square_cloth")
    file.fail(t.get("generate"),
              tname + " generate: '" + kind + "' is not a generator (expected square_cloth)");
  const toml::node* nn = t.get("n");
  if (!nn)
    file.fail(t.get("generate"), tname + ": generate = \"square_cloth\" needs n (points per side)");
  if (!nn->is_integer() || *nn->value<int64_t>() < 2 || *nn->value<int64_t>() > 4096)
    file.fail(nn, tname + " n: expected a whole number from 2 to 4096 (points per side)");
  const int side = static_cast<int>(*nn->value<int64_t>());
  std::string key = "square_cloth(n = " + std::to_string(side) + ")";
  if (!meshes_.count(key)) meshes_.emplace(key, square_cloth(side));
  return key;
}

const runtime::Mesh& MeshCache::read(const SceneFile& file, const std::string& path,
                                     const toml::node* at, const std::string& key) {
  auto it = meshes_.find(path);
  if (it != meshes_.end()) return it->second;
  if (!fs::exists(path)) file.fail(at, key + ": no such file '" + path + "'");
  try {
    runtime::Mesh m = runtime::read_mesh(path);
    runtime::check_mesh(m, path);
    // A tet listed in the other orientation would have a negative rest volume in every FEM
    // program written for TetGen's (-det/6); swapping two of its vertices is the same tet.
    runtime::orient_tets(m);
    return meshes_.emplace(path, std::move(m)).first->second;
  } catch (const runtime::MeshError& e) {
    file.fail(at, key + ": " + e.what());
  }
}

const MeshOrder& MeshCache::order(const std::string& path, Reorder how) {
  auto found = orders_.find({path, how});
  if (found != orders_.end()) return found->second;
  const runtime::Mesh& m = meshes_.at(path);
  const int32_t n = static_cast<int32_t>(m.points.size());
  MeshOrder o;
  if (how != Reorder::Off) o.vertex_order = runtime::locality_order(m, how == Reorder::Hilbert);
  if (!o.identity()) {
    o.vertex_position = runtime::invert_permutation(o.vertex_order);
    o.renumbered.points.resize(m.points.size());
    for (int32_t i = 0; i < n; ++i) o.renumbered.points[i] = m.points[o.vertex_order[i]];
  }
  return orders_.emplace(std::make_pair(path, how), std::move(o)).first->second;
}

}  // namespace simit::scene
