// Type checker: types as written (§5) and the type helpers the other checker files use.
#include <algorithm>
#include <unordered_set>

#include "frontend/checker_impl.h"

namespace simit::frontend::checker_detail {

using ast::Variable;

// ---------------------------------------------------------------------------
// Type construction, substitution and comparison

TypeRef element_type(const ast::ElementDecl* decl, IndexSet source, bool has_source) {
  auto t = std::make_shared<Type>();
  t->kind = Type::Kind::Element;
  t->element = decl;
  t->source = source;
  t->has_source = has_source;
  return t;
}

TypeRef generic_element_type(const Variable* generic) {
  return element_type(nullptr, IndexSet::generic(generic), true);
}

TypeRef with_source(const TypeRef& element, IndexSet source) {
  return element_type(element->element, source, true);
}

TypeRef tuple_type(std::vector<TypeRef> members, std::vector<std::string> names) {
  auto t = std::make_shared<Type>();
  t->kind = Type::Kind::Tuple;
  t->members = std::move(members);
  t->names = std::move(names);
  return t;
}

IndexSet substitute(const IndexSet& d, const Subst& s) {
  if (d.kind == IndexSet::Kind::Fixed || d.var == nullptr) return d;
  auto it = s.find(d.var);
  return it == s.end() ? d : it->second;
}

TypeRef substitute(const TypeRef& t, const Subst& s) {
  if (!t || s.empty()) return t;
  switch (t->kind) {
    case Type::Kind::Tensor: {
      std::vector<IndexSet> dims;
      for (const auto& d : t->dims) dims.push_back(substitute(d, s));
      return make_tensor(std::move(dims), substitute(t->block, s), t->row);
    }
    case Type::Kind::Element:
      if (!t->has_source) return t;
      return element_type(t->element, substitute(t->source, s), true);
    case Type::Kind::Tuple:
    case Type::Kind::Multi:
    case Type::Kind::Set: {
      auto c = std::make_shared<Type>(*t);
      for (auto& m : c->members) m = substitute(m, s);
      for (auto& e : c->endpoints) e = substitute(e, s);
      return c;
    }
    default: return t;
  }
}

static const ast::ElementDecl* element_of_set(const IndexSet& d) {
  if (d.kind != IndexSet::Kind::Set || !d.var || !d.var->type) return nullptr;
  return d.var->type->element;
}

static bool same_set_type(const Type& a, const Type& b) {
  if (a.element != b.element || a.grid_dims != b.grid_dims) return false;
  if (a.endpoints.size() != b.endpoints.size()) return false;
  for (size_t i = 0; i < a.endpoints.size(); ++i) {
    if (a.grid_dims > 0) {
      if (a.endpoints[i] != b.endpoints[i]) return false;
    } else if (element_of_set(a.endpoints[i]) != element_of_set(b.endpoints[i])) {
      return false;
    }
  }
  return true;
}

static bool same_members(const Type& a, const Type& b) {
  if (a.members.size() != b.members.size()) return false;
  for (size_t i = 0; i < a.members.size(); ++i) {
    if (!a.members[i] || !b.members[i] || !same_type(*a.members[i], *b.members[i])) return false;
  }
  return true;
}

bool same_type(const Type& a, const Type& b) {
  if (a.kind != b.kind) return false;
  switch (a.kind) {
    case Type::Kind::Void:
    case Type::Kind::Opaque: return true;
    case Type::Kind::Scalar:
    case Type::Kind::Tensor: return types_equal(a, b);
    case Type::Kind::Element:
      return a.element == b.element && (!a.has_source || !b.has_source || a.source == b.source);
    case Type::Kind::Tuple:
      if (!same_members(a, b)) return false;
      // Names matter only where both sides are named (endpoint tuples are unnamed).
      if (!a.names.empty() && !b.names.empty()) return a.names == b.names;
      return true;
    case Type::Kind::Set: return same_set_type(a, b);
    case Type::Kind::Multi: return same_members(a, b);
  }
  return false;
}

bool is_single_value(const Type& t) {
  return t.kind != Type::Kind::Void && t.kind != Type::Kind::Multi;
}

bool is_tensor_or_opaque(const Type& t) { return t.is_tensor() || t.kind == Type::Kind::Opaque; }

bool is_int(const Type& t) { return t.is_scalar() && t.scalar == ScalarKind::Int; }

bool is_bool(const Type& t) { return t.is_scalar() && t.scalar == ScalarKind::Bool; }

bool is_set_var(const Variable* v) {
  return v && v->kind != Variable::Kind::Generic && v->type && v->type->kind == Type::Kind::Set;
}

bool is_int_dim(const IndexSet& d) {
  return d.kind == IndexSet::Kind::Fixed ||
         (d.kind == IndexSet::Kind::Generic && d.var && d.var->ranged);
}

// The product of the integer dimensions over all blocking levels (a set or generic
// dimension counts 1), saturated just above the limit so that it cannot wrap.
uint64_t fixed_components(const Type& t) {
  uint64_t n = 1;
  for (const Type* level = &t; level && level->kind == Type::Kind::Tensor;
       level = level->block.get())
    for (const IndexSet& d : level->dims)
      if (d.kind == IndexSet::Kind::Fixed && d.size > 0)
        n = std::min<uint64_t>(n * static_cast<uint64_t>(d.size), kMaxTensorComponents + 1);
  return n;
}

std::string index_set_name(const IndexSet& d) {
  if (d.kind == IndexSet::Kind::Fixed) return std::to_string(d.size);
  return d.var ? d.var->name : "?";
}

static std::string element_name(const Type& t) {
  if (t.element) return t.element->name;
  return "element of " + index_set_name(t.source);
}

static std::string set_type_name(const Type& t) {
  std::string e = t.element ? t.element->name : "?";
  if (t.grid_dims > 0) {
    std::string p = t.endpoints.empty() ? "?" : index_set_name(t.endpoints[0]);
    return "grid[" + std::to_string(t.grid_dims) + "]{" + e + "}(" + p + ")";
  }
  std::string s = "set{" + e + "}";
  if (t.endpoints.empty()) return s;
  s += "(";
  for (size_t i = 0; i < t.endpoints.size(); ++i)
    s += (i ? ", " : "") + index_set_name(t.endpoints[i]);
  return s + ")";
}

static std::string tuple_type_name(const Type& t) {
  bool uniform = t.names.empty() && !t.members.empty();
  for (const auto& m : t.members)
    if (!m || !t.members[0] || m->element != t.members[0]->element) uniform = false;
  if (uniform)
    return "(" + element_name(*t.members[0]) + " * " + std::to_string(t.members.size()) + ")";
  std::string s = "(";
  for (size_t i = 0; i < t.members.size(); ++i) {
    s += i ? ", " : "";
    if (i < t.names.size()) s += t.names[i] + " : ";
    s += t.members[i] ? element_name(*t.members[i]) : "?";
  }
  return s + ")";
}

std::string type_name(const Type& t) {
  switch (t.kind) {
    case Type::Kind::Void: return "void";
    case Type::Kind::Opaque: return "opaque";
    case Type::Kind::Element: return element_name(t);
    case Type::Kind::Set: return set_type_name(t);
    case Type::Kind::Tuple: return tuple_type_name(t);
    case Type::Kind::Multi: {
      std::string s = "(";
      for (size_t i = 0; i < t.members.size(); ++i)
        s += (i ? ", " : "") + (t.members[i] ? type_name(*t.members[i]) : "?");
      return s + ")";
    }
    case Type::Kind::Scalar:
    case Type::Kind::Tensor: return to_string(t);
  }
  return "?";
}

std::string quoted(const Type& t) { return "'" + type_name(t) + "'"; }

// ---------------------------------------------------------------------------
// Types as written

TypeRef Checker::resolve_type(ast::TypeExpr& t, TypePos pos) {
  TypeRef r = resolve_type_expr(t);
  if (r && !check_position(t, *r, pos)) return nullptr;
  t.type = r;
  return r;
}

bool Checker::check_position(const ast::TypeExpr& t, const Type& type, TypePos pos) {
  switch (pos) {
    case TypePos::Field:
      if (type.is_tensor() && !type.is_global()) return true;
      error(SemanticKind::Type, t.span,
            "element fields must have tensor types without set dimensions, not " + quoted(type));
      return false;
    case TypePos::Extern:
      if (type.is_tensor() || type.kind == Type::Kind::Set) return true;
      error(SemanticKind::Type, t.span,
            "externs must have a set or tensor type, not " + quoted(type));
      return false;
    case TypePos::GlobalConst:
    case TypePos::Local:
      if (type.is_tensor()) return true;
      error(SemanticKind::Type, t.span,
            "cannot declare a non-tensor variable of type " + quoted(type));
      return false;
    case TypePos::Param:
    case TypePos::Result: return true;
  }
  return true;
}

TypeRef Checker::resolve_type_expr(ast::TypeExpr& t) {
  switch (t.kind) {
    case ast::NodeKind::ScalarTypeExpr: return make_scalar(t.as<ast::ScalarTypeExpr>()->scalar);
    case ast::NodeKind::TensorTypeExpr: return resolve_tensor_type(*t.as<ast::TensorTypeExpr>());
    case ast::NodeKind::NamedTypeExpr: {
      auto* n = t.as<ast::NamedTypeExpr>();
      n->element = resolve_element(n->name, n->span);
      return n->element ? element_type(n->element, IndexSet::fixed(0), false) : nullptr;
    }
    case ast::NodeKind::SetTypeExpr: return resolve_set_type(*t.as<ast::SetTypeExpr>());
    case ast::NodeKind::GridTypeExpr: return resolve_grid_type(*t.as<ast::GridTypeExpr>());
    case ast::NodeKind::TupleTypeExpr: return resolve_tuple_type(*t.as<ast::TupleTypeExpr>());
    case ast::NodeKind::OpaqueTypeExpr: return make_opaque();
    default: SIMIT_ASSERT(false, "not a type node");
  }
  return nullptr;
}

const ast::ElementDecl* Checker::resolve_element(const std::string& name, SourceSpan span) {
  auto it = elements_.find(name);
  if (it != elements_.end()) return it->second;
  undeclared("undeclared element type", name, span);
  return nullptr;
}

// A name used as a tensor dimension or explicit generic argument: a set or a generic
// parameter of the enclosing function.
bool Checker::resolve_dim(ast::IndexSetExpr& d, bool allow_generic) {
  if (d.is_int) {
    if (d.value < 1 || d.value > 0x7fffffff) {
      error(SemanticKind::Dimension, d.span,
            "dimension size must be positive, not " + std::to_string(d.value));
      return false;
    }
    d.resolved = IndexSet::fixed(static_cast<int>(d.value));
    return true;
  }
  Variable* v = scopes_.lookup(d.name);
  if (v && v->kind == Variable::Kind::Generic && allow_generic) {
    d.resolved = IndexSet::generic(v);
    return true;
  }
  return resolve_set_name(d);
}

bool Checker::resolve_set_name(ast::IndexSetExpr& d) {
  if (d.is_int) {
    error(SemanticKind::Type, d.span,
          "expected a set but got the integer " + std::to_string(d.value));
    return false;
  }
  Variable* v = scopes_.lookup(d.name);
  if (!v) {
    undeclared("undeclared set", d.name, d.span);
    return false;
  }
  if (is_set_var(v)) {
    d.resolved = IndexSet::set(v);
    return true;
  }
  if (v->kind == Variable::Kind::Generic) {
    error(SemanticKind::Type, d.span, "expected a set but '" + d.name + "' is a generic parameter");
  } else if (v->type) {
    error(SemanticKind::Type, d.span,
          "expected a set but '" + d.name + "' is of type " + quoted(*v->type));
  } else if (v->kind == Variable::Kind::IndexVar) {
    error(SemanticKind::Type, d.span, "expected a set but '" + d.name + "' is an index variable");
  }
  return false;
}

TypeRef Checker::resolve_tensor_type(ast::TensorTypeExpr& t) {
  TypeRef block = t.block ? resolve_type_expr(*t.block) : nullptr;
  if (t.block) t.block->type = block;
  if (!block) return nullptr;
  if (!block->is_tensor()) {
    error(SemanticKind::Type, t.block->span, "tensor blocks must be tensor types");
    return nullptr;
  }
  if (t.dims.empty()) {
    if (!t.transposed) return block;
    if (block->order() != 1 || block->row) {
      error(SemanticKind::Type, t.span, "transposed type must be a vector");
      return nullptr;
    }
    return make_tensor(block->dims, block->block, true);
  }
  std::vector<IndexSet> dims;
  bool ok = true, has_set = false, has_int = false;
  for (auto& d : t.dims) {
    if (!resolve_dim(d, true)) {
      ok = false;
      continue;
    }
    dims.push_back(d.resolved);
    has_set |= d.resolved.kind == IndexSet::Kind::Set;
    has_int |= is_int_dim(d.resolved);
  }
  if (!ok) return nullptr;
  if (block->kind == Type::Kind::Tensor && block->order() != static_cast<int>(dims.size())) {
    error(SemanticKind::Dimension, t.span,
          "blocked tensor type must contain same number of dimensions as its blocks");
    return nullptr;
  }
  if (has_set && has_int) {
    error(SemanticKind::Dimension, t.span,
          "a tensor cannot mix integer and set dimensions; use a blocked type");
    return nullptr;
  }
  if (has_set && dims.size() > 2) {
    error(SemanticKind::Dimension, t.span, "tensors with set dimensions must have order 1 or 2");
    return nullptr;
  }
  if (t.transposed && dims.size() != 1) {
    error(SemanticKind::Type, t.span, "transposed type must be a vector");
    return nullptr;
  }
  TypeRef tensor = make_tensor(std::move(dims), block, t.transposed);
  if (fixed_components(*tensor) > kMaxTensorComponents) {
    error(SemanticKind::Dimension, t.span,
          "tensor type has more than " + std::to_string(kMaxTensorComponents) +
              " components (2^31 - 1, the limit for a dense tensor)");
    return nullptr;
  }
  return tensor;
}

TypeRef Checker::resolve_set_type(ast::SetTypeExpr& t) {
  const ast::ElementDecl* e = resolve_element(t.element, t.element_span);
  if (!e) return nullptr;
  if (t.shorthand && t.shorthand_count < 1) {
    error(SemanticKind::Type, t.span, "edge set must have positive arity");
    return nullptr;
  }
  auto s = std::make_shared<Type>();
  s->kind = Type::Kind::Set;
  s->element = e;
  for (auto& d : t.endpoints) {
    if (!resolve_set_name(d)) return nullptr;
    s->endpoints.push_back(d.resolved);
  }
  return s;
}

TypeRef Checker::resolve_grid_type(ast::GridTypeExpr& t) {
  const ast::ElementDecl* e = resolve_element(t.element, t.element_span);
  if (!e) return nullptr;
  if (t.dims < 1 || t.dims > 16) {
    error(SemanticKind::Type, t.span, "grid must have between 1 and 16 dimensions");
    return nullptr;
  }
  if (!resolve_set_name(t.point_set)) return nullptr;
  const Type& p = *t.point_set.resolved.var->type;
  if (p.grid_dims > 0) {
    error(SemanticKind::Type, t.point_set.span,
          "expected underlying point set of unstructured kind");
    return nullptr;
  }
  if (!p.endpoints.empty()) {
    error(SemanticKind::Type, t.point_set.span,
          "expected underlying point set of zero cardinality");
    return nullptr;
  }
  auto s = std::make_shared<Type>();
  s->kind = Type::Kind::Set;
  s->element = e;
  s->grid_dims = static_cast<int>(t.dims);
  s->endpoints.push_back(t.point_set.resolved);
  return s;
}

TypeRef Checker::resolve_tuple_type(ast::TupleTypeExpr& t) {
  std::vector<TypeRef> members;
  if (!t.named) {
    if (t.count < 1 || t.elements.empty()) {
      error(SemanticKind::Type, t.span, "tuple must have positive length");
      return nullptr;
    }
    SourceSpan span = t.element_spans.empty() ? t.span : t.element_spans[0];
    const ast::ElementDecl* e = resolve_element(t.elements[0], span);
    if (!e) return nullptr;
    if (t.count > 4096) {
      error(SemanticKind::Type, t.span, "tuple is too long");
      return nullptr;
    }
    for (long long i = 0; i < t.count; ++i)
      members.push_back(element_type(e, IndexSet::fixed(0), false));
    return tuple_type(std::move(members), {});
  }
  std::unordered_set<std::string> seen;
  for (size_t i = 0; i < t.elements.size() && i < t.names.size(); ++i) {
    SourceSpan span = i < t.element_spans.size() ? t.element_spans[i] : t.span;
    if (!seen.insert(t.names[i]).second) {
      error(SemanticKind::Redefinition, span, "redefinition of tuple element '" + t.names[i] + "'");
      return nullptr;
    }
    const ast::ElementDecl* e = resolve_element(t.elements[i], span);
    if (!e) return nullptr;
    members.push_back(element_type(e, IndexSet::fixed(0), false));
  }
  if (members.empty()) {
    error(SemanticKind::Type, t.span, "tuple must have positive length");
    return nullptr;
  }
  return tuple_type(std::move(members), t.names);
}

}  // namespace simit::frontend::checker_detail
