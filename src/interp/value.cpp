// Run-time values of the interpreter.
#include "interp/value.h"

#include <cstring>
#include <vector>

#include "runtime/fault.h"

namespace simit::interp {

namespace detail {

constinit thread_local TensorBoxes tensor_boxes{};

Tensor* new_tensor_box() { return new Tensor; }
void delete_tensor_box(Tensor* t) noexcept { delete t; }

}  // namespace detail

Value Value::of_string(std::string v) {
  Value x(Kind::String);
  x.u_.s = new std::string(std::move(v));
  return x;
}

Value Value::of_tensor(Tensor t) {
  Value x(Kind::Tensor);
  x.u_.t = detail::acquire_tensor_box();
  *x.u_.t = std::move(t);
  return x;
}

Value Value::of_matrix(std::shared_ptr<runtime::SystemMatrix> m) {
  Value x(Kind::Matrix);
  x.u_.m = new std::shared_ptr<runtime::SystemMatrix>(std::move(m));
  return x;
}

Value Value::of_opaque(std::shared_ptr<SolverHandle> h) {
  Value x(Kind::Opaque);
  x.u_.o = new std::shared_ptr<SolverHandle>(std::move(h));
  return x;
}

void Value::copy_from(const Value& o) {
  kind_ = o.kind_;
  i_ = o.i_;
  aux_ = o.aux_;
  switch (kind_) {
    case Kind::String: u_.s = new std::string(*o.u_.s); break;
    case Kind::Tensor:
      u_.t = detail::acquire_tensor_box();
      *u_.t = *o.u_.t;
      break;
    case Kind::Matrix: u_.m = new std::shared_ptr<runtime::SystemMatrix>(*o.u_.m); break;
    case Kind::Opaque: u_.o = new std::shared_ptr<SolverHandle>(*o.u_.o); break;
    default: u_ = o.u_; break;
  }
}

void Value::release() noexcept {
  switch (kind_) {
    case Kind::String: delete u_.s; break;
    case Kind::Tensor: detail::recycle_tensor_box(u_.t); break;
    case Kind::Matrix: delete u_.m; break;
    case Kind::Opaque: delete u_.o; break;
    default: break;
  }
  kind_ = Kind::Empty;
}

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
  if (k == ComponentKind::String) return of_tensor(Tensor(k, shape));
  Value v = uninit_tensor(k, shape);
  Tensor& t = v.tensor();
  std::memset(t.mutable_ints(), 0, component_bytes(k) * t.size());
  return v;
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

ComponentKind Value::component_kind_slow() const {
  switch (kind_) {
    case Kind::Bool: return ComponentKind::Bool;
    case Kind::Complex: return ComponentKind::Complex;
    case Kind::String: return ComponentKind::String;
    case Kind::Matrix: return *u_.m ? (*u_.m)->kind() : ComponentKind::Float;
    default: break;
  }
  throw runtime::Fault("a value was used before it was assigned");
}

Tensor Value::to_tensor() const {
  if (is_tensor()) return *u_.t;
  Tensor t(component_kind(), Shape());
  fill_into(t, 0, 1);
  return t;
}

void Value::fill_into(Tensor& t, size_t offset, size_t count) const {
  switch (kind_) {
    case Kind::Int: return t.fill(offset, count, i_);
    case Kind::Float: return t.fill(offset, count, u_.f);
    case Kind::Bool: return t.fill(offset, count, u_.b);
    case Kind::Complex: return t.fill(offset, count, as_complex());
    case Kind::String: return t.fill(offset, count, *u_.s);
    default: throw runtime::Fault("only a scalar can fill tensor components");
  }
}

bool Value::operator==(const Value& o) const {
  if (kind_ != o.kind_) return false;
  switch (kind_) {
    case Kind::Empty: return true;
    case Kind::Int: return i_ == o.i_;
    case Kind::Float: return u_.f == o.u_.f;
    case Kind::Bool: return u_.b == o.u_.b;
    case Kind::Complex: return as_complex() == o.as_complex();
    case Kind::String: return *u_.s == *o.u_.s;
    case Kind::Tensor: return *u_.t == *o.u_.t;
    case Kind::Element:
    case Kind::Tuple: return u_.set == o.u_.set && i_ == o.i_;
    case Kind::Set: return u_.set == o.u_.set;
    case Kind::Matrix: return *u_.m == *o.u_.m;
    case Kind::Opaque: return *u_.o == *o.u_.o;
  }
  return false;
}

}  // namespace simit::interp
