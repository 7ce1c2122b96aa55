// Evaluating a scene's field values per element.
#include "scene/field_values.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <memory>
#include <vector>

#include "scene/scene_expr.h"

namespace simit::scene {

namespace ast = frontend::ast;
using runtime::ComponentKind;
using runtime::FieldType;

namespace {

// Where one component's value comes from: a constant, an expression or the position.
struct Source {
  double constant = 0.0;
  std::shared_ptr<PositionExpr> expr;
  int coordinate = -1;  // "position": component d of the position
};

// The element's position: the vertex, or the centroid of the element's vertices.
void position(const SceneSet& s, const runtime::Mesh& m, int e, double p[3]) {
  if (s.elements == Elements::Vertices) {
    for (int d = 0; d < 3; ++d) p[d] = m.points[e][d];
    return;
  }
  p[0] = p[1] = p[2] = 0.0;
  for (int k = 0; k < s.arity; ++k)
    for (int d = 0; d < 3; ++d) p[d] += m.points[s.connectivity[size_t(e) * s.arity + k]][d];
  for (int d = 0; d < 3; ++d) p[d] /= s.arity;
}

// An expression quoted in a message: a long one by its start only.
std::string clipped(const std::string& text) {
  constexpr size_t kShown = 60;
  return text.size() <= kShown ? text : text.substr(0, kShown) + "...";
}

Source scalar_source(const SceneFile& file, const toml::node& v, const std::string& key,
                     const ast::FieldDecl& decl, const FieldType& ft) {
  Source out;
  if (v.is_boolean())
    out.constant = *v.value<bool>() ? 1.0 : 0.0;
  else if (v.is_number())
    out.constant = *v.value<double>();
  else if (v.is_string()) {
    try {
      out.expr = std::make_shared<PositionExpr>(*v.value<std::string>());
    } catch (const std::invalid_argument& e) {
      file.fail(&v, key + ": in \"" + clipped(*v.value<std::string>()) + "\": " + e.what());
    }
  } else {
    file.fail(&v, key + ": expected a number, a boolean, an expression string or an array of them");
  }
  if (!out.expr && ft.kind == ComponentKind::Int && out.constant != std::floor(out.constant))
    file.fail(&v, key + ": field '" + decl.name + "' holds ints, but the value is not whole");
  return out;
}

// One source per component of the field.
std::vector<Source> sources(const SceneFile& file, const toml::node& value, const std::string& key,
                            const ast::FieldDecl& decl, const FieldType& ft) {
  const size_t comps = ft.components();
  std::vector<Source> src;
  std::function<void(const toml::node&)> flatten = [&](const toml::node& v) {
    if (const toml::array* a = v.as_array()) {
      for (const toml::node& item : *a) flatten(item);
    } else {
      src.push_back(scalar_source(file, v, key, decl, ft));
    }
  };
  if (value.is_string() && *value.value<std::string>() == "position") {
    if (ft.kind != ComponentKind::Float || comps != 3)
      file.fail(&value, key + ": \"position\" needs a field of 3 floats, but '" + decl.name +
                            "' is " + ft.str());
    for (int d = 0; d < 3; ++d) src.push_back(Source{0.0, nullptr, d});
  } else if (value.is_array()) {
    flatten(value);
    if (src.size() != comps)
      file.fail(&value, key + ": field '" + decl.name + "' (" + ft.str() + ") has " +
                            std::to_string(comps) + " components per element, but " +
                            std::to_string(src.size()) + " values were given");
  } else {
    src.assign(comps, scalar_source(file, value, key, decl, ft));  // one value for every component
  }
  return src;
}

void store(runtime::Field& field, const FieldType& ft, int e, size_t k, double v) {
  switch (ft.kind) {
    case ComponentKind::Float:
      if (ft.single)
        field.at<float>(e)[k] = static_cast<float>(v);
      else
        field.at<double>(e)[k] = v;
      break;
    case ComponentKind::Int: field.at<int32_t>(e)[k] = static_cast<int32_t>(std::llround(v)); break;
    case ComponentKind::Bool: field.at<bool>(e)[k] = v != 0.0; break;
    default: break;
  }
}

void fill_field(const SceneFile& file, SceneSet& s, const runtime::Mesh& m,
                const ast::FieldDecl& decl, const toml::node& value, const std::string& key) {
  runtime::Field& field = s.set->field(decl.name);
  const FieldType& ft = field.type();
  if (ft.kind == ComponentKind::Complex || ft.kind == ComponentKind::String)
    file.fail(&value, key + ": scenes cannot initialise " + ft.str() + " fields");
  const std::vector<Source> src = sources(file, value, key, decl, ft);
  double lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};  // the mesh's bounding box
  for (int d = 0; d < 3 && !m.points.empty(); ++d) {
    lo[d] = hi[d] = m.points[0][d];
    for (const runtime::Point& q : m.points) {
      lo[d] = std::min(lo[d], q[d]);
      hi[d] = std::max(hi[d], q[d]);
    }
  }
  bool needs_position = false;
  for (const Source& c : src) needs_position = needs_position || c.expr || c.coordinate >= 0;
  for (int e = 0; e < s.set->size(); ++e) {
    double p[3] = {0, 0, 0};
    if (needs_position) position(s, m, e, p);
    for (size_t k = 0; k < src.size(); ++k) {
      const Source& c = src[k];
      store(field, ft, e, k,
            c.coordinate >= 0 ? p[c.coordinate]
            : c.expr          ? c.expr->eval(p, lo, hi)
                              : c.constant);
    }
  }
}

}  // namespace

void init_fields(const SceneFile& file, SceneSet& s, const runtime::Mesh& m) {
  const toml::node* fields = s.table->get("fields");
  if (!fields) return;
  std::string tname = "[sets." + s.name + ".fields]";
  const toml::table* t = fields->as_table();
  if (!t) file.fail(fields, tname + ": expected a table of field values");
  const ast::ElementDecl* decl = s.var->type->element;
  for (auto&& [key, value] : *t) {
    std::string name(key.str());
    int index = decl->field_index(name);
    if (index < 0) {
      std::string list;
      for (const ast::FieldDecl& f : decl->fields) list += (list.empty() ? "" : ", ") + f.name;
      file.fail(&value, tname + " " + name + ": element " + decl->name + " (of extern '" + s.name +
                            "') declares no field '" + name + "' (its fields: " + list + ")");
    }
    fill_field(file, s, m, decl->fields[index], value, tname + " " + name);
  }
}

}  // namespace simit::scene
