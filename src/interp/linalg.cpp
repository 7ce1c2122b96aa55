// System matrices in expressions: products, sums, scaling, component reads, `A \ b` and
// the solver intrinsics of LANGUAGE.md §9.5, all delegated to the runtime's block-CSR code.
#include <span>

#include "interp/interpreter.h"
#include "runtime/fault.h"
#include "runtime/solvers.h"
#include "runtime/system_ops.h"

namespace simit::interp {

namespace ast = frontend::ast;
using runtime::Fault;
using runtime::SystemMatrix;
using frontend::Type;

namespace {

bool is_row(const Type& t) { return t.kind == Type::Kind::Tensor && t.dims.size() == 1 && t.row; }

std::span<const double> floats(const Value& v) {
  if (!v.is_tensor() || v.tensor().kind() != ComponentKind::Float)
    throw Fault("expected a float vector");
  return {v.tensor().floats(), v.tensor().size()};
}

Value matrix_value(SystemMatrix m) { return Value::of_matrix(std::make_shared<SystemMatrix>(std::move(m))); }

double scalar_of(const Value& v) {
  if (v.kind() == Value::Kind::Int) return v.as_int();
  return v.as_float();
}

}  // namespace

// One operand is a system matrix (or the operator is `\`): false when it is not a case for
// the sparse operations, so the dense operators take over.
bool Interpreter::system_binary(const ast::Binary& b, const Value& l, const Value& r, Value& out) {
  using Op = ast::Binary::Op;
  const bool lm = l.kind() == Value::Kind::Matrix, rm = r.kind() == Value::Kind::Matrix;
  auto vector_result = [&](size_t n) {
    Shape s = shape_of(*b.type, b.span);
    if (s.size() != n) throw Fault("the product has " + std::to_string(n) + " components but its type " + s.str());
    return Tensor(ComponentKind::Float, s);
  };
  switch (b.op) {
    case Op::Mul:
      if (lm && rm) { out = matrix_value(runtime::multiply(*l.matrix(), *r.matrix())); return true; }
      if (lm && l.is_scalar() == false && r.is_tensor()) {
        const SystemMatrix& a = *l.matrix();
        auto x = floats(r);
        if (static_cast<int64_t>(x.size()) != a.scalar_cols())
          throw Fault("matrix with " + std::to_string(a.scalar_cols()) + " columns times a vector of " + std::to_string(x.size()) + " components");
        Tensor y = vector_result(a.scalar_rows());
        runtime::multiply(a, x, {y.mutable_floats(), y.size()});
        out = Value::of_tensor(std::move(y));
        return true;
      }
      if (rm && l.is_tensor()) {
        const SystemMatrix& a = *r.matrix();
        auto x = floats(l);
        if (static_cast<int64_t>(x.size()) != a.scalar_rows())
          throw Fault("a vector of " + std::to_string(x.size()) + " components times a matrix with " + std::to_string(a.scalar_rows()) + " rows");
        Tensor y = vector_result(a.scalar_cols());
        runtime::multiply_transposed(a, x, {y.mutable_floats(), y.size()});
        out = Value::of_tensor(std::move(y));
        return true;
      }
      if (lm && r.is_scalar()) { out = matrix_value(runtime::scaled(scalar_of(r), *l.matrix())); return true; }
      if (rm && l.is_scalar()) { out = matrix_value(runtime::scaled(scalar_of(l), *r.matrix())); return true; }
      break;
    case Op::Div:
      if (lm && r.is_scalar()) { out = matrix_value(runtime::scaled(1.0 / scalar_of(r), *l.matrix())); return true; }
      break;
    case Op::Add:
    case Op::Sub:
      if (lm && rm) {
        const SystemMatrix &a = *l.matrix(), &c = *r.matrix();
        if (a.rows() != c.rows() || a.cols() != c.cols() || a.block_size() != c.block_size())
          throw Fault("matrices of different sizes");
        out = matrix_value(runtime::add(a, c, 1.0, b.op == Op::Add ? 1.0 : -1.0, &patterns_));
        return true;
      }
      break;
    case Op::LeftDiv:
      if (lm && r.is_tensor()) {
        const SystemMatrix& a = *l.matrix();
        auto x = floats(r);
        if (a.scalar_rows() != a.scalar_cols()) throw Fault("'\\' needs a square matrix");
        if (static_cast<int64_t>(x.size()) != a.scalar_rows())
          throw Fault("a matrix with " + std::to_string(a.scalar_rows()) + " rows cannot solve a vector of " + std::to_string(x.size()) + " components");
        std::vector<double> sol = runtime::solve(a, x);
        Tensor y = vector_result(sol.size());
        std::copy(sol.begin(), sol.end(), y.mutable_floats());
        out = Value::of_tensor(std::move(y));
        return true;
      }
      break;
    case Op::ElemMul:
    case Op::ElemDiv:
      if (lm || rm) throw Fault("element-wise products of system matrices are not supported");
      break;
    default: break;
  }
  (void)is_row;
  if (lm || rm) throw Fault(std::string("operator '") + ast::binary_op_spelling(b.op) + "' is not defined on these system values");
  return false;
}

// `A(a, b)` (a block, zero outside the pattern) and `A(a, :)` / `A(:, b)`.
Value Interpreter::matrix_read(const ast::TensorRead& r, const Value& mv) {
  const SystemMatrix& m = *mv.matrix();
  if (r.indices.size() != 2) fail(r.span, "system matrices take two indices");
  auto index = [&](int k, int size) { return static_cast<int>(index_value(*r.indices[k], size)); };
  const int br = m.block_rows(), bc = m.block_cols();
  Shape block = br * bc == 1 && !(r.type && r.type->kind == Type::Kind::Tensor && !r.indices[0] == !r.indices[1])
                    ? Shape()
                    : Shape{br, bc};
  if (r.indices[0] && r.indices[1]) {
    const int i = index(0, m.rows()), j = index(1, m.cols());
    if (r.type && r.type->kind == Type::Kind::Scalar) return Value::of_float(m.component(static_cast<int64_t>(i) * br, static_cast<int64_t>(j) * bc));
    Tensor t(ComponentKind::Float, shape_of(*r.type, r.span));
    double* o = t.mutable_floats();
    for (int a = 0; a < br; ++a)
      for (int c = 0; c < bc; ++c) o[a * bc + c] = m.component(static_cast<int64_t>(i) * br + a, static_cast<int64_t>(j) * bc + c);
    return Value::of_tensor(std::move(t));
  }
  (void)block;
  Tensor t(ComponentKind::Float, shape_of(*r.type, r.span));
  double* o = t.mutable_floats();
  if (r.indices[0]) {
    const int i = index(0, m.rows());
    for (int j = 0; j < m.cols(); ++j)
      for (int a = 0; a < br; ++a)
        for (int c = 0; c < bc; ++c)
          o[(static_cast<size_t>(j) * br + a) * bc + c] = m.component(static_cast<int64_t>(i) * br + a, static_cast<int64_t>(j) * bc + c);
  } else {
    const int j = index(1, m.cols());
    for (int i = 0; i < m.rows(); ++i)
      for (int a = 0; a < br; ++a)
        for (int c = 0; c < bc; ++c)
          o[(static_cast<size_t>(i) * br + a) * bc + c] = m.component(static_cast<int64_t>(i) * br + a, static_cast<int64_t>(j) * bc + c);
  }
  return Value::of_tensor(std::move(t));
}

Value Interpreter::solver_intrinsic(const ast::Call& c, std::vector<Value>& args) {
  using frontend::Intrinsic;
  auto matrix = [&](const Value& v) -> const SystemMatrix& {
    if (v.kind() != Value::Kind::Matrix) fail(c.span, "expected a system matrix");
    return *v.matrix();
  };
  auto handle = [&]() -> SolverHandle& {
    if (args[0].kind() != Value::Kind::Opaque || !args[0].opaque()) fail(c.span, "expected a factorisation");
    SolverHandle& h = *args[0].opaque();
    if (std::holds_alternative<std::monostate>(h.factor)) fail(c.span, "the factorisation was already freed");
    return h;
  };
  auto vector_solve = [&](auto& factor) {
    auto b = floats(args[1]);
    if (static_cast<int64_t>(b.size()) != factor.size())
      fail(c.span, "the right-hand side has " + std::to_string(b.size()) + " components but the factorised matrix has " + std::to_string(factor.size()) + " rows");
    Tensor x(ComponentKind::Float, shape_of(*c.type, c.span));
    if (static_cast<int64_t>(x.size()) != factor.size())
      fail(c.span, "the result has " + std::to_string(x.size()) + " components but the factorised matrix has " + std::to_string(factor.size()) + " rows");
    factor.solve(b, {x.mutable_floats(), x.size()});
    return Value::of_tensor(std::move(x));
  };
  try {
    switch (c.intrinsic) {
      case Intrinsic::Lu:
      case Intrinsic::Chol: {
        const SystemMatrix& a = matrix(args[0]);
        if (a.scalar_rows() != a.scalar_cols()) fail(c.span, "cannot factorise a non-square matrix");
        auto h = std::make_shared<SolverHandle>();
        if (c.intrinsic == Intrinsic::Lu) h->factor.emplace<runtime::LuFactor>(a);
        else h->factor.emplace<runtime::CholeskyFactor>(a);
        return Value::of_opaque(std::move(h));
      }
      case Intrinsic::LuSolve:
      case Intrinsic::LltSolve: {
        SolverHandle& h = handle();
        if (auto* lu = std::get_if<runtime::LuFactor>(&h.factor)) return vector_solve(*lu);
        return vector_solve(std::get<runtime::CholeskyFactor>(h.factor));
      }
      case Intrinsic::LuMatSolve:
      case Intrinsic::LltMatSolve: {
        SolverHandle& h = handle();
        const SystemMatrix& b = matrix(args[1]);
        SystemMatrix x;
        if (auto* lu = std::get_if<runtime::LuFactor>(&h.factor)) {
          if (b.scalar_rows() != lu->size()) fail(c.span, "the right-hand side has the wrong number of rows");
          x = lu->solve(b);
        } else {
          auto& ch = std::get<runtime::CholeskyFactor>(h.factor);
          if (b.scalar_rows() != ch.size()) fail(c.span, "the right-hand side has the wrong number of rows");
          x = ch.solve(b);
        }
        return matrix_value(std::move(x));
      }
      case Intrinsic::LuFree:
      case Intrinsic::CholFree:
        handle().factor = std::monostate{};
        return {};
      case Intrinsic::TriangularSolve: {
        const SystemMatrix& a = matrix(args[0]);
        auto b = floats(args[1]);
        if (static_cast<int64_t>(b.size()) != a.scalar_rows())
          fail(c.span, "the right-hand side has " + std::to_string(b.size()) + " components but the matrix has " + std::to_string(a.scalar_rows()) + " rows");
        Tensor x(ComponentKind::Float, shape_of(*c.type, c.span));
        runtime::lower_triangular_solve(a, b, {x.mutable_floats(), x.size()});
        return Value::of_tensor(std::move(x));
      }
      default: break;
    }
  } catch (const Fault& f) {
    fail(c.span, f.what());
  }
  fail(c.span, "not a solver intrinsic");
}

}  // namespace simit::interp
