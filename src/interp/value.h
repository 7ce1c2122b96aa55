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

namespace detail {
// Tensor boxes recycled per thread: interpreter temporaries are created and dropped at a
// high rate, and a box from this list costs no allocation. Constant-initialised and trivial,
// so reaching it costs no guard.
struct TensorBoxes {
  static constexpr int kKeep = 512;
  runtime::Tensor* items[kKeep];
  int count;
};
extern constinit thread_local TensorBoxes tensor_boxes;
runtime::Tensor* new_tensor_box();
void delete_tensor_box(runtime::Tensor* t) noexcept;

inline runtime::Tensor* acquire_tensor_box() {
  TensorBoxes& b = tensor_boxes;
  return b.count ? b.items[--b.count] : new_tensor_box();
}
inline void recycle_tensor_box(runtime::Tensor* t) noexcept {
  t->release_shared();
  TensorBoxes& b = tensor_boxes;
  if (b.count < TensorBoxes::kKeep)
    b.items[b.count++] = t;
  else
    delete_tensor_box(t);
}
}  // namespace detail

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
    Tensor,   // a dense tensor of order >= 1, possibly blocked (global vectors too)
    Element,  // one element of a bound set (set + index)
    Set,      // a bound set
    Tuple,    // the endpoint tuple of one edge (edge set + edge index)
    Matrix,   // a system matrix (block CSR over a shared pattern)
    Opaque,   // a solver factorisation
  };

  Value() noexcept = default;
  Value(const Value& o) : kind_(o.kind_), i_(o.i_), aux_(o.aux_), u_(o.u_) {
    if (owns()) copy_from(o);  // out-of-line payloads are copied, the rest is plain data
  }
  Value(Value&& o) noexcept : kind_(o.kind_), i_(o.i_), aux_(o.aux_), u_(o.u_) {
    o.kind_ = Kind::Empty;
  }
  Value& operator=(const Value& o) {
    if (this != &o) {
      Value copy(o);
      *this = std::move(copy);
    }
    return *this;
  }
  Value& operator=(Value&& o) noexcept {
    if (this != &o) {
      drop();
      kind_ = o.kind_;
      i_ = o.i_;
      aux_ = o.aux_;
      u_ = o.u_;
      o.kind_ = Kind::Empty;
    }
    return *this;
  }
  ~Value() { drop(); }

  static Value of_int(int32_t v) {
    Value x(Kind::Int);
    x.i_ = v;
    return x;
  }
  static Value of_float(double v) {
    Value x(Kind::Float);
    x.u_.f = v;
    return x;
  }
  static Value of_bool(bool v) {
    Value x(Kind::Bool);
    x.u_.b = v;
    return x;
  }
  static Value of_complex(Complex v) {
    Value x(Kind::Complex);
    x.u_.c[0] = v.real();
    x.u_.c[1] = v.imag();
    return x;
  }
  static Value of_string(std::string v);
  static Value of_tensor(Tensor t);
  // A tensor of `kind` and `shape` whose components the caller writes next: no zero-fill
  // (every component must be written before the value is read).
  static Value uninit_tensor(ComponentKind kind, const Shape& shape) {
    if (kind == ComponentKind::String) return of_tensor(Tensor(kind, shape));
    Value x(Kind::Tensor);
    x.u_.t = detail::acquire_tensor_box();
    x.u_.t->reset_uninit(kind, shape);
    return x;
  }
  static Value of_element(SetBinding* set, int32_t index, int32_t offset_tag = -1) {
    Value x(Kind::Element);
    x.u_.set = set;
    x.i_ = index;
    x.aux_ = offset_tag;
    return x;
  }
  static Value of_set(SetBinding* set) {
    Value x(Kind::Set);
    x.u_.set = set;
    return x;
  }
  static Value of_tuple(SetBinding* edges, int32_t edge) {
    Value x(Kind::Tuple);
    x.u_.set = edges;
    x.i_ = edge;
    return x;
  }
  static Value of_matrix(std::shared_ptr<runtime::SystemMatrix> m);
  static Value of_opaque(std::shared_ptr<SolverHandle> h);
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
  double as_float() const { return u_.f; }
  bool as_bool() const { return u_.b; }
  Complex as_complex() const { return {u_.c[0], u_.c[1]}; }
  const std::string& as_string() const { return *u_.s; }
  const Tensor& tensor() const { return *u_.t; }
  Tensor& tensor() { return *u_.t; }

  void set_float(double v) { u_.f = v; }

  // Element, Set, Tuple: the set binding; element / edge index; for grid points read as
  // `P[o]` inside a stencil map, the stencil offset's number (-1 otherwise).
  SetBinding* binding() const { return u_.set; }
  int32_t index() const { return i_; }
  int32_t offset_tag() const { return aux_; }
  // Matrix and Opaque payloads (shared: copies of a value share one matrix, which is
  // never modified after it was produced).
  const std::shared_ptr<runtime::SystemMatrix>& matrix() const { return *u_.m; }
  const std::shared_ptr<SolverHandle>& opaque() const { return *u_.o; }

  // The component kind of a scalar or tensor.
  ComponentKind component_kind() const {
    if (kind_ == Kind::Float) return ComponentKind::Float;
    if (kind_ == Kind::Tensor) return u_.t->kind();
    if (kind_ == Kind::Int) return ComponentKind::Int;
    return component_kind_slow();
  }
  // The shape of a tensor; the scalar shape for scalars.
  Shape shape() const { return is_tensor() ? u_.t->shape() : Shape(); }
  // A scalar as a 1-component tensor of `shape` (which must have size 1), or the tensor.
  Tensor to_tensor() const;
  // Writes this scalar into components [offset, offset + count) of `t`.
  void fill_into(Tensor& t, size_t offset, size_t count) const;

  // Exact equality (floats with ==); for tests of the interpreter itself.
  bool operator==(const Value& o) const;

 private:
  explicit Value(Kind k) : kind_(k) {}
  void copy_from(const Value& o);
  ComponentKind component_kind_slow() const;
  // String, Tensor, Matrix and Opaque hold their payload out of line.
  bool owns() const {
    constexpr unsigned kOwning = 1u << unsigned(Kind::String) | 1u << unsigned(Kind::Tensor) |
                                 1u << unsigned(Kind::Matrix) | 1u << unsigned(Kind::Opaque);
    return (kOwning >> unsigned(kind_)) & 1u;
  }
  void release() noexcept;
  void drop() noexcept {
    if (kind_ == Kind::Tensor)
      detail::recycle_tensor_box(u_.t);
    else if (owns())
      release();
  }

  // A few machine words: scalars, elements and set references inline; tensors, strings
  // and shared payloads out of line (tensors in recycled boxes, so temporaries cost no
  // allocation once the interpreter has warmed up).
  Kind kind_ = Kind::Empty;
  int32_t i_ = 0;     // Int; Element and Tuple index
  int32_t aux_ = -1;  // Element: stencil offset tag
  union Payload {
    double f;
    bool b;
    double c[2];
    SetBinding* set;
    Tensor* t;
    std::string* s;
    std::shared_ptr<runtime::SystemMatrix>* m;
    std::shared_ptr<SolverHandle>* o;
  } u_{};
};

}  // namespace simit::interp
