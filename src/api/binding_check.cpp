// Binding checks: set kind, arity, endpoint sets, fields, component types and shapes.
#include "binding_check.h"

#include <algorithm>

#include "api/set_access.h"
#include "interp/set_binding.h"

namespace simit::api {

namespace ast = frontend::ast;
using frontend::IndexSet;
using frontend::ScalarKind;
using frontend::Type;
using runtime::ComponentKind;

namespace {

// Set fields cannot hold strings (LANGUAGE.md §4.2, Rec.).
std::optional<ComponentKind> field_component_of(ScalarKind k) {
  if (k == ScalarKind::String) return std::nullopt;
  return interp::component_of(k);
}

std::string dims_text(const std::vector<int>& dims) {
  std::string s;
  for (size_t i = 0; i < dims.size(); ++i) s += (i ? "x" : "") + std::to_string(dims[i]);
  return s;
}

size_t count(const std::vector<int>& dims) {
  size_t n = 1;
  for (int d : dims) n *= static_cast<size_t>(d);
  return n;
}

std::string plural(size_t n, const char* word) {
  return std::to_string(n) + " " + word + (n == 1 ? "" : "s");
}

// Why the host storage `got` cannot hold values of the Simit type `want` (empty: it can).
std::string mismatch(const runtime::FieldType& want, ComponentKind got_kind, bool got_single,
                     const std::vector<int>& got_dims, int float_size) {
  if (got_kind != want.kind)
    return std::string("has ") + runtime::component_name(got_kind) + " components";
  if (got_single != want.single)
    return std::string("stores ") + (got_single ? "binary32" : "binary64") +
           " components, but the program's float size is " + std::to_string(float_size) +
           " (host type " + (want.single ? "float" : "double") + ")";
  if (count(got_dims) != count(want.dims)) return "has " + plural(count(got_dims), "component");
  if (got_dims != want.dims)
    return "has dimensions " + (got_dims.empty() ? std::string("scalar") : dims_text(got_dims));
  return {};
}

std::string set_shape(const runtime::Set& s) {
  if (s.is_grid()) return "is a " + std::to_string(s.dimensions()) + "-dimensional grid";
  if (s.arity() == 0) return "is a vertex set";
  return "is an edge set with " + plural(static_cast<size_t>(s.arity()), "endpoint");
}

void check_kind(const std::string& who, const Type& t, const runtime::Set& s,
                std::vector<std::string>& problems) {
  if (t.grid_dims > 0) {
    if (!s.is_grid() || s.dimensions() != t.grid_dims)
      problems.push_back(who + "is a " + std::to_string(t.grid_dims) +
                         "-dimensional grid in the program but " + s.describe() + " " +
                         set_shape(s));
    return;
  }
  const size_t arity = t.endpoints.size();
  if (s.is_grid() || static_cast<size_t>(s.arity()) != arity) {
    std::string want =
        arity == 0 ? "a vertex set" : "an edge set with " + plural(arity, "endpoint");
    problems.push_back(who + "is " + want + " in the program but " + s.describe() + " " +
                       set_shape(s));
  }
}

void check_fields(const std::string& who, const ast::ElementDecl& element, const runtime::Set& s,
                  int float_size, std::vector<std::string>& problems) {
  for (const ast::FieldDecl& f : element.fields) {
    const std::string spelled = f.type ? frontend::to_string(*f.type) : "?";
    auto want = f.type ? field_type_for(*f.type, float_size) : std::nullopt;
    if (!want) {
      problems.push_back(who + "field '" + f.name + "' has type " + spelled +
                         ", which host sets cannot store");
      continue;
    }
    int index = s.field_index(f.name);
    if (index < 0) {
      problems.push_back(who + "field '" + f.name + "' (" + spelled + ") is missing from " +
                         s.describe());
      continue;
    }
    const runtime::FieldType& got = s.field(index).type();
    std::string why = mismatch(*want, got.kind, got.single, got.dims, float_size);
    if (!why.empty())
      problems.push_back(who + "field '" + f.name + "' is " + spelled +
                         " in the program but the set's field '" + f.name + "' " + why);
  }
}

}  // namespace

std::optional<runtime::FieldType> field_type_for(const Type& type, int float_size) {
  runtime::FieldType out;
  const Type* t = &type;
  while (t->kind == Type::Kind::Tensor) {
    for (const IndexSet& d : t->dims) {
      if (d.kind != IndexSet::Kind::Fixed) return std::nullopt;
      out.dims.push_back(d.size);
    }
    if (!t->block) return std::nullopt;
    t = t->block.get();
  }
  if (t->kind != Type::Kind::Scalar) return std::nullopt;
  auto kind = field_component_of(t->scalar);
  if (!kind) return std::nullopt;
  out.kind = *kind;
  out.single =
      float_size == 4 && (out.kind == ComponentKind::Float || out.kind == ComponentKind::Complex);
  return out;
}

std::vector<std::string> check_set(const ast::Variable& var, const runtime::Set& set,
                                   int float_size) {
  std::vector<std::string> problems;
  const std::string who = "extern '" + var.name + "': ";
  const Type& t = *var.type;
  check_kind(who, t, set, problems);
  if (t.element) check_fields(who, *t.element, set, float_size, problems);
  return problems;
}

std::vector<std::string> check_endpoints(
    const ast::Variable& var, const runtime::Set& set,
    const std::function<const runtime::Set*(const ast::Variable&)>& bound) {
  std::vector<std::string> problems;
  const Type& t = *var.type;
  const size_t n = std::min(t.endpoints.size(), static_cast<size_t>(set.arity()));
  for (size_t k = 0; k < n; ++k) {
    const IndexSet& d = t.endpoints[k];
    if (d.kind != IndexSet::Kind::Set || !d.var) continue;
    const runtime::Set* want = bound(*d.var);
    if (!want) continue;
    const runtime::Set& got = set.endpoint_set(static_cast<int>(k));
    if (&got != want)
      problems.push_back("extern '" + var.name + "': endpoint " + std::to_string(k) +
                         " must come from the set bound to '" + d.var->name + "' (" +
                         want->describe() + "), but the bound set's endpoint " + std::to_string(k) +
                         " is " + got.describe());
  }
  return problems;
}

std::vector<std::string> check_tensor(const std::string& what, const Type& type,
                                      const TensorSlot& tensor, int float_size) {
  const std::string spelled = frontend::to_string(type);
  auto want = field_type_for(type, float_size);
  if (!want) {
    if (type.is_tensor() && type.is_global())
      return {what + " has type " + spelled +
              ", whose size depends on a set; bind the set instead (host tensors have fixed "
              "dimensions)"};
    return {what + " has type " + spelled + ", which a host tensor cannot hold"};
  }
  std::string why =
      mismatch(*want, runtime_kind(tensor.kind), tensor.single, tensor.dims, float_size);
  if (why.empty()) return {};
  return {what + " is " + spelled + " in the program but the host tensor (" +
          host_type_name(runtime_kind(tensor.kind), tensor.single, tensor.dims) + ") " + why};
}

std::string host_type_name(ComponentKind kind, bool single, const std::vector<int>& dims) {
  std::string s;
  switch (kind) {
    case ComponentKind::Int: s = "int"; break;
    case ComponentKind::Float: s = single ? "float" : "double"; break;
    case ComponentKind::Bool: s = "bool"; break;
    case ComponentKind::Complex: s = single ? "float_complex" : "double_complex"; break;
    case ComponentKind::String: s = "string"; break;
  }
  return dims.empty() ? s : s + " " + dims_text(dims);
}

}  // namespace simit::api
