// Calls of the intrinsic functions of LANGUAGE.md §9.1-9.4 and of the decompositions of
// docs/intrinsics.md (the sparse solvers of §9.5 need system matrices and come with sets).
#include <chrono>
#include <cmath>
#include <limits>

#include "interp/frame.h"
#include "interp/interpreter.h"
#include "interp/set_reductions.h"
#include "runtime/blocked_sum.h"
#include "runtime/decompositions.h"
#include "runtime/dense_linalg.h"
#include "runtime/fault.h"
#include "runtime/math/math_functions.h"

namespace simit::interp {

namespace ast = frontend::ast;
using frontend::Intrinsic;

namespace {

// The transcendental functions are the project's own (docs/math.md): the same bits in every
// executor and on every target.
double float_math(Intrinsic id, double x) {
  switch (id) {
    case Intrinsic::Sin: return math::sin(x);
    case Intrinsic::Cos: return math::cos(x);
    case Intrinsic::Tan: return math::tan(x);
    case Intrinsic::Asin: return math::asin(x);
    case Intrinsic::Acos: return math::acos(x);
    case Intrinsic::Sqrt: return std::sqrt(x);
    case Intrinsic::Cbrt: return math::cbrt(x);
    case Intrinsic::Log: return math::log(x);
    case Intrinsic::Exp: return math::exp(x);
    case Intrinsic::Abs: return std::fabs(x);
    default: return x;
  }
}

double float_math2(Intrinsic id, double x, double y) {
  switch (id) {
    case Intrinsic::Atan2: return math::atan2(x, y);
    case Intrinsic::Pow: return math::pow(x, y);
    case Intrinsic::Max: return std::fmax(x, y);
    case Intrinsic::Min: return std::fmin(x, y);
    default: return x;
  }
}

double microseconds_now() {
  using namespace std::chrono;
  return static_cast<double>(
             duration_cast<nanoseconds>(steady_clock::now().time_since_epoch()).count()) /
         1000.0;
}

// Components of a float tensor (all of them, for blocked vectors too).
const double* floats_of(const Value& v, size_t& n) {
  n = v.tensor().size();
  return v.tensor().floats();
}

// Both sum each element's block first, as every inner product does, and then the element
// sums left to right, or for global vectors (`over_set`) in the blocked order
// (docs/arithmetic.md). float32: a dense vector's sum in binary32 steps; a reduction over a
// set keeps binary64 and is rounded once by the caller.
double sum_of_products(const double* x, const double* y, size_t n, size_t group, bool over_set,
                       bool float32) {
  return over_set ? runtime::blocked_dot(x, y, n, group)
                  : runtime::grouped_dot(x, y, n, group, float32);
}

Value norm(const Value& v, bool over_set, bool float32) {
  size_t n;
  const double* x = floats_of(v, n);
  const size_t group = runtime::inner_product_group(v.tensor().shape());
  return Value::of_float(std::sqrt(sum_of_products(x, x, n, group, over_set, float32)));
}

Value dot(const Value& a, const Value& b, bool over_set, bool float32) {
  size_t n, m;
  const double* x = floats_of(a, n);
  const double* y = floats_of(b, m);
  if (n != m) throw runtime::Fault("dot of vectors of different lengths");
  const size_t group = runtime::inner_product_group(a.tensor().shape());
  if (runtime::inner_product_group(b.tensor().shape()) != group)
    throw runtime::Fault("dot of vectors blocked differently");
  return Value::of_float(sum_of_products(x, y, n, group, over_set, float32));
}

Value cross(const Value& a, const Value& b) {
  const double* x = a.tensor().floats();
  const double* y = b.tensor().floats();
  Value out = Value::uninit_tensor(ComponentKind::Float, Shape{3});
  double* o = out.tensor().mutable_floats();
  o[0] = x[1] * y[2] - x[2] * y[1];
  o[1] = x[2] * y[0] - x[0] * y[2];
  o[2] = x[0] * y[1] - x[1] * y[0];
  return out;
}

}  // namespace

Value Interpreter::call_intrinsic(const ast::Call& c) {
  const Intrinsic id = c.intrinsic;
  // Arguments by reference where they are variables: nothing here modifies them.
  Value s0, s1;
  const Value& a0 = c.args.empty() ? s0 : operand(*c.args[0], s0);
  const Value& a1 = c.args.size() > 1 ? operand(*c.args[1], s1) : s1;
  switch (id) {
    case Intrinsic::Mod: {
      int32_t x = a0.as_int(), y = a1.as_int();
      if (y == 0) fail(c.span, "mod by zero");
      if (y == -1) return Value::of_int(0);  // also INT_MIN mod -1, which would trap in C
      return Value::of_int(x % y);
    }
    case Intrinsic::Sin:
    case Intrinsic::Cos:
    case Intrinsic::Tan:
    case Intrinsic::Asin:
    case Intrinsic::Acos:
    case Intrinsic::Sqrt:
    case Intrinsic::Cbrt:
    case Intrinsic::Log:
    case Intrinsic::Exp:
    case Intrinsic::Abs: return Value::of_float(float_math(id, a0.as_float()));
    case Intrinsic::Atan2:
    case Intrinsic::Pow:
    case Intrinsic::Max:
    case Intrinsic::Min: return Value::of_float(float_math2(id, a0.as_float(), a1.as_float()));
    case Intrinsic::Clock: return Value::of_float(microseconds_now());
    case Intrinsic::StoreTime: return Value::of_float(0.0);
    case Intrinsic::Det:
    case Intrinsic::Det2:
    case Intrinsic::Det4: return Value::of_float(runtime::determinant(a0.tensor()));
    case Intrinsic::Inv:
    case Intrinsic::Inv2:
    case Intrinsic::Inv4: return Value::of_tensor(runtime::inverse(a0.tensor()));
    case Intrinsic::Cross: return cross(a0, a1);
    case Intrinsic::Norm:
      if (const runtime::Set* set = distributed_set(c.args[0]->type.get()))
        return distributed_inner_product(a0, a0, *set, true, c.span);
      return norm(a0, is_set_vector(c.args[0]->type.get()), options_.float32);
    case Intrinsic::Dot: {
      const runtime::Set* set = distributed_set(c.args[0]->type.get());
      if (!set) set = distributed_set(c.args[1]->type.get());
      if (set) return distributed_inner_product(a0, a1, *set, false, c.span);
      return dot(a0, a1,
                 is_set_vector(c.args[0]->type.get()) || is_set_vector(c.args[1]->type.get()),
                 options_.float32);
    }
    case Intrinsic::CreateComplex: return Value::of_complex({a0.as_float(), a1.as_float()});
    case Intrinsic::ComplexGetReal: return Value::of_float(a0.as_complex().real());
    case Intrinsic::ComplexGetImag: return Value::of_float(a0.as_complex().imag());
    case Intrinsic::ComplexNorm: return Value::of_float(std::abs(a0.as_complex()));
    case Intrinsic::ComplexConj: return Value::of_complex(std::conj(a0.as_complex()));
    case Intrinsic::TriangularSolve:
      if (a0.kind() == Value::Kind::Matrix) {
        std::vector<Value> args{a0, a1};
        return solver_intrinsic(c, args);
      }
      if (a0.is_tensor() && a1.is_tensor())
        return Value::of_tensor(runtime::lower_triangular_solve(a0.tensor(), a1.tensor()));
      break;
    case Intrinsic::Lu:
    case Intrinsic::LuSolve:
    case Intrinsic::LuMatSolve:
    case Intrinsic::LuFree:
    case Intrinsic::Chol:
    case Intrinsic::LltSolve:
    case Intrinsic::LltMatSolve:
    case Intrinsic::CholFree: {
      std::vector<Value> args{a0, a1};
      return solver_intrinsic(c, args);
    }
    case Intrinsic::ProjectSpd:
    case Intrinsic::ProjectSpdAbs: return call_project_spd(c, a0);
    case Intrinsic::Svd:
    case Intrinsic::Eig:
    case Intrinsic::Polar: fail(c.span, "function '" + c.callee + "' returns several values");
    case Intrinsic::None: break;
  }
  unsupported(c.span, "sparse solver intrinsics");
}

double Interpreter::symmetry_tolerance() const { return options_.float32 ? 1e-4 : 1e-8; }

Value Interpreter::call_project_spd(const ast::Call& c, const Value& a) {
  const auto mode = c.intrinsic == Intrinsic::ProjectSpd ? runtime::SpdProjection::Clamp
                                                         : runtime::SpdProjection::Absolute;
  try {
    return Value::of_tensor(runtime::project_spd(a.tensor(), mode, symmetry_tolerance()));
  } catch (const runtime::Fault& f) {
    fail(c.span, f.what());
  }
}

std::vector<Value> Interpreter::call_decomposition(const ast::Call& c) {
  Value scratch;
  const Tensor& a = operand(*c.args[0], scratch).tensor();
  std::vector<Value> out;
  try {
    switch (c.intrinsic) {
      case Intrinsic::Svd: {
        runtime::RotationSvd d = runtime::rotation_svd(a);
        out = {Value::of_tensor(std::move(d.u)), Value::of_tensor(std::move(d.s)),
               Value::of_tensor(std::move(d.v))};
        break;
      }
      case Intrinsic::Eig: {
        runtime::SymmetricEig d = runtime::symmetric_eig(a, symmetry_tolerance());
        out = {Value::of_tensor(std::move(d.w)), Value::of_tensor(std::move(d.q))};
        break;
      }
      case Intrinsic::Polar: {
        runtime::PolarDecomposition d = runtime::polar_decomposition(a);
        out = {Value::of_tensor(std::move(d.r)), Value::of_tensor(std::move(d.s))};
        break;
      }
      default: fail(c.span, "function '" + c.callee + "' returns one value");
    }
  } catch (const runtime::Fault& f) {
    fail(c.span, f.what());
  }
  for (Value& v : out) finish(v, c);
  return out;
}

}  // namespace simit::interp
