// Sets in the interpreter: binding host sets, element and set field reads and writes,
// endpoint tuples, grid reads and loops over sets.
#include <cstring>
#include <utility>

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
  if (t.kind != Type::Kind::Set || !t.element) fail(v.span, "extern '" + v.name + "' is not a set");
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
      b->field_shapes.push_back(shape_of(*f.type, f.span));
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

// Components [offset, offset + shape.size()) of a field's array, read in place (float32
// storage converted), as a scalar for the scalar shape.
Value read_components(const runtime::Field& f, size_t offset, const Shape& shape) {
  const runtime::FieldType& t = f.type();
  if (shape.is_scalar()) {
    // The kind (and width) is the field type's, so its bytes are read without a check.
    const std::byte* bytes = f.bytes();
    switch (t.kind) {
      case ComponentKind::Int:
        return Value::of_int(reinterpret_cast<const int32_t*>(bytes)[offset]);
      case ComponentKind::Bool: return Value::of_bool(reinterpret_cast<const bool*>(bytes)[offset]);
      case ComponentKind::Float:
        return Value::of_float(t.single ? reinterpret_cast<const float*>(bytes)[offset]
                                        : reinterpret_cast<const double*>(bytes)[offset]);
      case ComponentKind::Complex:
        return Value::of_complex(t.single ? Complex(f.data<std::complex<float>>()[offset])
                                          : f.data<Complex>()[offset]);
      case ComponentKind::String: break;
    }
    throw runtime::Fault("field '" + f.name() + "' cannot be read");
  }
  if (t.kind == ComponentKind::String) return Value::of_tensor(Tensor(t.kind, shape));
  Value result = Value::uninit_tensor(t.kind, shape);
  Tensor& out = result.tensor();
  const size_t n = shape.size();
  if (t.kind == ComponentKind::Float && !t.single) {  // the common case: doubles, copied
    // The field type was just checked to be binary64: read its bytes without the check.
    const double* src = reinterpret_cast<const double*>(f.bytes()) + offset;
    double* dst = out.mutable_floats();
    for (size_t i = 0; i < n; ++i) dst[i] = src[i];
    return result;
  }
  if (t.single && t.kind == ComponentKind::Float) {
    const float* src = f.data<float>() + offset;
    double* dst = out.mutable_floats();
    for (size_t i = 0; i < n; ++i) dst[i] = src[i];
  } else if (t.single && t.kind == ComponentKind::Complex) {
    const std::complex<float>* src = f.data<std::complex<float>>() + offset;
    Complex* dst = out.mutable_complexes();
    for (size_t i = 0; i < n; ++i) dst[i] = Complex(src[i]);
  } else if (n) {
    const size_t w = t.component_bytes();
    std::memcpy(out.mutable_ints(), f.bytes() + offset * w, n * w);
  }
  return result;
}

}  // namespace

// `S.f` as a vector: shares the field's array (copy-on-write), no copy.
Value Interpreter::field_vector(const SetBinding& b, int field) {
  Tensor t = b.set->field_tensor(b.fields[field]);
  const Shape declared = Shape::blocked(std::vector<int>{b.set->size()}, b.field_shapes[field]);
  if (t.shape() != declared) t.reshape(declared);
  return Value::of_tensor(std::move(t));
}

Value Interpreter::eval_field_read(const ast::FieldRead& r) {
  Value scratch;
  const Value& base = operand(*r.base, scratch);
  if (r.of_set || base.kind() == Value::Kind::Set)
    return field_vector(*base.binding(), r.field_index);
  if (base.kind() != Value::Kind::Element)
    fail(r.span, "field read of a value that is not an element");
  const SetBinding& b = *base.binding();
  const runtime::Set& s = *b.set;
  if (base.index() < 0 || base.index() >= s.size())
    fail(r.span, s.describe() + " has no element " + std::to_string(base.index()));
  const runtime::Field& f = s.field(b.fields[r.field_index]);
  return read_components(f, static_cast<size_t>(base.index()) * f.components(),
                         b.field_shapes[r.field_index]);
}

Value Interpreter::eval_tuple_read(const ast::TupleRead& r) {
  Value scratch;
  const Value& t = operand(*r.base, scratch);
  if (t.kind() != Value::Kind::Tuple) fail(r.span, "tuple read of a value that is not a tuple");
  int k = r.member_index;
  if (const auto* lit = r.index ? r.index->as<ast::IntLit>() : nullptr) {
    k = static_cast<int>(lit->value);  // `p(1)`: the common, constant case
  } else if (r.index) {
    Value i = eval(*r.index);
    k = i.as_int();
  }
  const runtime::Set& edges = *t.binding()->set;
  if (k < 0 || k >= edges.arity())
    fail(r.span, "tuple index " + std::to_string(k) + " is out of range for " +
                     std::to_string(edges.arity()) + " endpoints");
  SetBinding& tb = *t.binding();
  if (tb.endpoint_bindings.size() != static_cast<size_t>(edges.arity())) [[unlikely]]
    tb.endpoint_bindings.assign(static_cast<size_t>(edges.arity()), nullptr);
  if (!tb.endpoint_bindings[k]) [[unlikely]]
    tb.endpoint_bindings[k] = &binding_of(edges.endpoint_set(k), r.span);
  return Value::of_element(tb.endpoint_bindings[k], edges.endpoint(t.index(), k));
}

// `g[o;q]` (a link of the grid) and `P[o]` (a point at an offset), relative to the point
// the stencil map is visiting.
Value Interpreter::eval_set_read(const ast::SetRead& r) {
  if (!map_ || !map_->grid)
    fail(r.span, "grid reads are only possible inside a map through a grid");
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
  if (base.kind() == Value::Kind::Element)
    return field_element_place(b, r.field_index, base.index(), r.span);
  Place p;
  p.field_set = b.set;
  p.field = b.fields[r.field_index];
  p.shape = Shape::blocked(std::vector<int>{b.set->size()}, b.field_shapes[r.field_index]);
  return p;
}

// `e.f` and `S.f(e)`: the element's components in the field's array.
Place Interpreter::field_element_place(const SetBinding& b, int field, int element,
                                       const SourceSpan& at) {
  const runtime::Set& s = *b.set;
  if (element < 0 || element >= s.size())
    fail(at, s.describe() + " has no element " + std::to_string(element));
  const runtime::Field& f = s.field(b.fields[field]);
  Place p;
  p.field_set = b.set;
  p.field = b.fields[field];
  p.element = element;
  p.whole = false;
  p.offset = static_cast<size_t>(element) * f.components();
  p.shape = b.field_shapes[field];
  return p;
}

Value Interpreter::read_field(const Place& p) const {
  const runtime::Set& s = *p.field_set;
  if (p.whole) {
    Tensor t = s.field_tensor(p.field);
    if (t.shape() != p.shape && t.size() == p.shape.size()) t.reshape(p.shape);
    return Value::of_tensor(std::move(t));
  }
  return read_components(s.field(p.field), p.offset, p.shape);
}

// Writes land in the field's array: `S.f = v` adopts v's storage (or copies it); a part is
// written in place through the array moved out of the set (copied first only while a value
// read earlier shares it) and put back.
void Interpreter::write_field(const Place& p, Value value, const SourceSpan& at) {
  runtime::Set& s = *p.field_set;
  if (p.whole && !value.is_scalar()) {
    if (!value.is_tensor()) fail(at, "only a tensor can be stored in a set field");
    s.assign_field(p.field, value.tensor());
    return;
  }
  const runtime::Field& f = std::as_const(s).field(p.field);
  // Stage one element for float32 storage, and for a pinned set, whose whole array would be
  // copied out and back (take_field cannot move it) for every element written.
  const bool one = (f.type().single || s.fields_pinned()) && p.element >= 0;
  const size_t base = one ? static_cast<size_t>(p.element) * f.components() : 0;
  Value staged = Value::of_tensor(one ? s.get(p.field, p.element) : s.take_field(p.field));
  Place q;
  q.root = &staged;
  q.whole = p.whole;
  q.offset = p.offset - base;
  q.shape = p.shape;
  q.accumulate = p.accumulate;
  auto put_back = [&] {
    if (one)
      s.set(p.field, p.element, staged.tensor());
    else
      s.assign_field(p.field, staged.tensor());
  };
  try {
    write_place_raw(q, std::move(value), at);
  } catch (...) {
    put_back();
    throw;
  }
  put_back();
}

}  // namespace simit::interp
