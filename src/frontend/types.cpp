// Construction, equality (LANGUAGE.md §10.2) and spelling of semantic types.
#include "frontend/types.h"

#include "frontend/ast.h"

namespace simit::frontend {

bool IndexSet::operator==(const IndexSet& o) const {
  if (kind != o.kind) return false;
  // Sets and generic parameters are equal only to themselves, never by shape.
  return kind == Kind::Fixed ? size == o.size : var == o.var;
}

ScalarKind Type::component() const {
  if (kind == Kind::Tensor && block) return block->component();
  return scalar;
}

bool Type::is_global() const {
  if (kind != Kind::Tensor) return false;
  for (const IndexSet& d : dims)
    if (d.kind != IndexSet::Kind::Fixed) return true;
  return block && block->is_global();
}

TypeRef make_void() {
  static const TypeRef v = std::make_shared<const Type>();
  return v;
}

TypeRef make_scalar(ScalarKind k) {
  auto t = std::make_shared<Type>();
  t->kind = Type::Kind::Scalar;
  t->scalar = k;
  return t;
}

TypeRef make_tensor(std::vector<IndexSet> dims, TypeRef block, bool row) {
  // `tensor(B)` is B itself (Q22).
  if (dims.empty()) return block;
  auto t = std::make_shared<Type>();
  t->kind = Type::Kind::Tensor;
  t->row = dims.size() == 1 && row;  // orientation is tracked for vectors only
  t->dims = std::move(dims);
  t->block = std::move(block);
  if (t->block) t->scalar = t->block->component();
  return t;
}

TypeRef make_opaque() {
  auto t = std::make_shared<Type>();
  t->kind = Type::Kind::Opaque;
  return t;
}

TypeRef make_multi(std::vector<TypeRef> members) {
  auto t = std::make_shared<Type>();
  t->kind = Type::Kind::Multi;
  t->members = std::move(members);
  return t;
}

namespace {

// A hand-built tensor without dimensions stands for its block.
const Type& strip(const Type& t) {
  if (t.kind == Type::Kind::Tensor && t.dims.empty() && t.block) return strip(*t.block);
  return t;
}

bool same_element(const ast::ElementDecl* a, const ast::ElementDecl* b) {
  if (a == b) return true;
  return a && b && a->name == b->name;
}

bool tensors_equal(const Type& a, const Type& b) {
  if (a.dims != b.dims) return false;
  if (a.dims.size() == 1 && a.row != b.row) return false;
  if (!a.block || !b.block) return a.block == b.block;
  return types_equal(*a.block, *b.block);
}

// A source of kind Fixed with size 0 stands for "unknown", whatever `has_source` says.
bool source_known(const Type& t) {
  return t.source.kind != IndexSet::Kind::Fixed || (t.has_source && t.source.size != 0);
}

bool elements_equal(const Type& a, const Type& b) {
  if (!same_element(a.element, b.element)) return false;
  return !(source_known(a) && source_known(b)) || a.source == b.source;
}

bool lists_equal(const std::vector<TypeRef>& a, const std::vector<TypeRef>& b) {
  if (a.size() != b.size()) return false;
  for (size_t i = 0; i < a.size(); ++i) {
    if (!a[i] || !b[i]) {
      if (a[i] != b[i]) return false;
    } else if (!types_equal(*a[i], *b[i])) {
      return false;
    }
  }
  return true;
}

bool tuples_equal(const Type& a, const Type& b) {
  if (!lists_equal(a.members, b.members)) return false;
  // Names only matter where both sides have them: map passes unnamed endpoint tuples.
  if (a.names.empty() || b.names.empty()) return true;
  for (size_t i = 0; i < a.names.size() && i < b.names.size(); ++i)
    if (!a.names[i].empty() && !b.names[i].empty() && a.names[i] != b.names[i]) return false;
  return true;
}

// The element type of an endpoint set, or null when the endpoint is not a typed set.
const ast::ElementDecl* endpoint_element(const IndexSet& s) {
  if (!s.var || !s.var->type || s.var->type->kind != Type::Kind::Set) return nullptr;
  return s.var->type->element;
}

bool sets_equal(const Type& a, const Type& b) {
  if (!same_element(a.element, b.element)) return false;
  if (a.grid_dims != b.grid_dims || a.endpoints.size() != b.endpoints.size()) return false;
  // A grid is tied to its point set; an edge set only to its endpoints' element types.
  if (a.grid_dims > 0) return a.endpoints == b.endpoints;
  for (size_t i = 0; i < a.endpoints.size(); ++i) {
    const ast::ElementDecl* ea = endpoint_element(a.endpoints[i]);
    const ast::ElementDecl* eb = endpoint_element(b.endpoints[i]);
    if (ea || eb ? !same_element(ea, eb) : a.endpoints[i] != b.endpoints[i]) return false;
  }
  return true;
}

std::string index_set_string(const IndexSet& s) {
  if (s.kind == IndexSet::Kind::Fixed) return std::to_string(s.size);
  return s.var ? s.var->name : std::string("?");
}

std::string index_list_string(const std::vector<IndexSet>& sets) {
  std::string out;
  for (size_t i = 0; i < sets.size(); ++i) {
    if (i > 0) out += ",";
    out += index_set_string(sets[i]);
  }
  return out;
}

std::string element_string(const ast::ElementDecl* e) { return e ? e->name : std::string("?"); }

std::string tensor_string(const Type& t) {
  std::string out = t.dims.size() == 1 ? "vector[" : "tensor[";
  out += index_list_string(t.dims) + "](";
  out += t.block ? to_string(*t.block) : std::string("?");
  out += ")";
  if (t.dims.size() == 1 && t.row) out += "'";
  return out;
}

std::string set_string(const Type& t) {
  if (t.grid_dims > 0)
    return "grid[" + std::to_string(t.grid_dims) + "]{" + element_string(t.element) + "}(" +
           index_list_string(t.endpoints) + ")";
  std::string out = "set{" + element_string(t.element) + "}";
  if (!t.endpoints.empty()) out += "(" + index_list_string(t.endpoints) + ")";
  return out;
}

std::string member_string(const TypeRef& m) { return m ? to_string(*m) : std::string("?"); }

std::string tuple_string(const Type& t) {
  if (t.names.empty()) {
    std::string first = t.members.empty() ? std::string("?") : member_string(t.members[0]);
    return "(" + first + "*" + std::to_string(t.members.size()) + ")";
  }
  std::string out = "(";
  for (size_t i = 0; i < t.members.size(); ++i) {
    if (i > 0) out += ", ";
    if (i < t.names.size()) out += t.names[i] + " : ";
    out += member_string(t.members[i]);
  }
  return out + ")";
}

std::string multi_string(const Type& t) {
  std::string out = "(";
  for (size_t i = 0; i < t.members.size(); ++i) {
    if (i > 0) out += ", ";
    out += member_string(t.members[i]);
  }
  return out + ")";
}

}  // namespace

bool types_equal(const Type& a0, const Type& b0) {
  const Type& a = strip(a0);
  const Type& b = strip(b0);
  if (a.kind != b.kind) return false;
  switch (a.kind) {
    case Type::Kind::Void: return true;
    case Type::Kind::Scalar: return a.scalar == b.scalar;
    case Type::Kind::Tensor: return tensors_equal(a, b);
    case Type::Kind::Element: return elements_equal(a, b);
    case Type::Kind::Set: return sets_equal(a, b);
    case Type::Kind::Tuple: return tuples_equal(a, b);
    case Type::Kind::Opaque: return true;
    case Type::Kind::Multi: return lists_equal(a.members, b.members);
  }
  return false;
}

std::string to_string(ScalarKind k) {
  switch (k) {
    case ScalarKind::Int: return "int";
    case ScalarKind::Float: return "float";
    case ScalarKind::Bool: return "bool";
    case ScalarKind::Complex: return "complex";
    case ScalarKind::String: return "string";
  }
  return "?";
}

std::string to_string(const Type& t0) {
  const Type& t = strip(t0);
  switch (t.kind) {
    case Type::Kind::Void: return "void";
    case Type::Kind::Scalar: return to_string(t.scalar);
    case Type::Kind::Tensor: return tensor_string(t);
    case Type::Kind::Element: return element_string(t.element);
    case Type::Kind::Set: return set_string(t);
    case Type::Kind::Tuple: return tuple_string(t);
    case Type::Kind::Opaque: return "opaque";
    case Type::Kind::Multi: return multi_string(t);
  }
  return "?";
}

}  // namespace simit::frontend
