// Run-time values of the interpreter: scalars held inline, dense tensors (small ones
// without heap allocation), and room for the set-related kinds that follow (element and
// set references, system vectors and matrices, tuples, opaque handles).
#pragma once

#include <cstdint>
#include <string>
#include <utility>

#include <memory>

#include "runtime/system_matrix.h"
#include "runtime/tensor.h"

namespace simit::interp {

struct SetBinding;
struct SolverHandle;

using runtime::Complex;
using runtime::ComponentKind;
using runtime::Shape;
using runtime::Tensor;

class Value {
 public:
  enum class Kind : uint8_t {
    Empty,  // no value yet (an unbound extern, a slot not yet assigned)
    Int,
    Float,
    Bool,
    Complex,
    String,
    Tensor,  // a dense tensor of order >= 1, possibly blocked (global vectors too)
    Element,  // one element of a bound set (set + index)
    Set,      // a bound set
    Tuple,    // the endpoint tuple of one edge (edge set + edge index)
    Matrix,   // a system matrix (block CSR over a shared pattern)
    Opaque,   // a solver factorisation
  };

  Value() = default;
  static Value of_int(int32_t v) {
    Value x(Kind::Int);
    x.i_ = v;
    return x;
  }
  static Value of_float(double v) {
    Value x(Kind::Float);
    x.f_ = v;
    return x;
  }
  static Value of_bool(bool v) {
    Value x(Kind::Bool);
    x.b_ = v;
    return x;
  }
  static Value of_complex(Complex v) {
    Value x(Kind::Complex);
    x.re_ = v.real();
    x.im_ = v.imag();
    return x;
  }
  static Value of_string(std::string v) {
    Value x(Kind::String);
    x.s_ = std::move(v);
    return x;
  }
  static Value of_tensor(Tensor t) {
    Value x(Kind::Tensor);
    x.t_ = std::move(t);
    return x;
  }
  static Value of_element(SetBinding* set, int32_t index, int32_t offset_tag = -1) {
    Value x(Kind::Element);
    x.set_ = set;
    x.i_ = index;
    x.aux_ = offset_tag;
    return x;
  }
  static Value of_set(SetBinding* set) {
    Value x(Kind::Set);
    x.set_ = set;
    return x;
  }
  static Value of_tuple(SetBinding* edges, int32_t edge) {
    Value x(Kind::Tuple);
    x.set_ = edges;
    x.i_ = edge;
    return x;
  }
  static Value of_matrix(std::shared_ptr<runtime::SystemMatrix> m) {
    Value x(Kind::Matrix);
    x.m_ = std::move(m);
    return x;
  }
  static Value of_opaque(std::shared_ptr<SolverHandle> h) {
    Value x(Kind::Opaque);
    x.o_ = std::move(h);
    return x;
  }
  // The zero of a component kind (0, 0.0, false, <0,0>, "").
  static Value zero(ComponentKind k);
  // Zero of a shape: a scalar for the scalar shape, otherwise a zero tensor.
  static Value zero(ComponentKind k, const Shape& shape);
  // Component `i` of a tensor as a scalar value.
  static Value component(const Tensor& t, size_t i);

  Kind kind() const { return kind_; }
  bool empty() const { return kind_ == Kind::Empty; }
  bool is_scalar() const { return kind_ >= Kind::Int && kind_ <= Kind::String; }
  bool is_tensor() const { return kind_ == Kind::Tensor; }

  int32_t as_int() const { return i_; }
  double as_float() const { return f_; }
  bool as_bool() const { return b_; }
  Complex as_complex() const { return {re_, im_}; }
  const std::string& as_string() const { return s_; }
  const Tensor& tensor() const { return t_; }
  Tensor& tensor() { return t_; }

  void set_float(double v) { f_ = v; }

  // Element, Set, Tuple: the set binding; element / edge index; for grid points read as
  // `P[o]` inside a stencil map, the stencil offset's number (-1 otherwise).
  SetBinding* binding() const { return set_; }
  int32_t index() const { return i_; }
  int32_t offset_tag() const { return aux_; }
  // Matrix and Opaque payloads (shared: copies of a value share one matrix, which is
  // never modified after it was produced).
  const std::shared_ptr<runtime::SystemMatrix>& matrix() const { return m_; }
  const std::shared_ptr<SolverHandle>& opaque() const { return o_; }

  // The component kind of a scalar or tensor.
  ComponentKind component_kind() const;
  // The shape of a tensor; the scalar shape for scalars.
  Shape shape() const { return is_tensor() ? t_.shape() : Shape(); }
  // A scalar as a 1-component tensor of `shape` (which must have size 1), or the tensor.
  Tensor to_tensor() const;
  // Writes this scalar into components [offset, offset + count) of `t`.
  void fill_into(Tensor& t, size_t offset, size_t count) const;

  // Exact equality (floats with ==); for tests of the interpreter itself.
  bool operator==(const Value& o) const;

 private:
  explicit Value(Kind k) : kind_(k) {}

  Kind kind_ = Kind::Empty;
  union {
    double f_ = 0.0;
    int32_t i_;
    bool b_;
    double re_;
  };
  double im_ = 0.0;
  int32_t aux_ = -1;
  SetBinding* set_ = nullptr;
  std::string s_;
  Tensor t_;
  std::shared_ptr<runtime::SystemMatrix> m_;
  std::shared_ptr<SolverHandle> o_;
};

}  // namespace simit::interp
