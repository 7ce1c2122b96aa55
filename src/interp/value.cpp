// Run-time values of the interpreter.
#include "interp/value.h"

#include "runtime/fault.h"

namespace simit::interp {

Value Value::zero(ComponentKind k) {
  switch (k) {
    case ComponentKind::Int: return of_int(0);
    case ComponentKind::Float: return of_float(0.0);
    case ComponentKind::Bool: return of_bool(false);
    case ComponentKind::Complex: return of_complex({0.0, 0.0});
    case ComponentKind::String: return of_string("");
  }
  return {};
}

Value Value::zero(ComponentKind k, const Shape& shape) {
  if (shape.is_scalar()) return zero(k);
  return of_tensor(Tensor(k, shape));
}

Value Value::component(const Tensor& t, size_t i) {
  switch (t.kind()) {
    case ComponentKind::Int: return of_int(t.ints()[i]);
    case ComponentKind::Float: return of_float(t.floats()[i]);
    case ComponentKind::Bool: return of_bool(t.bools()[i]);
    case ComponentKind::Complex: return of_complex(t.complexes()[i]);
    case ComponentKind::String: return of_string(t.strings()[i]);
  }
  return {};
}

ComponentKind Value::component_kind() const {
  switch (kind_) {
    case Kind::Int: return ComponentKind::Int;
    case Kind::Float: return ComponentKind::Float;
    case Kind::Bool: return ComponentKind::Bool;
    case Kind::Complex: return ComponentKind::Complex;
    case Kind::String: return ComponentKind::String;
    case Kind::Tensor: return t_.kind();
    case Kind::Matrix: return m_ ? m_->kind() : ComponentKind::Float;
    default: break;
  }
  throw runtime::Fault("a value was used before it was assigned");
}

Tensor Value::to_tensor() const {
  if (is_tensor()) return t_;
  Tensor t(component_kind(), Shape());
  fill_into(t, 0, 1);
  return t;
}

void Value::fill_into(Tensor& t, size_t offset, size_t count) const {
  switch (kind_) {
    case Kind::Int: return t.fill(offset, count, i_);
    case Kind::Float: return t.fill(offset, count, f_);
    case Kind::Bool: return t.fill(offset, count, b_);
    case Kind::Complex: return t.fill(offset, count, Complex(re_, im_));
    case Kind::String: return t.fill(offset, count, s_);
    default: throw runtime::Fault("only a scalar can fill tensor components");
  }
}

bool Value::operator==(const Value& o) const {
  if (kind_ != o.kind_) return false;
  switch (kind_) {
    case Kind::Empty: return true;
    case Kind::Int: return i_ == o.i_;
    case Kind::Float: return f_ == o.f_;
    case Kind::Bool: return b_ == o.b_;
    case Kind::Complex: return re_ == o.re_ && im_ == o.im_;
    case Kind::String: return s_ == o.s_;
    case Kind::Tensor: return t_ == o.t_;
    case Kind::Element:
    case Kind::Tuple: return set_ == o.set_ && i_ == o.i_;
    case Kind::Set: return set_ == o.set_;
    case Kind::Matrix: return m_ == o.m_;
    case Kind::Opaque: return o_ == o.o_;
  }
  return false;
}

}  // namespace simit::interp
