// Sets in the interpreter: binding host sets, element and set field reads and writes,
// endpoint tuples, grid reads and loops over sets.
#include <cstring>

#include "interp/frame.h"
#include "interp/interpreter.h"
#include "interp/map_context.h"

namespace simit::interp {

namespace ast = frontend::ast;
using frontend::IndexSet;
using frontend::SourceSpan;
using frontend::Type;

runtime::FieldType field_type_of(const Type& t) {
  runtime::FieldType ft;
  const Type* s = &t;
  if (t.kind == Type::Kind::Tensor) {
    for (const IndexSet& d : t.dims) ft.dims.push_back(d.size);
    if (t.block && t.block->kind == Type::Kind::Tensor)
      for (const IndexSet& d : t.block->dims) ft.dims.push_back(d.size);
    s = t.block.get();
    while (s && s->kind == Type::Kind::Tensor) s = s->block.get();
  }
  switch (s ? s->scalar : frontend::ScalarKind::Float) {
    case frontend::ScalarKind::Int: ft.kind = ComponentKind::Int; break;
    case frontend::ScalarKind::Bool: ft.kind = ComponentKind::Bool; break;
    case frontend::ScalarKind::Complex: ft.kind = ComponentKind::Complex; break;
    case frontend::ScalarKind::String: ft.kind = ComponentKind::String; break;
    case frontend::ScalarKind::Float: ft.kind = ComponentKind::Float; break;
  }
  return ft;
}

void Interpreter::bind_set(const ast::Variable& v, runtime::Set& set) {
  const Type& t = *v.type;
  if (t.kind != Type::Kind::Set || !t.element)
    fail(v.span, "extern '" + v.name + "' is not a set");
  SetBinding* b = nullptr;
  for (auto& existing : bindings_)
    if (existing->set == &set && existing->element == t.element) b = existing.get();
  if (!b) {
    bindings_.push_back(std::make_unique<SetBinding>());
    b = bindings_.back().get();
    b->set = &set;
    b->element = t.element;
    for (const ast::FieldDecl& f : t.element->fields) {
      int index = set.field_index(f.name);
      if (index < 0)
        fail(v.span, "set '" + v.name + "' has no field '" + f.name + "' of element type '" +
                         t.element->name + "'");
      runtime::FieldType want = field_type_of(*f.type), got = set.field(index).type();
      if (want.kind != got.kind || want.dims != got.dims)
        fail(v.span, "field '" + f.name + "' of set '" + v.name + "' has type '" + got.str() +
                         "' but the program declares '" + want.str() + "'");
      b->fields.push_back(index);
    }
  }
  const size_t arity = t.endpoints.size();
  if (t.grid_dims == 0 && static_cast<size_t>(set.arity()) != arity)
    fail(v.span, "set '" + v.name + "' has " + std::to_string(set.arity()) +
                     " endpoints but the program declares " + std::to_string(arity));
  if (t.grid_dims > 0 && (!set.is_grid() || set.dimensions() != t.grid_dims))
    fail(v.span, "set '" + v.name + "' is not a " + std::to_string(t.grid_dims) + "-d grid");
  globals_.at(v.slot) = Value::of_set(b);
}

SetBinding& Interpreter::binding_of(const runtime::Set& s, const SourceSpan& at) {
  for (auto& b : bindings_)
    if (b->set == &s) return *b;
  fail(at, "set '" + s.name() + "' is not bound to the program");
}

int Interpreter::set_size(const ast::Variable& v, const SourceSpan& at) {
  const Value& s = var(v);
  if (s.kind() == Value::Kind::Set) return s.binding()->set->size();
  if (s.kind() == Value::Kind::Int) return s.as_int();
  fail(at, "set '" + v.name + "' has no value (the host did not bind it)");
}

namespace {

Value from_tensor(Tensor t) {
  if (t.shape().is_scalar()) return Value::component(t, 0);
  return Value::of_tensor(std::move(t));
}

}  // namespace

Value Interpreter::field_vector(const SetBinding& b, int field) {
  const runtime::Field& f = b.set->field(b.fields[field]);
  const int n = b.set->size();
  Shape block = Shape::of(f.type().dims);
  Tensor t(f.type().kind, Shape::blocked(std::vector<int>{n}, block));
  if (!f.type().single && f.type().kind != ComponentKind::String) {
    if (t.size()) std::memcpy(t.mutable_floats(), f.bytes(), t.size() * component_bytes(t.kind()));
  } else {
    for (int e = 0; e < n; ++e) t.write_range(e * block.size(), b.set->get(b.fields[field], e));
  }
  return Value::of_tensor(std::move(t));
}

Value Interpreter::eval_field_read(const ast::FieldRead& r) {
  Value scratch;
  const Value& base = operand(*r.base, scratch);
  if (r.of_set || base.kind() == Value::Kind::Set) return field_vector(*base.binding(), r.field_index);
  if (base.kind() != Value::Kind::Element) fail(r.span, "field read of a value that is not an element");
  const SetBinding& b = *base.binding();
  return from_tensor(b.set->get(b.fields[r.field_index], base.index()));
}

Value Interpreter::eval_tuple_read(const ast::TupleRead& r) {
  Value scratch;
  const Value& t = operand(*r.base, scratch);
  if (t.kind() != Value::Kind::Tuple) fail(r.span, "tuple read of a value that is not a tuple");
  int k = r.member_index;
  if (r.index) {
    Value i = eval(*r.index);
    k = i.as_int();
  }
  const runtime::Set& edges = *t.binding()->set;
  if (k < 0 || k >= edges.arity())
    fail(r.span, "tuple index " + std::to_string(k) + " is out of range for " +
                     std::to_string(edges.arity()) + " endpoints");
  return Value::of_element(&binding_of(edges.endpoint_set(k), r.span), edges.endpoint(t.index(), k));
}

// `g[o;q]` (a link of the grid) and `P[o]` (a point at an offset), relative to the point
// the stencil map is visiting.
Value Interpreter::eval_set_read(const ast::SetRead& r) {
  if (!map_ || !map_->grid) fail(r.span, "grid reads are only possible inside a map through a grid");
  Value scratch;
  const Value& base = operand(*r.base, scratch);
  auto ints = [&](const std::vector<ast::ExprPtr>& exprs) {
    std::vector<int> out;
    for (const auto& e : exprs) out.push_back(eval(*e).as_int());
    return out;
  };
  const runtime::Set& grid = *map_->grid->set;
  std::vector<int> first = ints(r.first);
  if (static_cast<int>(first.size()) != grid.dimensions())
    fail(r.span, "grid access expects " + std::to_string(grid.dimensions()) + " offsets");
  try {
    if (r.has_semicolon) {
      std::vector<int> second = ints(r.second);
      int link = grid.grid_link_between(map_->element, first, second);
      return Value::of_element(base.binding(), link);
    }
    int point = grid.grid_point_at(map_->element, first);
    return Value::of_element(base.binding(), point, map_->offset_tag(first));
  } catch (const runtime::Fault& f) {
    fail(r.span, f.what());
  }
}

Place Interpreter::field_place(const ast::FieldRead& r) {
  Value base = eval(*r.base);
  if (base.kind() != Value::Kind::Element && base.kind() != Value::Kind::Set)
    fail(r.span, "field write to a value that is not an element or a set");
  const SetBinding& b = *base.binding();
  Place p;
  p.field_set = b.set;
  p.field = b.fields[r.field_index];
  p.element = base.kind() == Value::Kind::Element ? base.index() : -1;
  p.staged = std::make_shared<Value>(p.element < 0 ? field_vector(b, r.field_index)
                                                   : from_tensor(b.set->get(p.field, p.element)));
  p.root = p.staged.get();
  return p;
}

void Interpreter::store_field(const Place& p) {
  runtime::Set& s = *p.field_set;
  const Value& v = *p.root;
  if (p.element >= 0) {
    s.set(p.field, p.element, v.to_tensor());
    return;
  }
  const Tensor& t = v.tensor();
  runtime::Field& f = s.field(p.field);
  const size_t per = f.components();
  if (t.size() != per * static_cast<size_t>(s.size()))
    throw runtime::Fault("a vector of " + std::to_string(t.size()) + " components cannot be stored in field '" +
                         f.name() + "' of " + s.describe());
  const Shape block = Shape::of(f.type().dims);
  for (int e = 0; e < s.size(); ++e) s.set(p.field, e, t.range(e * per, block));
}

}  // namespace simit::interp
