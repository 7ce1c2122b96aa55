// `simit run SCENE.toml`: reads and checks a scene, builds the sets from meshes, runs the
// program's init and step procedures and writes a ParaView series.
#include "scene_command.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <deque>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <sstream>
#include <stdexcept>
#include <vector>

#include <toml++/toml.h>  // Debian names the header toml.h (upstream also ships toml.hpp)

#include "api/binding_check.h"
#include "api/tensor_values.h"
#include "frontend/ast.h"
#include "frontend/frontend.h"
#include "frontend/types.h"
#include "runtime/mesh/atomic_file.h"
#include "runtime/mesh/mesh.h"
#include "runtime/mesh/mesh_reader.h"
#include "runtime/mesh/pvd_writer.h"
#include "runtime/mesh/quicklook.h"
#include "runtime/mesh/topology.h"
#include "scene_expr.h"
#include "simit/simit.h"

namespace simit::tools {

namespace ast = frontend::ast;
namespace fs = std::filesystem;
using frontend::Type;
using runtime::ComponentKind;
using runtime::FieldType;

namespace {

// A problem with the scene; the message is complete ("FILE:line:col: error: ...").
struct SceneError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// How the elements of a set come from its mesh.
enum class Elements { Vertices, Tets, Triangles, Edges, TetEdges, BoundaryTriangles, Hinges };
const std::map<std::string, Elements> kElementNames = {
    {"vertices", Elements::Vertices},
    {"tets", Elements::Tets},
    {"triangles", Elements::Triangles},
    {"edges", Elements::Edges},
    {"tet_edges", Elements::TetEdges},
    {"boundary_triangles", Elements::BoundaryTriangles},
    {"hinges", Elements::Hinges},
};

struct SceneSet {
  std::string name;
  std::string mesh_path;  // resolved
  Elements elements = Elements::Vertices;
  const toml::table* table = nullptr;
  const ast::Variable* var = nullptr;  // the program's extern
  std::unique_ptr<simit::Set> set;
  std::vector<int32_t> connectivity;  // arity indices per element (not for vertices)
  int arity = 0;
};

// An extern tensor bound from the scene's [tensors] table; owns the storage the binding uses.
struct SceneTensor {
  std::string name;
  FieldType type;
  std::vector<double> doubles;
  std::vector<float> floats;
  std::vector<int32_t> ints;
  std::unique_ptr<bool[]> bools;
  simit::TensorSlot slot;
};

class Scene {
 public:
  explicit Scene(const SceneOptions& options) : options_(options) {}
  int run(std::ostream& out, std::ostream& err);
#ifdef SIMIT_HAVE_REPL
  // Reads and builds the scene without output or frames (the REPL's :scene); `owner` keeps
  // this scene alive for as long as the REPL holds its sets.
  std::optional<repl::SceneData> session_data(std::shared_ptr<void> owner, std::ostream& err);
#endif

 private:
  [[noreturn]] void fail(const toml::node* at, const std::string& what) const {
    std::ostringstream s;
    s << options_.file;
    if (at && at->source().begin.line > 0)
      s << ':' << at->source().begin.line << ':' << at->source().begin.column;
    s << ": error: " << what;
    throw SceneError(s.str());
  }
  void check_keys(const toml::table& t, const std::string& table_name,
                  const std::set<std::string>& allowed) const;
  std::string required_string(const toml::table& t, const std::string& table_name,
                              const std::string& key) const;
  std::optional<std::string> optional_string(const toml::table& t, const std::string& table_name,
                                             const std::string& key) const;
  std::string resolve(const std::string& relative) const;

  void load();
  void load_program();
  void build_sets();
  const runtime::Mesh& mesh(const std::string& path, const toml::node* at, const std::string& key);
  void load_tensors();
  std::string generated_mesh(const toml::table& t, const std::string& tname);
  void init_fields(SceneSet& s);
  void fill_field(SceneSet& s, const ast::FieldDecl& decl, const toml::node& value,
                  const std::string& key);
  void check_output();
  void check_png(const toml::table* output);
  void open_output();
  void bind(simit::Function& f, const std::string& what);
  void write_frame(int frame);
  void write_final_csv();

  const SceneOptions& options_;
  toml::table doc_;
  std::string dir_;  // the scene file's folder
  std::string program_path_, init_name_, step_name_;
  int frames_ = 0;
  double frame_time_ = 1.0;
  int every_ = 1;
  std::unique_ptr<frontend::Compilation> compilation_;
  std::map<std::string, runtime::Mesh> meshes_;
  std::vector<std::unique_ptr<SceneSet>> sets_;
  std::map<std::string, SceneSet*> by_name_;
  std::map<std::string, std::unique_ptr<SceneTensor>> tensors_;
  // output
  std::string out_folder_, out_name_, csv_path_;
  std::string png_path_;  // the quick-look picture of the last frame, when asked for
  SceneSet* points_ = nullptr;
  SceneSet* cells_ = nullptr;
  std::string position_field_;
  std::vector<std::string> point_fields_, cell_fields_;
  std::unique_ptr<runtime::PvdWriter> pvd_;
  std::vector<std::string> stat_names_;  // scalar results of step
};

void Scene::check_keys(const toml::table& t, const std::string& table_name,
                       const std::set<std::string>& allowed) const {
  for (auto&& [key, value] : t) {
    if (allowed.count(std::string(key.str()))) continue;
    std::string list;
    for (const std::string& a : allowed) list += (list.empty() ? "" : ", ") + a;
    fail(&value, "unknown key '" + std::string(key.str()) + "' in " + table_name +
                     " (expected one of: " + list + ")");
  }
}

std::optional<std::string> Scene::optional_string(const toml::table& t,
                                                  const std::string& table_name,
                                                  const std::string& key) const {
  const toml::node* n = t.get(key);
  if (!n) return std::nullopt;
  if (!n->is_string()) fail(n, table_name + " " + key + ": expected a string");
  return n->value<std::string>();
}

std::string Scene::required_string(const toml::table& t, const std::string& table_name,
                                   const std::string& key) const {
  std::optional<std::string> v = optional_string(t, table_name, key);
  if (!v) fail(nullptr, table_name + ": missing key '" + key + "'");
  return *v;
}

std::string Scene::resolve(const std::string& relative) const {
  fs::path p(relative);
  if (p.is_absolute() || dir_.empty()) return p.lexically_normal().string();
  return (fs::path(dir_) / p).lexically_normal().string();
}

void Scene::load() {
  try {
    doc_ = toml::parse_file(options_.file);
  } catch (const toml::parse_error& e) {
    std::ostringstream s;
    s << options_.file;
    if (e.source().begin.line > 0) s << ':' << e.source().begin.line << ':' << e.source().begin.column;
    s << ": error: " << e.description();
    throw SceneError(s.str());
  }
  dir_ = fs::path(options_.file).parent_path().string();
  check_keys(doc_, "the scene", {"program", "init", "step", "frames", "frame_time", "sets", "tensors", "output"});
  program_path_ = resolve(required_string(doc_, "the scene", "program"));
  init_name_ = optional_string(doc_, "the scene", "init").value_or("");
  step_name_ = required_string(doc_, "the scene", "step");
  if (const toml::node* n = doc_.get("frames")) {
    if (!n->is_integer() || n->value<int64_t>().value() < 0)
      fail(n, "frames: expected a whole number >= 0");
    frames_ = static_cast<int>(*n->value<int64_t>());
  } else {
    fail(nullptr, "the scene: missing key 'frames'");
  }
  if (options_.frames >= 0) frames_ = options_.frames;
  if (const toml::node* n = doc_.get("frame_time")) {
    if (!n->is_number() || !(n->value<double>().value() > 0))
      fail(n, "frame_time: expected a positive number (seconds between frames in the .pvd)");
    frame_time_ = *n->value<double>();
  }
  load_program();
  load_tensors();
  build_sets();
  if (!options_.load_only && !options_.quiet) check_output();
}

void Scene::load_program() {
  if (!fs::exists(program_path_))
    fail(doc_.get("program"), "program: no such file '" + program_path_ + "'");
  compilation_ = frontend::compile_file(program_path_);
  if (!compilation_->ok())
    throw SceneError(compilation_->diagnostics.render_all() + options_.file +
                     ": error: the program '" + program_path_ + "' does not compile");
  auto check_func = [&](const std::string& key, const std::string& name) {
    const ast::FuncDecl* f = compilation_->program->find_func(name);
    if (!f) fail(doc_.get(key), key + ": the program has no function '" + name + "'");
    if (!f->exported) fail(doc_.get(key), key + ": '" + name + "' is not an exported function");
    if (!f->params.empty())
      fail(doc_.get(key), key + ": '" + name + "' takes parameters; a scene can only run "
                               "procedures without parameters");
    return f;
  };
  if (!init_name_.empty()) check_func("init", init_name_);
  const ast::FuncDecl* step = check_func("step", step_name_);
  for (const ast::Param& r : step->results)
    if (r.var && r.var->type && r.var->type->is_scalar() &&
        r.var->type->scalar != frontend::ScalarKind::String)
      stat_names_.push_back(r.name);
}

// [tensors]: values of the program's extern tensors (scalars, or dense tensors of fixed
// size given as a flat or nested array of their components, row-major).
void Scene::load_tensors() {
  const toml::node* node = doc_.get("tensors");
  if (!node) return;
  const toml::table* t = node->as_table();
  if (!t) fail(node, "tensors: expected a table of extern tensor values");
  const ast::Program& program = *compilation_->program;
  std::map<std::string, const ast::Variable*> externs;
  for (const ast::Variable* g : program.globals)
    if (g->kind == ast::Variable::Kind::Extern && g->type && g->type->is_tensor())
      externs[g->name] = g;
  const int float_size = options_.float32 ? 4 : 8;
  for (auto&& [key, value] : *t) {
    std::string name(key.str());
    std::string what = "[tensors] " + name;
    auto ext = externs.find(name);
    if (ext == externs.end()) {
      std::string list;
      for (const auto& [n, v] : externs) list += (list.empty() ? "" : ", ") + n;
      fail(&value, what + ": the program declares no extern tensor '" + name + "'" +
                       (list.empty() ? std::string(" (it declares none)")
                                     : " (its extern tensors: " + list + ")"));
    }
    const Type& type = *ext->second->type;
    std::optional<FieldType> ft = api::field_type_for(type, float_size);
    if (!ft || ft->kind == ComponentKind::Complex || ft->kind == ComponentKind::String)
      fail(&value, what + ": extern '" + name + "' is " + frontend::to_string(type) +
                       ", which a scene cannot set (only int, float and bool tensors of "
                       "fixed size)");
    std::vector<const toml::node*> items;
    std::function<void(const toml::node&)> flatten = [&](const toml::node& v) {
      if (const toml::array* a = v.as_array()) {
        for (const toml::node& item : *a) flatten(item);
      } else {
        items.push_back(&v);
      }
    };
    flatten(value);
    const size_t comps = ft->components();
    if (items.size() != comps)
      fail(&value, what + ": extern '" + name + "' is " + frontend::to_string(type) + " with " +
                       std::to_string(comps) + " component" + (comps == 1 ? "" : "s") +
                       ", but " + std::to_string(items.size()) + " value" +
                       (items.size() == 1 ? " was" : "s were") + " given");
    auto st = std::make_unique<SceneTensor>();
    st->name = name;
    st->type = *ft;
    switch (ft->kind) {
      case ComponentKind::Float: st->doubles.resize(comps); st->floats.resize(comps); break;
      case ComponentKind::Int: st->ints.resize(comps); break;
      case ComponentKind::Bool: st->bools = std::make_unique<bool[]>(comps); break;
      default: break;
    }
    for (size_t k = 0; k < comps; ++k) {
      const toml::node& v = *items[k];
      switch (ft->kind) {
        case ComponentKind::Float:
          if (!v.is_number())
            fail(&v, what + ": extern '" + name + "' is " + frontend::to_string(type) +
                         ": expected a number");
          st->doubles[k] = *v.value<double>();
          st->floats[k] = static_cast<float>(st->doubles[k]);
          break;
        case ComponentKind::Int:
          if (!v.is_integer())
            fail(&v, what + ": extern '" + name + "' is " + frontend::to_string(type) +
                         ": expected a whole number");
          st->ints[k] = static_cast<int32_t>(*v.value<int64_t>());
          break;
        case ComponentKind::Bool:
          if (!v.is_boolean())
            fail(&v, what + ": extern '" + name + "' is " + frontend::to_string(type) +
                         ": expected true or false");
          st->bools[k] = *v.value<bool>();
          break;
        default: break;
      }
    }
    void* data = ft->kind == ComponentKind::Int    ? static_cast<void*>(st->ints.data())
                 : ft->kind == ComponentKind::Bool ? static_cast<void*>(st->bools.get())
                 : ft->single                      ? static_cast<void*>(st->floats.data())
                                                   : static_cast<void*>(st->doubles.data());
    st->slot = simit::TensorSlot{ft->kind, ft->single, ft->dims, data};
    tensors_[name] = std::move(st);
  }
}

// `generate = "square_cloth"`, `n = N`: an N x N grid of points on the unit square in the
// xz-plane (y = 0, point i + N j at (i, 0, j) / (N - 1)), each cell split into the triangles
// (p, p+1, p+N+1) and (p, p+N+1, p+N) -- the cloth of bench/baselines/cloth_baseline.cpp.
// Sets generated with the same n share one mesh; the key stands for its path.
std::string Scene::generated_mesh(const toml::table& t, const std::string& tname) {
  std::string kind = required_string(t, tname, "generate");
  if (kind != "square_cloth")
    fail(t.get("generate"), tname + " generate: '" + kind + "' is not a generator (expected square_cloth)");
  const toml::node* nn = t.get("n");
  if (!nn) fail(t.get("generate"), tname + ": generate = \"square_cloth\" needs n (points per side)");
  if (!nn->is_integer() || *nn->value<int64_t>() < 2 || *nn->value<int64_t>() > 4096)
    fail(nn, tname + " n: expected a whole number from 2 to 4096 (points per side)");
  const int side = static_cast<int>(*nn->value<int64_t>());
  std::string key = "square_cloth(n = " + std::to_string(side) + ")";
  if (meshes_.count(key)) return key;
  runtime::Mesh m;
  m.points.resize(size_t(side) * side);
  for (int j = 0; j < side; ++j)
    for (int i = 0; i < side; ++i)
      m.points[size_t(i) + size_t(side) * j] = {double(i) / (side - 1), 0.0, double(j) / (side - 1)};
  for (int j = 0; j + 1 < side; ++j)
    for (int i = 0; i + 1 < side; ++i) {
      const int p = i + side * j;
      m.triangles.push_back({p, p + 1, p + side + 1});
      m.triangles.push_back({p, p + side + 1, p + side});
    }
  meshes_.emplace(key, std::move(m));
  return key;
}

const runtime::Mesh& Scene::mesh(const std::string& path, const toml::node* at,
                                 const std::string& key) {
  auto it = meshes_.find(path);
  if (it != meshes_.end()) return it->second;
  if (!fs::exists(path)) fail(at, key + ": no such file '" + path + "'");
  try {
    runtime::Mesh m = runtime::read_mesh(path);
    runtime::check_mesh(m, path);
    return meshes_.emplace(path, std::move(m)).first->second;
  } catch (const runtime::MeshError& e) {
    fail(at, key + ": " + e.what());
  }
}

void Scene::build_sets() {
  const toml::table* sets = doc_["sets"].as_table();
  if (!sets) fail(doc_.get("sets"), "the scene needs a [sets] table binding the program's extern sets");
  const ast::Program& program = *compilation_->program;
  std::map<std::string, const ast::Variable*> externs;
  for (const ast::Variable* g : program.globals)
    if (g->kind == ast::Variable::Kind::Extern && g->type && g->type->kind == Type::Kind::Set)
      externs[g->name] = g;

  for (auto&& [key, node] : *sets) {
    std::string name(key.str());
    std::string tname = "[sets." + name + "]";
    const toml::table* t = node.as_table();
    if (!t) fail(&node, "sets." + name + ": expected a table");
    auto ext = externs.find(name);
    if (ext == externs.end()) fail(&node, tname + ": the program declares no extern set '" + name + "'");
    check_keys(*t, tname, {"mesh", "generate", "n", "elements", "fields"});
    auto s = std::make_unique<SceneSet>();
    s->name = name;
    s->table = t;
    s->var = ext->second;
    if (t->get("generate")) {
      if (t->get("mesh")) fail(t->get("generate"), tname + ": give either mesh or generate, not both");
      s->mesh_path = generated_mesh(*t, tname);
    } else {
      if (t->get("n")) fail(t->get("n"), tname + " n: only for generate");
      s->mesh_path = resolve(required_string(*t, tname, "mesh"));
    }
    std::string el = required_string(*t, tname, "elements");
    auto e = kElementNames.find(el);
    if (e == kElementNames.end())
      fail(t->get("elements"), tname + " elements: '" + el + "' is not one of vertices, tets, "
                                       "triangles, edges, tet_edges, boundary_triangles, hinges");
    s->elements = e->second;
    if (s->var->type->grid_dims > 0)
      fail(&node, tname + ": extern '" + name + "' is a grid; scenes bind only vertex and edge sets");
    by_name_[name] = s.get();
    sets_.push_back(std::move(s));
  }
  for (const auto& [name, var] : externs)
    if (!by_name_.count(name))
      fail(nullptr, "[sets]: the program's extern set '" + name + "' is not bound (add [sets." +
                        name + "])");

  // Vertex sets first: edge sets name them as endpoints.
  for (int pass = 0; pass < 2; ++pass) {
    for (auto& sp : sets_) {
      SceneSet& s = *sp;
      bool vertex = s.elements == Elements::Vertices;
      if (vertex != (pass == 0)) continue;
      std::string tname = "[sets." + s.name + "]";
      const runtime::Mesh& m = mesh(s.mesh_path, s.table->get("mesh"), tname + " mesh");
      const std::vector<frontend::IndexSet>& ends = s.var->type->endpoints;
      if (vertex) {
        if (!ends.empty())
          fail(s.table->get("elements"), tname + ": extern '" + s.name + "' is an edge set with " +
                                             std::to_string(ends.size()) +
                                             " endpoints, but elements = \"vertices\"");
        s.set = std::make_unique<simit::Set>(s.name);
        s.set->runtime().add_many(static_cast<int>(m.points.size()));
      } else {
        std::vector<int32_t>& c = s.connectivity;
        try {
          auto append = [&](const auto& list) {
            for (const auto& el : list) c.insert(c.end(), el.begin(), el.end());
          };
          switch (s.elements) {
            case Elements::Tets: s.arity = 4; append(m.tets); break;
            case Elements::Triangles: s.arity = 3; append(m.triangles); break;
            case Elements::Edges:
              s.arity = 2;
              if (!m.edges.empty()) append(m.edges);
              else if (!m.tets.empty()) append(runtime::tet_edges(m.tets));
              else append(runtime::triangle_edges(m.triangles));
              break;
            case Elements::TetEdges: s.arity = 2; append(runtime::tet_edges(m.tets)); break;
            case Elements::BoundaryTriangles:
              s.arity = 3;
              append(runtime::boundary_triangles(m));
              break;
            case Elements::Hinges:
              s.arity = 4;
              append(runtime::hinges(m.triangles.empty() ? runtime::boundary_triangles(m)
                                                          : m.triangles));
              break;
            case Elements::Vertices: break;
          }
        } catch (const runtime::MeshError& e) {
          fail(s.table->get("elements"), tname + " elements: " + e.what());
        }
        if (c.empty())
          fail(s.table->get("elements"),
               tname + ": the mesh '" + s.mesh_path + "' gives no " +
                   s.table->get("elements")->value<std::string>().value() + "");
        if (static_cast<int>(ends.size()) != s.arity)
          fail(s.table->get("elements"),
               tname + ": extern '" + s.name + "' has " + std::to_string(ends.size()) +
                   " endpoints per element, but its elements have " + std::to_string(s.arity) +
                   " vertices");
        std::vector<simit::Set*> endpoint_sets;
        for (const frontend::IndexSet& end : ends) {
          auto it = end.var ? by_name_.find(end.var->name) : by_name_.end();
          if (it == by_name_.end())
            fail(s.table, tname + ": its endpoint set is not bound in the scene");
          SceneSet& v = *it->second;
          if (v.elements != Elements::Vertices || v.mesh_path != s.mesh_path)
            fail(s.table->get("mesh"), tname + ": its endpoints are in '" + v.name +
                                           "', which must be the vertices of the same mesh ('" +
                                           s.mesh_path + "')");
          endpoint_sets.push_back(v.set.get());
        }
        s.set = std::make_unique<simit::Set>(s.name, endpoint_sets);
        s.set->runtime().add_edges(std::span<const int32_t>(c));
      }
      // Every field the element type declares, zero until the scene or `init` sets it.
      const ast::ElementDecl* decl = s.var->type->element;
      int float_size = options_.float32 ? 4 : 8;
      for (const ast::FieldDecl& f : decl->fields) {
        std::optional<FieldType> ft = f.type ? api::field_type_for(*f.type, float_size) : std::nullopt;
        if (!ft)
          fail(s.table, tname + ": field '" + f.name + "' of element " + decl->name +
                            " has a type host sets cannot store");
        s.set->add_field(f.name, *ft);
      }
      init_fields(s);
    }
  }
}

void Scene::init_fields(SceneSet& s) {
  const toml::node* fields = s.table->get("fields");
  if (!fields) return;
  std::string tname = "[sets." + s.name + ".fields]";
  const toml::table* t = fields->as_table();
  if (!t) fail(fields, tname + ": expected a table of field values");
  const ast::ElementDecl* decl = s.var->type->element;
  for (auto&& [key, value] : *t) {
    std::string name(key.str());
    int index = decl->field_index(name);
    if (index < 0) {
      std::string list;
      for (const ast::FieldDecl& f : decl->fields) list += (list.empty() ? "" : ", ") + f.name;
      fail(&value, tname + " " + name + ": element " + decl->name + " (of extern '" + s.name +
                       "') declares no field '" + name + "' (its fields: " + list + ")");
    }
    fill_field(s, decl->fields[index], value, tname + " " + name);
  }
}

void Scene::fill_field(SceneSet& s, const ast::FieldDecl& decl, const toml::node& value,
                       const std::string& key) {
  runtime::Set& rs = s.set->runtime();
  runtime::Field& field = rs.field(decl.name);
  const FieldType& ft = field.type();
  const size_t comps = ft.components();
  const int n = rs.size();
  if (ft.kind == ComponentKind::Complex || ft.kind == ComponentKind::String)
    fail(&value, key + ": scenes cannot initialise " + ft.str() + " fields");
  const runtime::Mesh& m = meshes_.at(s.mesh_path);
  // The element's position: the vertex, or the centroid of the element's vertices.
  auto position = [&](int e, double p[3]) {
    if (s.elements == Elements::Vertices) {
      for (int d = 0; d < 3; ++d) p[d] = m.points[e][d];
      return;
    }
    p[0] = p[1] = p[2] = 0.0;
    for (int k = 0; k < s.arity; ++k)
      for (int d = 0; d < 3; ++d) p[d] += m.points[s.connectivity[size_t(e) * s.arity + k]][d];
    for (int d = 0; d < 3; ++d) p[d] /= s.arity;
  };
  // One source per component: a constant or an expression.
  struct Source {
    double constant = 0.0;
    std::shared_ptr<PositionExpr> expr;
    int coordinate = -1;  // "position": component d of the position
  };
  std::vector<Source> src;
  auto scalar_source = [&](const toml::node& v) {
    Source out;
    if (v.is_boolean()) out.constant = *v.value<bool>() ? 1.0 : 0.0;
    else if (v.is_number()) out.constant = *v.value<double>();
    else if (v.is_string()) {
      try {
        out.expr = std::make_shared<PositionExpr>(*v.value<std::string>());
      } catch (const std::invalid_argument& e) {
        fail(&v, key + ": in \"" + *v.value<std::string>() + "\": " + e.what());
      }
    } else {
      fail(&v, key + ": expected a number, a boolean, an expression string or an array of them");
    }
    if (!out.expr && ft.kind == ComponentKind::Int && out.constant != std::floor(out.constant))
      fail(&v, key + ": field '" + decl.name + "' holds ints, but the value is not whole");
    return out;
  };
  std::function<void(const toml::node&)> flatten = [&](const toml::node& v) {
    if (const toml::array* a = v.as_array()) {
      for (const toml::node& item : *a) flatten(item);
    } else {
      src.push_back(scalar_source(v));
    }
  };
  if (value.is_string() && *value.value<std::string>() == "position") {
    if (ft.kind != ComponentKind::Float || comps != 3)
      fail(&value, key + ": \"position\" needs a field of 3 floats, but '" + decl.name + "' is " +
                       ft.str());
    for (int d = 0; d < 3; ++d) src.push_back(Source{0.0, nullptr, d});
  } else if (value.is_array()) {
    flatten(value);
    if (src.size() != comps)
      fail(&value, key + ": field '" + decl.name + "' (" + ft.str() + ") has " +
                       std::to_string(comps) + " components per element, but " +
                       std::to_string(src.size()) + " values were given");
  } else {
    src.assign(comps, scalar_source(value));  // one value for every component
  }
  double lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
  for (int d = 0; d < 3 && !m.points.empty(); ++d) {
    lo[d] = hi[d] = m.points[0][d];
    for (const runtime::Point& q : m.points) {
      lo[d] = std::min(lo[d], q[d]);
      hi[d] = std::max(hi[d], q[d]);
    }
  }
  bool needs_position = false;
  for (const Source& c : src) needs_position = needs_position || c.expr || c.coordinate >= 0;
  for (int e = 0; e < n; ++e) {
    double p[3] = {0, 0, 0};
    if (needs_position) position(e, p);
    for (size_t k = 0; k < comps; ++k) {
      const Source& c = src[k];
      double v = c.coordinate >= 0 ? p[c.coordinate]
                 : c.expr           ? c.expr->eval(p, lo, hi)
                                    : c.constant;
      switch (ft.kind) {
        case ComponentKind::Float:
          if (ft.single) field.at<float>(e)[k] = static_cast<float>(v);
          else field.at<double>(e)[k] = v;
          break;
        case ComponentKind::Int: field.at<int32_t>(e)[k] = static_cast<int32_t>(std::llround(v)); break;
        case ComponentKind::Bool: field.at<bool>(e)[k] = v != 0.0; break;
        default: break;
      }
    }
  }
}

void Scene::check_output() {
  const toml::node* node = doc_.get("output");
  if (!node && !options_.png.empty())
    fail(nullptr, "--png needs an [output] table (its points are what the picture shows)");
  if (!node) return;  // no output: run the frames only
  const toml::table* t = node->as_table();
  if (!t) fail(node, "output: expected a table");
  const std::string tname = "[output]";
  check_keys(*t, tname, {"folder", "name", "points", "position", "cells", "point_fields",
                         "cell_fields", "every", "csv", "png"});
  out_folder_ = options_.output_dir.empty() ? required_string(*t, tname, "folder") : options_.output_dir;
  out_name_ = required_string(*t, tname, "name");
  std::string points = required_string(*t, tname, "points");
  auto find_set = [&](const std::string& key, const std::string& name) -> SceneSet* {
    auto it = by_name_.find(name);
    if (it == by_name_.end()) fail(t->get(key), tname + " " + key + ": no set '" + name + "' in [sets]");
    return it->second;
  };
  points_ = find_set("points", points);
  if (points_->elements != Elements::Vertices)
    fail(t->get("points"), tname + " points: '" + points + "' is not bound to vertices");
  position_field_ = optional_string(*t, tname, "position").value_or("");
  if (!position_field_.empty()) {
    if (!points_->set->has_field(position_field_))
      fail(t->get("position"), tname + " position: set '" + points + "' has no field '" +
                                   position_field_ + "'");
    const FieldType& ft = points_->set->runtime().field(position_field_).type();
    if (ft.kind != ComponentKind::Float || ft.components() != 3)
      fail(t->get("position"), tname + " position: '" + position_field_ + "' is " + ft.str() +
                                   ", not 3 floats");
  }
  if (auto cells = optional_string(*t, tname, "cells")) {
    cells_ = find_set("cells", *cells);
    if (cells_->elements == Elements::Vertices || cells_->elements == Elements::Hinges)
      fail(t->get("cells"), tname + " cells: '" + *cells + "' must be tets, triangles or edges");
    if (cells_->mesh_path != points_->mesh_path)
      fail(t->get("cells"), tname + " cells: '" + *cells + "' is not on the mesh of '" + points + "'");
  }
  auto field_list = [&](const std::string& key, SceneSet* s, std::vector<std::string>& list) {
    const toml::node* n = t->get(key);
    if (!n) return;
    const toml::array* a = n->as_array();
    if (!a) fail(n, tname + " " + key + ": expected an array of field names");
    if (!s) fail(n, tname + " " + key + ": needs 'cells'");
    for (const toml::node& item : *a) {
      if (!item.is_string()) fail(&item, tname + " " + key + ": expected field names");
      std::string f = *item.value<std::string>();
      if (!s->set->has_field(f))
        fail(&item, tname + " " + key + ": set '" + s->name + "' has no field '" + f + "'");
      if (s->set->runtime().field(f).type().kind == ComponentKind::Complex)
        fail(&item, tname + " " + key + ": complex field '" + f + "' cannot be written");
      list.push_back(f);
    }
  };
  field_list("point_fields", points_, point_fields_);
  field_list("cell_fields", cells_, cell_fields_);
  if (const toml::node* n = t->get("every")) {
    if (!n->is_integer() || *n->value<int64_t>() < 1) fail(n, tname + " every: expected a whole number >= 1");
    every_ = static_cast<int>(*n->value<int64_t>());
  }
  if (auto csv = optional_string(*t, tname, "csv")) csv_path_ = (fs::path(out_folder_) / *csv).string();
  check_png(t);
}

// [output] png (relative to the output folder) or --png (relative to the current folder): a
// .png name in the output folder or in a folder that exists.
void Scene::check_png(const toml::table* t) {
  const std::optional<std::string> key_value = optional_string(*t, "[output]", "png");
  const bool cli = !options_.png.empty();
  const toml::node* at = cli ? nullptr : t->get("png");
  const std::string key = cli ? "--png" : "[output] png";
  if (cli) png_path_ = options_.png;
  else if (key_value) png_path_ = (fs::path(out_folder_) / *key_value).string();
  else return;
  const fs::path path(png_path_);
  if (path.extension() != ".png") fail(at, key + ": '" + png_path_ + "' is not a .png file name");
  std::error_code ec;
  if (fs::is_directory(path, ec)) fail(at, key + ": '" + png_path_ + "' is a folder");
  const fs::path folder = (path.parent_path().empty() ? fs::path(".") : path.parent_path());
  const fs::path out = (fs::path(out_folder_) / "x").parent_path();
  if (folder.lexically_normal() != out.lexically_normal() && !fs::is_directory(folder, ec))
    fail(at, key + ": the folder '" + folder.string() + "' does not exist");
}

// Creates the output folder once everything is checked (so a scene error leaves nothing
// behind), then makes sure the quick-look picture can be written there before any frame runs.
void Scene::open_output() {
  if (!points_) return;
  const toml::table& t = *doc_["output"].as_table();
  std::error_code ec;
  fs::create_directories(out_folder_, ec);
  if (ec)
    fail(t.get("folder"),
         "[output] folder: cannot create '" + out_folder_ + "': " + ec.message());
  const std::string pvd = (fs::path(out_folder_) / (out_name_ + ".pvd")).string();
  pvd_ = std::make_unique<runtime::PvdWriter>(pvd);
  if (png_path_.empty()) return;
  try {
    runtime::AtomicFile probe(png_path_);  // removed again: only a test that the folder takes it
  } catch (const runtime::MeshError& e) {
    const bool cli = !options_.png.empty();
    fail(cli ? nullptr : t.get("png"),
         std::string(cli ? "--png" : "[output] png") + ": cannot write: " + e.what());
  }
}

void Scene::bind(simit::Function& f, const std::string& what) {
  for (const std::string& name : f.unbound()) {
    auto it = by_name_.find(name);
    if (it != by_name_.end()) {
      f.bind(name, *it->second->set);
      continue;
    }
    auto t = tensors_.find(name);
    if (t != tensors_.end()) {
      f.bind(name, t->second->slot);
      continue;
    }
    const ast::Variable* g = nullptr;
    for (const ast::Variable* v : compilation_->program->globals)
      if (v->name == name && v->kind == ast::Variable::Kind::Extern) g = v;
    if (g && g->type && g->type->is_tensor())
      fail(doc_.get(what), what + ": '" + f.name() + "' uses the extern tensor '" + name +
                               "' (" + frontend::to_string(*g->type) +
                               "), which is not set: add it to [tensors]");
    fail(doc_.get(what), what + ": '" + f.name() + "' needs '" + name +
                             "' bound, which a scene cannot bind");
  }
  f.init();
}

// Field values of a set as a VTK array (converted to double or int32 where needed).
struct ArrayStore {
  std::deque<std::vector<double>> doubles;
  std::deque<std::vector<int32_t>> ints;
  runtime::VtuArray add(const runtime::Set& set, const std::string& name) {
    const runtime::Field& f = set.field(name);
    const FieldType& ft = f.type();
    const size_t count = ft.components() * static_cast<size_t>(set.size());
    runtime::VtuArray a{name, static_cast<int>(ft.components()), std::span<const double>()};
    switch (ft.kind) {
      case ComponentKind::Float:
        if (!ft.single) {
          a.values = std::span<const double>(f.data<double>(), count);
        } else {
          const float* p = f.data<float>();
          doubles.emplace_back(p, p + count);
          a.values = std::span<const double>(doubles.back());
        }
        break;
      case ComponentKind::Int: a.values = std::span<const int32_t>(f.data<int32_t>(), count); break;
      case ComponentKind::Bool: {
        const bool* p = f.data<bool>();
        ints.emplace_back(p, p + count);
        a.values = std::span<const int32_t>(ints.back());
        break;
      }
      default: break;
    }
    return a;
  }
};

void Scene::write_frame(int frame) {
  if (!pvd_) return;
  runtime::Mesh m;
  const runtime::Mesh& source = meshes_.at(points_->mesh_path);
  const runtime::Set& ps = points_->set->runtime();
  if (position_field_.empty()) {
    m.points = source.points;
  } else {
    const runtime::Field& f = ps.field(position_field_);
    m.points.resize(ps.size());
    for (int i = 0; i < ps.size(); ++i)
      for (int d = 0; d < 3; ++d)
        m.points[i][d] = f.type().single ? f.at<float>(i)[d] : f.at<double>(i)[d];
  }
  if (cells_) {
    const std::vector<int32_t>& c = cells_->connectivity;
    const size_t ne = c.size() / cells_->arity;
    for (size_t e = 0; e < ne; ++e) {
      const int32_t* v = c.data() + e * cells_->arity;
      if (cells_->arity == 4) m.tets.push_back({v[0], v[1], v[2], v[3]});
      else if (cells_->arity == 3) m.triangles.push_back({v[0], v[1], v[2]});
      else m.edges.push_back({v[0], v[1]});
    }
  }
  ArrayStore store;
  std::vector<runtime::VtuArray> point_data, cell_data;
  for (const std::string& f : point_fields_) point_data.push_back(store.add(ps, f));
  if (cells_)
    for (const std::string& f : cell_fields_) cell_data.push_back(store.add(cells_->set->runtime(), f));
  pvd_->write_frame(frame * frame_time_, m, point_data, cell_data);
  std::string png_error;
  if (frame == frames_ && !png_path_.empty() && !runtime::write_quicklook(m, png_path_, png_error))
    throw SceneError(options_.file + ": error: writing the quick-look picture: " + png_error);
}

void Scene::write_final_csv() {
  if (options_.final_csv.empty()) return;
  std::ofstream out(options_.final_csv);
  out.precision(17);
  out << "x,y,z\n";
  if (!points_ || position_field_.empty())
    throw SceneError(options_.file + ": error: --final-csv needs [output] points and position");
  const runtime::Field& f = points_->set->runtime().field(position_field_);
  for (int i = 0; i < points_->set->size(); ++i) {
    for (int d = 0; d < 3; ++d)
      out << (d ? "," : "") << (f.type().single ? f.at<float>(i)[d] : f.at<double>(i)[d]);
    out << '\n';
  }
  if (!out) throw SceneError(options_.final_csv + ": error: cannot write");
}

std::string format_seconds(double s) {
  char buf[32];
  if (s < 60) std::snprintf(buf, sizeof buf, "%.1f s", s);
  else if (s < 3600) std::snprintf(buf, sizeof buf, "%d min %02d s", int(s) / 60, int(s) % 60);
  else std::snprintf(buf, sizeof buf, "%d h %02d min", int(s) / 3600, (int(s) % 3600) / 60);
  return buf;
}

int Scene::run(std::ostream& out, std::ostream& err) {
  using Clock = std::chrono::steady_clock;
  try {
    load();
    simit::Options popts;
    popts.float_size = options_.float32 ? 4 : 8;
    popts.check_finite = options_.check_finite;
    popts.out = &out;
    popts.trap = options_.trap;
    simit::Program program(popts);
    program.load_file(program_path_);
    simit::Function init_fn;
    if (!init_name_.empty()) {
      init_fn = program.compile(init_name_);
      bind(init_fn, "init");
    }
    simit::Function step_fn = program.compile(step_name_);
    bind(step_fn, "step");
    open_output();
    std::ofstream csv;
    if (!csv_path_.empty()) {
      csv.open(csv_path_);
      if (!csv) throw SceneError(options_.file + ": error: [output] csv: cannot write '" + csv_path_ + "'");
      csv.precision(17);
      csv << "frame,time,ms";
      for (const std::string& s : stat_names_) csv << ',' << s;
      // Last, so the columns before them keep their places: the frame's time in outermost
      // map/apply assemblies, and the rest of it (mostly the CG solve).
      csv << ",assembly_ms,solve_ms";
      csv << '\n';
    }
    std::string sizes;
    for (const auto& s : sets_)
      sizes += (sizes.empty() ? "" : ", ") + s->name + " " + std::to_string(s->set->size());
    out << options_.file << ": " << sizes << "; " << frames_ << " frames\n";
    // Everything is checked: run.
    if (init_fn.defined()) init_fn.run();
    write_frame(0);
    const auto start = Clock::now();
    double total_ms = 0.0;
    for (int frame = 1; frame <= frames_; ++frame) {
      const auto t0 = Clock::now();
      step_fn.reset_stats();
      step_fn.run();
      const double ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
      const double assembly_ms = std::min(ms, 1e3 * step_fn.stats().assembly_seconds);
      total_ms += ms;
      std::vector<double> stats;
      for (const std::string& s : stat_names_) {
        runtime::Tensor v = step_fn.result(s);
        switch (v.kind()) {
          case ComponentKind::Int: stats.push_back(v.ints()[0]); break;
          case ComponentKind::Bool: stats.push_back(v.bools()[0]); break;
          case ComponentKind::Float: stats.push_back(v.floats()[0]); break;
          default: stats.push_back(NAN); break;
        }
      }
      if (frame % every_ == 0 || frame == frames_) write_frame(frame);
      if (csv.is_open()) {
        csv << frame << ',' << frame * frame_time_ << ',' << ms;
        for (double s : stats) csv << ',' << s;
        csv << ',' << assembly_ms << ',' << ms - assembly_ms;
        csv << '\n' << std::flush;
      }
      if (options_.quiet) continue;
      const double elapsed = std::chrono::duration<double>(Clock::now() - start).count();
      const double eta = elapsed / frame * (frames_ - frame);
      char line[160];
      std::snprintf(line, sizeof line, "frame %d/%d  %.1f ms/frame  ETA %s", frame, frames_,
                    total_ms / frame, format_seconds(eta).c_str());
      if (options_.progress_line) {
        out << '\r' << line << "   " << std::flush;
      } else {
        out << line << "  (this frame " << std::fixed;
        out.precision(1);
        out << ms << " ms";
        out << std::defaultfloat;
        out.precision(6);
        for (size_t k = 0; k < stats.size(); ++k) out << ", " << stat_names_[k] << " = " << stats[k];
        out << ")\n" << std::flush;
      }
    }
    if (options_.progress_line && frames_ > 0) out << '\n';
    char summary[160];
    std::snprintf(summary, sizeof summary, "%d frames, %.1f ms/frame", frames_,
                  frames_ ? total_ms / frames_ : 0.0);
    if (options_.quiet) std::snprintf(summary, sizeof summary, "%d frames", frames_);
    out << summary;
    if (pvd_) out << "; wrote " << pvd_->path();
    out << "\n";
    write_final_csv();
  } catch (const SceneError& e) {
    out.flush();
    err << e.what() << "\n";
    return 1;
  } catch (const simit::CompileError& e) {
    err << e.what();
    return 1;
  } catch (const simit::RuntimeError& e) {
    out.flush();
    err << e.what() << "\n";
    return 1;
  } catch (const simit::Error& e) {
    out.flush();
    err << options_.file << ": error: " << e.what() << "\n";
    return 1;
  } catch (const runtime::MeshError& e) {
    out.flush();
    err << options_.file << ": error: writing output: " << e.what() << "\n";
    return 1;
  } catch (const std::exception& e) {
    out.flush();
    err << "simit run: internal error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}

#ifdef SIMIT_HAVE_REPL
std::optional<repl::SceneData> Scene::session_data(std::shared_ptr<void> owner, std::ostream& err) {
  try {
    load();
  } catch (const SceneError& e) {
    err << e.what() << "\n";
    return std::nullopt;
  } catch (const std::exception& e) {
    err << options_.file << ": error: " << e.what() << "\n";
    return std::nullopt;
  }
  repl::SceneData d;
  d.path = options_.file;
  d.program_path = program_path_;
  d.init = init_name_;
  d.step = step_name_;
  for (const auto& s : sets_) d.sets.emplace_back(s->name, &s->set->runtime());
  for (const ast::Variable* g : compilation_->program->globals) {
    auto t = tensors_.find(g->name);
    if (g->kind == ast::Variable::Kind::Extern && t != tensors_.end())
      d.tensors.emplace_back(g->name, api::to_value(t->second->slot, *g->type));
  }
  d.owner = std::move(owner);
  return d;
}
#endif

}  // namespace

#ifdef SIMIT_HAVE_REPL
std::optional<repl::SceneData> load_scene_data(const std::string& path, bool float32,
                                               std::ostream& err) {
  struct Holder {
    SceneOptions options;
    std::unique_ptr<Scene> scene;
  };
  auto holder = std::make_shared<Holder>();
  holder->options.file = path;
  holder->options.float32 = float32;
  holder->options.load_only = true;
  holder->scene = std::make_unique<Scene>(holder->options);
  Scene& scene = *holder->scene;
  return scene.session_data(std::move(holder), err);
}
#endif

int run_scene(const SceneOptions& options, std::ostream& out, std::ostream& err) {
  Scene scene(options);
  return scene.run(out, err);
}

}  // namespace simit::tools
