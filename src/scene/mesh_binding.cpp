// Building a scene's sets from its meshes.
#include "scene/mesh_binding.h"

#include <filesystem>
#include <string>
#include <vector>

#include "api/binding_check.h"
#include "runtime/mesh/reorder.h"
#include "runtime/mesh/topology.h"
#include "scene/field_values.h"

namespace simit::scene {

namespace ast = frontend::ast;
using runtime::FieldType;

namespace {

const std::map<std::string, Elements> kElementNames = {
    {"vertices", Elements::Vertices},   {"tets", Elements::Tets},
    {"triangles", Elements::Triangles}, {"edges", Elements::Edges},
    {"tet_edges", Elements::TetEdges},  {"boundary_triangles", Elements::BoundaryTriangles},
    {"hinges", Elements::Hinges},
};

std::string table_name(const SceneSet& s) { return "[sets." + s.name + "]"; }

// One [sets.NAME] table: its extern, its mesh and its kind of elements (nothing built yet).
std::unique_ptr<SceneSet> declare_set(const SceneFile& file, MeshCache& meshes,
                                      const std::string& name, const toml::node& node,
                                      const ast::Variable& var) {
  const std::string tname = "[sets." + name + "]";
  const toml::table* t = node.as_table();
  file.check_keys(*t, tname, {"mesh", "generate", "n", "elements", "fields"});
  auto s = std::make_unique<SceneSet>();
  s->name = name;
  s->table = t;
  s->var = &var;
  if (t->get("generate")) {
    if (t->get("mesh"))
      file.fail(t->get("generate"), tname + ": give either mesh or generate, not both");
    s->mesh_path = meshes.generate(file, *t, tname);
  } else {
    if (t->get("n")) file.fail(t->get("n"), tname + " n: only for generate");
    s->mesh_path = file.resolve(file.required_string(*t, tname, "mesh"));
  }
  std::string el = file.required_string(*t, tname, "elements");
  auto e = kElementNames.find(el);
  if (e == kElementNames.end())
    file.fail(t->get("elements"), tname + " elements: '" + el +
                                      "' is not one of vertices, tets, "
                                      "triangles, edges, tet_edges, boundary_triangles, hinges");
  s->elements = e->second;
  if (var.type->grid_dims > 0)
    file.fail(&node,
              tname + ": extern '" + name + "' is a grid; scenes bind only vertex and edge sets");
  return s;
}

void declare_sets(const SceneFile& file, MeshCache& meshes, BoundSets& out) {
  const toml::table* sets = file.doc["sets"].as_table();
  if (!sets)
    file.fail(file.doc.get("sets"),
              "the scene needs a [sets] table binding the program's extern sets");
  const std::map<std::string, const ast::Variable*> externs = program_externs(file, true);
  for (auto&& [key, node] : *sets) {
    std::string name(key.str());
    if (!node.as_table()) file.fail(&node, "sets." + name + ": expected a table");
    auto ext = externs.find(name);
    if (ext == externs.end())
      file.fail(&node, "[sets." + name + "]: the program declares no extern set '" + name + "'");
    out.sets.push_back(declare_set(file, meshes, name, node, *ext->second));
    out.by_name[name] = out.sets.back().get();
  }
  for (const auto& [name, var] : externs)
    if (!out.by_name.count(name))
      file.fail(nullptr, "[sets]: the program's extern set '" + name +
                             "' is not bound (add [sets." + name + "])");
}

// The elements of an edge set, `arity` vertex indices each.
void connect(SceneSet& s, const runtime::Mesh& m) {
  std::vector<int32_t>& c = s.connectivity;
  auto append = [&](const auto& list) {
    for (const auto& el : list) c.insert(c.end(), el.begin(), el.end());
  };
  switch (s.elements) {
    case Elements::Tets:
      s.arity = 4;
      append(m.tets);
      break;
    case Elements::Triangles:
      s.arity = 3;
      append(m.triangles);
      break;
    case Elements::Edges:
      s.arity = 2;
      if (!m.edges.empty())
        append(m.edges);
      else if (!m.tets.empty())
        append(runtime::tet_edges(m.tets));
      else
        append(runtime::triangle_edges(m.triangles));
      break;
    case Elements::TetEdges:
      s.arity = 2;
      append(runtime::tet_edges(m.tets));
      break;
    case Elements::BoundaryTriangles:
      s.arity = 3;
      append(runtime::boundary_triangles(m));
      break;
    case Elements::Hinges:
      s.arity = 4;
      append(runtime::hinges(m.triangles.empty() ? runtime::boundary_triangles(m) : m.triangles));
      break;
    case Elements::Vertices: break;
  }
}

// Why a TetGen mesh gave no elements of the kind asked for, when the companion files they
// come from (BASE.ele, .face, .edge) are missing; "" otherwise.
std::string missing_companions(const SceneSet& s) {
  const std::string& path = s.mesh_path;
  if (!(path.ends_with(".node") || path.ends_with(".ele") || path.ends_with(".face") ||
        path.ends_with(".edge")))
    return "";
  std::vector<const char*> sources;
  switch (s.elements) {
    case Elements::Tets:
    case Elements::TetEdges: sources = {".ele"}; break;
    case Elements::Triangles: sources = {".face"}; break;
    case Elements::Edges: sources = {".edge", ".ele", ".face"}; break;
    case Elements::BoundaryTriangles:
    case Elements::Hinges: sources = {".face", ".ele"}; break;
    case Elements::Vertices: return "";
  }
  const std::string base = path.substr(0, path.rfind('.'));
  std::string files;
  for (size_t i = 0; i < sources.size(); ++i) {
    std::error_code ec;
    if (std::filesystem::exists(base + sources[i], ec)) return "";
    files += (i == 0                    ? ""
              : i + 1 == sources.size() ? " or "
                                        : ", ") +
             ("'" + base + sources[i] + "'");
  }
  return sources.size() == 1 ? ": they come from " + files + ", which does not exist"
                             : ": they come from " + files + ", none of which exists";
}

void make_vertex_set(const SceneFile& file, SceneSet& s, const runtime::Mesh& m,
                     const MeshOrder& order) {
  const size_t ends = s.var->type->endpoints.size();
  if (ends != 0)
    file.fail(s.table->get("elements"), table_name(s) + ": extern '" + s.name +
                                            "' is an edge set with " + std::to_string(ends) +
                                            " endpoints, but elements = \"vertices\"");
  s.set = std::make_unique<runtime::Set>(s.name);
  s.set->add_many(static_cast<int>(m.points.size()));
  if (!order.identity()) s.set->set_mesh_numbers(order.vertex_order);
}

// The elements renumbered with their vertices (the vertex order within each kept) and sorted
// by their smallest new vertex, so that neighbouring elements run together; each keeps its
// number in the mesh's own element list.
std::vector<int32_t> renumber(SceneSet& s, const MeshOrder& order) {
  if (order.identity()) return {};
  const runtime::ElementList list{s.connectivity, s.arity};
  std::vector<int32_t> elements = runtime::element_order(list, order.vertex_position);
  s.connectivity = runtime::renumber_elements(list, elements, order.vertex_position);
  return elements;
}

void make_edge_set(const SceneFile& file, SceneSet& s, const runtime::Mesh& m,
                   const MeshOrder& order, const BoundSets& all) {
  const std::string tname = table_name(s);
  try {
    connect(s, m);
  } catch (const runtime::MeshError& e) {
    file.fail(s.table->get("elements"), tname + " elements: " + e.what());
  }
  if (s.connectivity.empty())
    file.fail(s.table->get("elements"), tname + ": the mesh '" + s.mesh_path + "' gives no " +
                                            s.table->get("elements")->value<std::string>().value() +
                                            missing_companions(s));
  const std::vector<frontend::IndexSet>& ends = s.var->type->endpoints;
  if (static_cast<int>(ends.size()) != s.arity)
    file.fail(s.table->get("elements"), tname + ": extern '" + s.name + "' has " +
                                            std::to_string(ends.size()) +
                                            " endpoints per element, but its elements have " +
                                            std::to_string(s.arity) + " vertices");
  std::vector<const runtime::Set*> endpoint_sets;
  for (const frontend::IndexSet& end : ends) {
    auto it = end.var ? all.by_name.find(end.var->name) : all.by_name.end();
    if (it == all.by_name.end())
      file.fail(s.table, tname + ": its endpoint set is not bound in the scene");
    const SceneSet& v = *it->second;
    if (v.elements != Elements::Vertices || v.mesh_path != s.mesh_path)
      file.fail(s.table->get("mesh"), tname + ": its endpoints are in '" + v.name +
                                          "', which must be the vertices of the same mesh ('" +
                                          s.mesh_path + "')");
    endpoint_sets.push_back(v.set.get());
  }
  std::vector<int32_t> mesh_numbers = renumber(s, order);
  s.set = std::make_unique<runtime::Set>(s.name, endpoint_sets);
  s.set->add_edges(std::span<const int32_t>(s.connectivity));
  if (!mesh_numbers.empty()) s.set->set_mesh_numbers(std::move(mesh_numbers));
}

// Every field the element type declares, zero until the scene or `init` sets it.
void add_fields(const SceneFile& file, SceneSet& s, bool float32) {
  const ast::ElementDecl* decl = s.var->type->element;
  for (const ast::FieldDecl& f : decl->fields) {
    std::optional<FieldType> ft =
        f.type ? api::field_type_for(*f.type, float32 ? 4 : 8) : std::nullopt;
    if (!ft)
      file.fail(s.table, table_name(s) + ": field '" + f.name + "' of element " + decl->name +
                             " has a type host sets cannot store");
    s.set->add_field(f.name, *ft);
  }
}

}  // namespace

BoundSets declared_sets(const SceneFile& file, MeshCache& meshes) {
  BoundSets out;
  declare_sets(file, meshes, out);
  return out;
}

BoundSets build_sets(const SceneFile& file, MeshCache& meshes, bool float32, Reorder reorder) {
  BoundSets out;
  declare_sets(file, meshes, out);
  // Vertex sets first: edge sets name them as endpoints.
  for (int pass = 0; pass < 2; ++pass) {
    for (auto& sp : out.sets) {
      SceneSet& s = *sp;
      const bool vertex = s.elements == Elements::Vertices;
      if (vertex != (pass == 0)) continue;
      const runtime::Mesh& m =
          meshes.read(file, s.mesh_path, s.table->get("mesh"), table_name(s) + " mesh");
      const MeshOrder& order = meshes.order(s.mesh_path, reorder);
      if (vertex)
        make_vertex_set(file, s, m, order);
      else
        make_edge_set(file, s, m, order, out);
      add_fields(file, s, float32);
      // Field values per element from the positions in the new vertex order.
      init_fields(file, s, order.identity() ? m : order.renumbered);
    }
  }
  return out;
}

}  // namespace simit::scene
