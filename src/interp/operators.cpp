// Arithmetic, comparison and logic on values.
#include "interp/operators.h"

#include <cmath>
#include <limits>

#include "runtime/dense_linalg.h"
#include "runtime/fault.h"
#include "runtime/sum_rounding.h"
#include "runtime/system_ops.h"

namespace simit::interp {

namespace {

using Op = frontend::ast::Binary::Op;
using runtime::Fault;

// ---------------------------------------------------------------------------
// Scalar arithmetic per component type. Integers wrap (LANGUAGE.md §5.1) and divide by
// truncation; a zero divisor is a run-time error (Q6).

enum class Arith { Add, Sub, Mul, Div };

int32_t int_arith(Arith a, int32_t x, int32_t y) {
  uint32_t ux = static_cast<uint32_t>(x), uy = static_cast<uint32_t>(y);
  switch (a) {
    case Arith::Add: return static_cast<int32_t>(ux + uy);
    case Arith::Sub: return static_cast<int32_t>(ux - uy);
    case Arith::Mul: return static_cast<int32_t>(ux * uy);
    case Arith::Div:
      if (y == 0) throw Fault("integer division by zero");
      // The one overflowing quotient wraps like the other operations instead of trapping.
      if (x == std::numeric_limits<int32_t>::min() && y == -1) return x;
      return x / y;
  }
  return 0;
}

template <class T>
T arith(Arith a, T x, T y) {
  switch (a) {
    case Arith::Add: return x + y;
    case Arith::Sub: return x - y;
    case Arith::Mul: return x * y;
    case Arith::Div: return x / y;
  }
  return x;
}

template <class T>
const T* data(const Tensor& t);
template <>
const int32_t* data(const Tensor& t) {
  return t.ints();
}
template <>
const double* data(const Tensor& t) {
  return t.floats();
}
template <>
const Complex* data(const Tensor& t) {
  return t.complexes();
}
template <class T>
T* mutable_data(Tensor& t);
template <>
int32_t* mutable_data(Tensor& t) {
  return t.mutable_ints();
}
template <>
double* mutable_data(Tensor& t) {
  return t.mutable_floats();
}
template <>
Complex* mutable_data(Tensor& t) {
  return t.mutable_complexes();
}
template <class T>
T scalar(const Value& v);
template <>
int32_t scalar(const Value& v) {
  return v.as_int();
}
template <>
double scalar(const Value& v) {
  return v.as_float();
}
template <>
Complex scalar(const Value& v) {
  return v.as_complex();
}
template <class T>
Value make(T v);
template <>
Value make(int32_t v) {
  return Value::of_int(v);
}
template <>
Value make(double v) {
  return Value::of_float(v);
}
template <>
Value make(Complex v) {
  return Value::of_complex(v);
}

template <class T>
T apply(Arith a, T x, T y) {
  if constexpr (std::is_same_v<T, int32_t>)
    return int_arith(a, x, y);
  else
    return arith(a, x, y);
}

// Element-wise `l a r` with scalar broadcast on either side.
template <class T>
Value elementwise(Arith a, const Value& l, const Value& r) {
  if (!l.is_tensor() && !r.is_tensor()) return make<T>(apply<T>(a, scalar<T>(l), scalar<T>(r)));
  const Tensor& shape_src = l.is_tensor() ? l.tensor() : r.tensor();
  if (l.is_tensor() && r.is_tensor() && l.tensor().shape() != r.tensor().shape())
    throw Fault("element-wise operation on tensors of shapes " + l.tensor().shape().str() +
                " and " + r.tensor().shape().str());
  Value result = Value::uninit_tensor(shape_src.kind(), shape_src.shape());
  Tensor& out = result.tensor();
  T* o = mutable_data<T>(out);
  const size_t n = out.size();
  if (l.is_tensor() && r.is_tensor()) {
    const T *x = data<T>(l.tensor()), *y = data<T>(r.tensor());
    for (size_t i = 0; i < n; ++i) o[i] = apply<T>(a, x[i], y[i]);
  } else if (l.is_tensor()) {
    const T* x = data<T>(l.tensor());
    T y = scalar<T>(r);
    for (size_t i = 0; i < n; ++i) o[i] = apply<T>(a, x[i], y);
  } else {
    T x = scalar<T>(l);
    const T* y = data<T>(r.tensor());
    for (size_t i = 0; i < n; ++i) o[i] = apply<T>(a, x, y[i]);
  }
  return result;
}

// Float operands, each a float or a float tensor (same shape when both are): the common case,
// with the operator chosen once outside the loop.
template <class Op>
Value float_elementwise(const Value& l, const Value& r, Op op) {
  const Tensor& t = l.is_tensor() ? l.tensor() : r.tensor();
  Value out = Value::uninit_tensor(ComponentKind::Float, t.shape());
  double* o = out.tensor().mutable_floats();
  const size_t n = t.size();
  if (l.is_tensor() && r.is_tensor()) {
    const double *x = l.tensor().floats(), *y = r.tensor().floats();
    for (size_t i = 0; i < n; ++i) o[i] = op(x[i], y[i]);
  } else if (l.is_tensor()) {
    const double* x = l.tensor().floats();
    const double y = r.as_float();
    for (size_t i = 0; i < n; ++i) o[i] = op(x[i], y);
  } else {
    const double x = l.as_float();
    const double* y = r.tensor().floats();
    for (size_t i = 0; i < n; ++i) o[i] = op(x, y[i]);
  }
  return out;
}

bool float_operands(const Value& l, const Value& r) {
  const bool lt = l.is_tensor(), rt = r.is_tensor();
  if (lt ? l.tensor().kind() != ComponentKind::Float : l.kind() != Value::Kind::Float) return false;
  if (rt ? r.tensor().kind() != ComponentKind::Float : r.kind() != Value::Kind::Float) return false;
  return (lt || rt) && (!lt || !rt || l.tensor().shape() == r.tensor().shape());
}

Value elementwise(Arith a, const Value& l, const Value& r) {
  if (float_operands(l, r)) {
    switch (a) {
      case Arith::Add: return float_elementwise(l, r, [](double x, double y) { return x + y; });
      case Arith::Sub: return float_elementwise(l, r, [](double x, double y) { return x - y; });
      case Arith::Mul: return float_elementwise(l, r, [](double x, double y) { return x * y; });
      case Arith::Div: return float_elementwise(l, r, [](double x, double y) { return x / y; });
    }
  }
  ComponentKind k = l.component_kind();
  if (k != r.component_kind()) throw Fault("operands of different component types");
  switch (k) {
    case ComponentKind::Int: return elementwise<int32_t>(a, l, r);
    case ComponentKind::Float: return elementwise<double>(a, l, r);
    case ComponentKind::Complex: return elementwise<Complex>(a, l, r);
    case ComponentKind::String:
      if (a == Arith::Add && !l.is_tensor() && !r.is_tensor())
        return Value::of_string(l.as_string() + r.as_string());
      break;
    case ComponentKind::Bool: break;
  }
  throw Fault(std::string("arithmetic on ") + runtime::component_name(k) + " values");
}

// ---------------------------------------------------------------------------
// Products `*` of two tensors (§6.5), through the logical unblocked forms.

int level_dim(const Shape& s, int level, int k) { return s.dim(level * s.order() + k); }

// The blocked shape whose level l has dimensions pick(l) (a list of one or two sizes).
template <class F>
Shape levels_shape(int levels, F pick) {
  Shape s;
  for (int l = levels - 1; l >= 0; --l) s = Shape::blocked(pick(l), s);
  return s;
}

// Unblocked float operands of order 1 or 2, straight into the result: the interpreter's
// common case (3x3 matrices and 3-vectors). Sums run over k in ascending order
// (docs/arithmetic.md), each product and addition rounded by R. False when the operands are
// not of that form.
template <class R>
bool float_product(const Tensor& a, bool arow, const Tensor& b, bool brow, Value& out) {
  const Shape &sa = a.shape(), &sb = b.shape();
  if (a.kind() != ComponentKind::Float || b.kind() != ComponentKind::Float || sa.levels() != 1 ||
      sb.levels() != 1)
    return false;
  const int ao = sa.order(), bo = sb.order();
  const double *x = a.floats(), *y = b.floats();
  if (ao == 1 && bo == 1) {
    const int n = sa.dim(0), m = sb.dim(0);
    if (arow && !brow) {
      if (n != m) return false;
      double s = 0.0;
      for (int k = 0; k < n; ++k) s = R::r(s + R::r(x[k] * y[k]));
      out = Value::of_float(s);
      return true;
    }
    if (arow || !brow) return false;
    out = Value::uninit_tensor(ComponentKind::Float, Shape{n, m});
    double* o = out.tensor().mutable_floats();
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < m; ++j) o[i * m + j] = x[i] * y[j];
    return true;
  }
  if (ao == 2 && bo == 1) {
    const int m = sa.dim(0), n = sa.dim(1);
    if (sb.dim(0) != n) return false;
    out = Value::uninit_tensor(ComponentKind::Float, Shape{m});
    double* o = out.tensor().mutable_floats();
    for (int i = 0; i < m; ++i) {
      double s = 0.0;
      for (int k = 0; k < n; ++k) s = R::r(s + R::r(x[i * n + k] * y[k]));
      o[i] = s;
    }
    return true;
  }
  if (ao == 1 && bo == 2) {
    const int n = sb.dim(0), m = sb.dim(1);
    if (sa.dim(0) != n) return false;
    out = Value::uninit_tensor(ComponentKind::Float, Shape{m});
    double* o = out.tensor().mutable_floats();
    for (int j = 0; j < m; ++j) {
      double s = 0.0;
      for (int k = 0; k < n; ++k) s = R::r(s + R::r(x[k] * y[k * m + j]));
      o[j] = s;
    }
    return true;
  }
  if (ao == 2 && bo == 2) {
    const int m = sa.dim(0), n = sa.dim(1), p = sb.dim(1);
    if (sb.dim(0) != n) return false;
    out = Value::uninit_tensor(ComponentKind::Float, Shape{m, p});
    double* o = out.tensor().mutable_floats();
    for (int i = 0; i < m; ++i)
      for (int j = 0; j < p; ++j) {
        double s = 0.0;
        for (int k = 0; k < n; ++k) s = R::r(s + R::r(x[i * n + k] * y[k * p + j]));
        o[i * p + j] = s;
      }
    return true;
  }
  return false;
}

// float32: each product and addition of a sum rounded to binary32 (runtime/sum_rounding.h).
Value product(const Tensor& a, bool arow, const Tensor& b, bool brow, bool float32) {
  if (Value fast; runtime::with_sums(
          float32, [&]<class R>(R) { return float_product<R>(a, arow, b, brow, fast); }))
    return fast;
  const Shape &sa = a.shape(), &sb = b.shape();
  if (sa.levels() != sb.levels() || !sa.uniform() || !sb.uniform())
    throw Fault("product of tensors blocked differently: " + sa.str() + " and " + sb.str());
  int levels = sa.levels();
  int ao = sa.order(), bo = sb.order();
  if (ao >= 3 || bo >= 3) throw Fault("product of tensors of order 3 or more");
  if (ao == 1 && bo == 1 && arow && !brow) {
    if (sa != sb)
      throw Fault("inner product of vectors of shapes " + sa.str() + " and " + sb.str());
    return Value::component(runtime::inner_product(a, b, float32), 0);
  }
  Tensor ua = runtime::unblock(a), ub = runtime::unblock(b);
  Tensor logical;
  Shape result;
  if (ao == 1 && bo == 1) {
    if (arow || !brow) throw Fault("product of two vectors of the same orientation");
    logical = runtime::outer_product(ua, ub);
    result = levels_shape(levels, [&](int l) {
      return std::vector<int>{level_dim(sa, l, 0), level_dim(sb, l, 0)};
    });
  } else if (ao == 2 && bo == 1) {
    logical = runtime::matrix_vector_product(ua, ub, float32);
    result = levels_shape(levels, [&](int l) { return std::vector<int>{level_dim(sa, l, 0)}; });
  } else if (ao == 1 && bo == 2) {
    logical = runtime::vector_matrix_product(ua, ub, float32);
    result = levels_shape(levels, [&](int l) { return std::vector<int>{level_dim(sb, l, 1)}; });
  } else {
    logical = runtime::matrix_product(ua, ub, float32);
    result = levels_shape(levels, [&](int l) {
      return std::vector<int>{level_dim(sa, l, 0), level_dim(sb, l, 1)};
    });
  }
  return Value::of_tensor(levels > 1 ? runtime::reblock(logical, result) : std::move(logical));
}

Value multiply(const Value& l, bool lrow, const Value& r, bool rrow, bool float32) {
  if (!l.is_tensor() || !r.is_tensor()) return elementwise(Arith::Mul, l, r);
  if (l.component_kind() != r.component_kind()) throw Fault("product of different component types");
  return product(l.tensor(), lrow, r.tensor(), rrow, float32);
}

Value solve(const Value& a, const Value& b) {
  if (!a.is_tensor() || !b.is_tensor()) throw Fault("solve needs a matrix and a vector");
  if (a.tensor().shape().is_blocked()) {
    Tensor x = runtime::solve(runtime::unblock(a.tensor()), runtime::unblock(b.tensor()));
    // The solution is blocked like A's columns.
    const Shape& sa = a.tensor().shape();
    Shape result =
        levels_shape(sa.levels(), [&](int l) { return std::vector<int>{level_dim(sa, l, 1)}; });
    return Value::of_tensor(runtime::reblock(x, result));
  }
  return Value::of_tensor(runtime::solve(a.tensor(), b.tensor()));
}

Value logic(Op op, const Value& l, const Value& r) {
  bool x = l.as_bool(), y = r.as_bool();
  switch (op) {
    case Op::And: return Value::of_bool(x && y);
    case Op::Or: return Value::of_bool(x || y);
    default: return Value::of_bool(x != y);
  }
}

template <class T>
Value negate_typed(const Value& v) {
  if (!v.is_tensor()) {
    if constexpr (std::is_same_v<T, int32_t>)
      return make<T>(static_cast<int32_t>(0u - static_cast<uint32_t>(v.as_int())));
    else
      return make<T>(-scalar<T>(v));
  }
  Value result = Value::uninit_tensor(v.tensor().kind(), v.tensor().shape());
  Tensor& out = result.tensor();
  const T* x = data<T>(v.tensor());
  T* o = mutable_data<T>(out);
  const size_t n = out.size();  // read once: the stores could alias the shape
  for (size_t i = 0; i < n; ++i) {
    if constexpr (std::is_same_v<T, int32_t>)
      o[i] = static_cast<int32_t>(0u - static_cast<uint32_t>(x[i]));
    else
      o[i] = -x[i];
  }
  return result;
}

template <class T>
bool ordered(frontend::ast::Compare::Op op, const T& x, const T& y) {
  using C = frontend::ast::Compare::Op;
  switch (op) {
    case C::Eq: return x == y;
    case C::Ne: return x != y;
    case C::Lt: return x < y;
    case C::Gt: return x > y;
    case C::Le: return x <= y;
    case C::Ge: return x >= y;
  }
  return false;
}

}  // namespace

Value binary_op(Op op, const Value& l, bool lrow, const Value& r, bool rrow, bool float32) {
  switch (op) {
    case Op::Add: return elementwise(Arith::Add, l, r);
    case Op::Sub: return elementwise(Arith::Sub, l, r);
    case Op::ElemMul: return elementwise(Arith::Mul, l, r);
    case Op::ElemDiv:
    case Op::Div: return elementwise(Arith::Div, l, r);
    case Op::Mul: return multiply(l, lrow, r, rrow, float32);
    case Op::LeftDiv: return solve(l, r);
    case Op::And:
    case Op::Or:
    case Op::Xor: return logic(op, l, r);
    case Op::Pow: break;
  }
  throw Fault("the '^' operator is not supported");
}

Value negate(const Value& v) {
  switch (v.component_kind()) {
    case ComponentKind::Int: return negate_typed<int32_t>(v);
    case ComponentKind::Float: return negate_typed<double>(v);
    case ComponentKind::Complex: return negate_typed<Complex>(v);
    default: throw Fault("negation of a non-numeric value");
  }
}

Value transpose_value(const Value& v) {
  if (!v.is_tensor() || v.tensor().shape().order() == 1) return v;
  const Tensor& t = v.tensor();
  const Shape& s = t.shape();
  if (t.kind() == ComponentKind::Float && s.levels() == 1 && s.order() == 2) {
    const int rows = s.dim(0), cols = s.dim(1);
    Value out = Value::uninit_tensor(ComponentKind::Float, Shape{cols, rows});
    const double* x = t.floats();
    double* o = out.tensor().mutable_floats();
    for (int i = 0; i < rows; ++i)
      for (int j = 0; j < cols; ++j) o[j * rows + i] = x[i * cols + j];
    return out;
  }
  return Value::of_tensor(runtime::transpose(v.tensor()));
}

bool compare(frontend::ast::Compare::Op op, const Value& l, const Value& r) {
  using C = frontend::ast::Compare::Op;
  switch (l.kind()) {
    case Value::Kind::Int: return ordered(op, l.as_int(), r.as_int());
    // Debugger expressions compare an element with an int by its index (`t == 17`); an
    // element value keeps its index where as_int() reads it.
    case Value::Kind::Element: return ordered(op, l.index(), r.as_int());
    case Value::Kind::Float: return ordered(op, l.as_float(), r.as_float());
    case Value::Kind::Bool: return ordered(op, l.as_bool(), r.as_bool());
    case Value::Kind::String: return ordered(op, l.as_string(), r.as_string());
    case Value::Kind::Complex:
      if (op == C::Eq) return l.as_complex() == r.as_complex();
      if (op == C::Ne) return l.as_complex() != r.as_complex();
      throw Fault("complex numbers cannot be ordered");
    default: throw Fault("comparison of non-scalar values");
  }
}

void round_to_float32(Value& v) {
  switch (v.kind()) {
    case Value::Kind::Float: v.set_float(static_cast<float>(v.as_float())); break;
    case Value::Kind::Complex: {
      Complex c = v.as_complex();
      v = Value::of_complex({static_cast<float>(c.real()), static_cast<float>(c.imag())});
      break;
    }
    case Value::Kind::Tensor: runtime::round_to_float32(v.tensor()); break;
    case Value::Kind::Matrix:
      // An operator's matrix is its own and is rounded in place; a call's may be shared with
      // a variable (or bound by the host): a copy is rounded, only when some value is not
      // binary32.
      if (v.matrix() && v.matrix().use_count() == 1) {
        runtime::round_to_float32(*v.matrix());
      } else if (v.matrix() && !runtime::is_binary32(*v.matrix())) {
        auto m = std::make_shared<runtime::SystemMatrix>(*v.matrix());
        runtime::round_to_float32(*m);
        v = Value::of_matrix(std::move(m));
      }
      break;
    default: break;
  }
}

bool is_finite(const Value& v) {
  switch (v.kind()) {
    case Value::Kind::Float: return std::isfinite(v.as_float());
    case Value::Kind::Complex:
      return std::isfinite(v.as_complex().real()) && std::isfinite(v.as_complex().imag());
    case Value::Kind::Tensor: return runtime::all_finite(v.tensor());
    default: return true;
  }
}

}  // namespace simit::interp
