// System matrices in expressions: products, sums, scaling, component reads, assembly
// writes, `A \ b` and the solver intrinsics of LANGUAGE.md §9.5, all delegated to the
// runtime's block-CSR code. Matrices hold float, int, bool or complex components.
#include <algorithm>
#include <span>
#include <type_traits>

#include "interp/interpreter.h"
#include "interp/set_reductions.h"
#include "interp/system_values.h"
#include "runtime/dense_linalg.h"
#include "runtime/fault.h"
#include "runtime/solvers.h"
#include "runtime/sum_rounding.h"
#include "runtime/system_ops.h"

namespace simit::interp {

namespace ast = frontend::ast;
using frontend::Type;
using runtime::Fault;
using runtime::SystemMatrix;

namespace {

std::span<const double> floats(const Value& v) {
  if (!v.is_tensor() || v.tensor().kind() != ComponentKind::Float)
    throw Fault(std::string("expected a vector of float components, not ") +
                (v.is_tensor() ? runtime::component_name(v.tensor().kind()) : "a scalar"));
  return {v.tensor().floats(), v.tensor().size()};
}

Value matrix_value(SystemMatrix m) {
  return Value::of_matrix(std::make_shared<SystemMatrix>(std::move(m)));
}

Complex scalar_of(const Value& v) {
  if (v.kind() == Value::Kind::Int) return v.as_int();
  if (v.kind() == Value::Kind::Float) return v.as_float();
  if (v.kind() == Value::Kind::Complex) return v.as_complex();
  throw Fault("a system matrix can only be scaled by a number");
}

// A dense tensor's components as a span of the type T that stores them.
template <class T>
std::span<const T> components(const Tensor& t) {
  if constexpr (std::is_same_v<T, double>) return {t.floats(), t.size()};
  if constexpr (std::is_same_v<T, Complex>) return {t.complexes(), t.size()};
  if constexpr (std::is_same_v<T, int32_t>) return {t.ints(), t.size()};
}
template <class T>
std::span<T> mutable_components(Tensor& t) {
  if constexpr (std::is_same_v<T, double>) return {t.mutable_floats(), t.size()};
  if constexpr (std::is_same_v<T, Complex>) return {t.mutable_complexes(), t.size()};
  if constexpr (std::is_same_v<T, int32_t>) return {t.mutable_ints(), t.size()};
}

template <class T>
void matrix_vector_as(const SystemMatrix& a, const Tensor& x, bool transposed, Tensor& y,
                      bool float32) {
  if constexpr (std::is_same_v<T, int32_t>) {
    if (transposed)
      runtime::multiply_transposed(a, components<T>(x), mutable_components<T>(y));
    else
      runtime::multiply(a, components<T>(x), mutable_components<T>(y));
  } else if (transposed) {
    runtime::multiply_transposed(a, components<T>(x), mutable_components<T>(y), float32);
  } else {
    runtime::multiply(a, components<T>(x), mutable_components<T>(y), float32);
  }
}

// y = A x (or Aᵀ x) in the component kind of A, which the vector must share (§6.5); float32:
// each row's sum in binary32 steps.
Tensor matrix_vector(const SystemMatrix& a, const Tensor& x, bool transposed, const Shape& result,
                     bool float32) {
  if (a.kind() == ComponentKind::Bool) throw Fault("a matrix of bool components has no products");
  if (x.kind() != a.kind())
    throw Fault(std::string("cannot multiply a matrix of ") + runtime::component_name(a.kind()) +
                " components and a vector of " + runtime::component_name(x.kind()) + " ones");
  const int64_t in = transposed ? a.scalar_rows() : a.scalar_cols();
  const int64_t out = transposed ? a.scalar_cols() : a.scalar_rows();
  if (static_cast<int64_t>(x.size()) != in)
    throw Fault("a matrix with " + std::to_string(in) + (transposed ? " rows" : " columns") +
                " cannot multiply a vector of " + std::to_string(x.size()) + " components");
  if (static_cast<int64_t>(result.size()) != out)
    throw Fault("the product has " + std::to_string(out) + " components but its type " +
                result.str());
  Tensor y(a.kind(), result);
  switch (a.kind()) {
    case ComponentKind::Float: matrix_vector_as<double>(a, x, transposed, y, float32); break;
    case ComponentKind::Complex: matrix_vector_as<Complex>(a, x, transposed, y, float32); break;
    default: matrix_vector_as<int32_t>(a, x, transposed, y, false); break;
  }
  return y;
}

// Component (i, j) of the logical matrix as a scalar of m's kind.
Value matrix_component(const SystemMatrix& m, int64_t i, int64_t j) {
  switch (m.kind()) {
    case ComponentKind::Float: return Value::of_float(m.component_as<double>(i, j));
    case ComponentKind::Complex: return Value::of_complex(m.component_as<Complex>(i, j));
    case ComponentKind::Int: return Value::of_int(m.component_as<int32_t>(i, j));
    default: return Value::of_bool(m.component_as<int32_t>(i, j) != 0);
  }
}

// For each component of a logical block, row-major, where a tensor of shape `block` holds
// it: the identity, except for blocks of blocks, which tensors store level by level.
std::vector<int32_t> block_layout(const SystemMatrix& m, const Shape& block) {
  if (block.levels() > 1) return runtime::nested_positions(block);
  std::vector<int32_t> at(static_cast<size_t>(m.block_size()));
  for (size_t k = 0; k < at.size(); ++k) at[k] = static_cast<int32_t>(k);
  return at;
}

// Writes block (i, j) of m into `out` from component `base` on, laid out by `at`.
void read_block(const SystemMatrix& m, int i, int j, const std::vector<int32_t>& at, Tensor& out,
                size_t base) {
  const int br = m.block_rows(), bc = m.block_cols();
  if (at.size() != static_cast<size_t>(m.block_size()) || base + at.size() > out.size())
    throw Fault("a block of " + std::to_string(m.block_size()) + " components read into " +
                out.shape().str());
  for (int a = 0; a < br; ++a)
    for (int c = 0; c < bc; ++c) {
      const Value v =
          matrix_component(m, static_cast<int64_t>(i) * br + a, static_cast<int64_t>(j) * bc + c);
      v.fill_into(out, base + at[static_cast<size_t>(a) * bc + c], 1);
    }
}

// A scalar value as the component type T.
template <class T>
T scalar_as(const Value& v) {
  if constexpr (std::is_same_v<T, double>) return v.as_float();
  if constexpr (std::is_same_v<T, Complex>) return v.as_complex();
  if constexpr (std::is_same_v<T, int32_t>) return v.as_int();
}

// Stores or adds v into count components; int sums wrap (through uint32), and under float32
// each addition rounds to binary32 (docs/arithmetic.md).
template <class T>
void write_part(T* dst, size_t count, const Value& v, bool accumulate, bool float32) {
  using Acc = std::conditional_t<std::is_same_v<T, int32_t>, uint32_t, T>;
  auto put = [&](size_t i, T x) {
    T sum = accumulate ? static_cast<T>(static_cast<Acc>(dst[i]) + static_cast<Acc>(x)) : x;
    if constexpr (!std::is_same_v<T, int32_t>)
      if (accumulate && float32) sum = runtime::Binary32Sums::r(sum);
    dst[i] = sum;
  };
  if (!v.is_tensor()) {
    const T x = scalar_as<T>(v);
    for (size_t i = 0; i < count; ++i) put(i, x);
    return;
  }
  const Tensor& t = v.tensor();
  if (t.size() != count)
    throw Fault("cannot store a value of shape " + t.shape().str() + " into a block of " +
                std::to_string(count) + " components");
  const T* src = components<T>(t).data();
  for (size_t i = 0; i < count; ++i) put(i, src[i]);
}

// Adds every stored block into `out` (repeated stencil entries sum, ints wrap).
template <class T, class Out>
void add_blocks(const SystemMatrix& m, Out* out) {
  const runtime::MatrixPattern& p = m.pattern();
  const int br = m.block_rows(), bc = m.block_cols();
  const int64_t cols = m.scalar_cols();
  const T* v = m.data<T>();
  for (int r = 0; r < m.rows(); ++r)
    for (int32_t k = p.row_ptr()[r]; k < p.row_ptr()[r + 1]; ++k)
      for (int i = 0; i < br; ++i)
        for (int j = 0; j < bc; ++j) {
          Out& dst = out[(static_cast<int64_t>(r) * br + i) * cols +
                         static_cast<int64_t>(p.col_idx()[k]) * bc + j];
          const T x = v[(static_cast<size_t>(k) * br + i) * bc + j];
          if constexpr (std::is_same_v<Out, bool>)
            dst = dst || x != T(0);
          else if constexpr (std::is_same_v<T, int32_t>)
            dst = static_cast<int32_t>(static_cast<uint32_t>(dst) + static_cast<uint32_t>(x));
          else
            dst += x;
        }
}

}  // namespace

Tensor dense_of(const SystemMatrix& m) {
  if (m.scalar_rows() * m.scalar_cols() > 100'000'000)
    throw Fault("a " + std::to_string(m.scalar_rows()) + " x " + std::to_string(m.scalar_cols()) +
                " system matrix is too large to show densely");
  Tensor t(m.kind(), Shape{static_cast<int>(m.scalar_rows()), static_cast<int>(m.scalar_cols())});
  switch (m.kind()) {
    case ComponentKind::Float: add_blocks<double>(m, t.mutable_floats()); break;
    case ComponentKind::Int: add_blocks<int32_t>(m, t.mutable_ints()); break;
    case ComponentKind::Complex: add_blocks<Complex>(m, t.mutable_complexes()); break;
    default: add_blocks<int32_t>(m, t.mutable_bools()); break;
  }
  return t;
}

void store_tensor_part(SystemMatrix& m, size_t offset, const Tensor& src, size_t from,
                       size_t count) {
  if (src.kind() != m.kind())
    throw Fault(std::string("cannot store ") + runtime::component_name(src.kind()) +
                " components into a matrix of " + runtime::component_name(m.kind()) + " ones");
  if (offset + count > m.value_count() || from + count > src.size())
    throw Fault("a block copy past the end of a matrix or tensor");
  switch (m.kind()) {
    case ComponentKind::Float: std::copy_n(src.floats() + from, count, m.values() + offset); break;
    case ComponentKind::Int: std::copy_n(src.ints() + from, count, m.ints() + offset); break;
    case ComponentKind::Complex:
      std::copy_n(src.complexes() + from, count, m.complexes() + offset);
      break;
    default: std::copy_n(src.bools() + from, count, m.ints() + offset); break;
  }
}

void write_matrix_part(SystemMatrix& m, size_t offset, size_t count, const Value& v,
                       bool accumulate, bool float32) {
  const ComponentKind k = v.component_kind();
  if (k != m.kind())
    throw Fault(std::string("cannot store ") + runtime::component_name(k) +
                " components into a matrix of " + runtime::component_name(m.kind()) + " ones");
  if (offset + count > m.value_count()) throw Fault("a write past the end of a matrix block");
  switch (k) {
    case ComponentKind::Float:
      return write_part(m.values() + offset, count, v, accumulate, float32);
    case ComponentKind::Int: return write_part(m.ints() + offset, count, v, accumulate, false);
    case ComponentKind::Complex:
      return write_part(m.complexes() + offset, count, v, accumulate, float32);
    default: break;
  }
  // Bool blocks store only: there is no sum of booleans to reduce with.
  if (accumulate) throw Fault("'reduce +' cannot assemble a matrix of bool components");
  if (v.is_tensor() && v.tensor().size() != count)
    throw Fault("cannot store a value of shape " + v.tensor().shape().str() + " into a block of " +
                std::to_string(count) + " components");
  int32_t* dst = m.ints() + offset;
  for (size_t i = 0; i < count; ++i) dst[i] = v.is_tensor() ? v.tensor().bools()[i] : v.as_bool();
}

bool is_set_vector(const Type* t) {
  return t && t->kind == Type::Kind::Tensor && t->dims.size() == 1 &&
         t->dims[0].kind != frontend::IndexSet::Kind::Fixed;
}

bool is_set_inner_product(const ast::Binary& b) {
  return b.op == ast::Binary::Op::Mul && is_set_vector(b.lhs->type.get()) && b.lhs->type->row &&
         is_set_vector(b.rhs->type.get()) && !b.rhs->type->row;
}

namespace {

Value inner_product_over_set(const Value& l, const Value& r) {
  if (!l.is_tensor() || !r.is_tensor()) throw Fault("an inner product needs two vectors");
  if (l.tensor().kind() != r.tensor().kind()) throw Fault("product of different component types");
  if (l.tensor().shape() != r.tensor().shape())
    throw Fault("inner product of vectors of shapes " + l.tensor().shape().str() + " and " +
                r.tensor().shape().str());
  return Value::component(runtime::set_inner_product(l.tensor(), r.tensor()), 0);
}

}  // namespace

// One operand is a system matrix, the operator is `\`, or the product is an inner product of
// global vectors: false when it is not a case for the sparse operations, so the dense
// operators take over.
bool Interpreter::system_binary(const ast::Binary& b, const Value& l, const Value& r, Value& out) {
  using Op = ast::Binary::Op;
  const bool lm = l.kind() == Value::Kind::Matrix, rm = r.kind() == Value::Kind::Matrix;
  // A distributed run holds complete rows of its owned elements only (interp/distribution.h):
  // what needs other rows is refused until it is built.
  const bool distributed = options_.distribution && (lm || rm);
  switch (b.op) {
    case Op::Mul:
      if (!lm && !rm && is_set_inner_product(b)) {
        if (const runtime::Set* set = distributed_set(b.lhs->type.get()))
          out = distributed_inner_product(l, r, *set, false, b.span);
        else
          out = inner_product_over_set(l, r);
        return true;
      }
      if (lm && rm) {
        if (distributed) not_distributed(b.span, "a product of two system matrices");
        out = matrix_value(runtime::multiply(*l.matrix(), *r.matrix(), options_.float32));
        return true;
      }
      if (lm && r.is_tensor()) {
        out = Value::of_tensor(matrix_vector(*l.matrix(), r.tensor(), false,
                                             shape_of(*b.type, b.span), options_.float32));
        // The ghost rows' sums miss the other ranks' elements: their owners' sums replace them.
        if (distributed) refresh_ghosts(out, b.type.get());
        return true;
      }
      if (rm && l.is_tensor()) {
        if (distributed) not_distributed(b.span, "a vector times a system matrix (x' * A)");
        out = Value::of_tensor(matrix_vector(*r.matrix(), l.tensor(), true,
                                             shape_of(*b.type, b.span), options_.float32));
        return true;
      }
      if (lm && r.is_scalar()) {
        out = matrix_value(runtime::scaled(scalar_of(r), *l.matrix()));
        return true;
      }
      if (rm && l.is_scalar()) {
        out = matrix_value(runtime::scaled(scalar_of(l), *r.matrix()));
        return true;
      }
      break;
    case Op::Div:
      if (lm && r.is_scalar()) {
        out = matrix_value(runtime::divided(*l.matrix(), scalar_of(r)));
        return true;
      }
      break;
    case Op::Add:
    case Op::Sub:
      if (lm && rm) {
        out = matrix_value(
            runtime::add(*l.matrix(), *r.matrix(), 1.0, b.op == Op::Add ? 1.0 : -1.0, &patterns_));
        return true;
      }
      if (lm || rm)
        throw Fault(
            "a scalar cannot be added to a system matrix (its components outside the "
            "sparsity pattern would stop being zero)");
      break;
    case Op::LeftDiv:
      if (lm && r.is_tensor()) {
        if (distributed) {
          out = distributed_solve(b, *l.matrix(), r);
          return true;
        }
        const SystemMatrix& a = *l.matrix();
        if (!a.is_float() || r.tensor().kind() != ComponentKind::Float)
          throw Fault(std::string("the solve operator '\\' needs float components, not ") +
                      runtime::component_name(a.is_float() ? r.tensor().kind() : a.kind()));
        auto x = floats(r);
        if (a.scalar_rows() != a.scalar_cols()) throw Fault("'\\' needs a square matrix");
        if (static_cast<int64_t>(x.size()) != a.scalar_rows())
          throw Fault("a matrix with " + std::to_string(a.scalar_rows()) +
                      " rows cannot solve a vector of " + std::to_string(x.size()) + " components");
        std::vector<double> sol = runtime::solve(a, x);
        Tensor y(ComponentKind::Float, shape_of(*b.type, b.span));
        if (y.size() != sol.size())
          throw Fault("the solution has " + std::to_string(sol.size()) +
                      " components but its type " + y.shape().str());
        std::copy(sol.begin(), sol.end(), y.mutable_floats());
        out = Value::of_tensor(std::move(y));
        return true;
      }
      break;
    case Op::ElemMul:
      if (lm && rm) {
        out = matrix_value(runtime::multiply_elementwise(*l.matrix(), *r.matrix(), &patterns_));
        return true;
      }
      if (lm && r.is_scalar()) {
        out = matrix_value(runtime::scaled(scalar_of(r), *l.matrix()));
        return true;
      }
      if (rm && l.is_scalar()) {
        out = matrix_value(runtime::scaled(scalar_of(l), *r.matrix()));
        return true;
      }
      break;
    case Op::ElemDiv:
      if (lm && r.is_scalar()) {
        out = matrix_value(runtime::divided(*l.matrix(), scalar_of(r)));
        return true;
      }
      if (lm || rm)
        throw Fault(
            "a system matrix can only be divided element-wise by a scalar (its "
            "components outside the sparsity pattern are zero)");
      break;
    default: break;
  }
  if (lm || rm)
    throw Fault(std::string("operator '") + ast::binary_op_spelling(b.op) +
                "' is not defined on these system values");
  return false;
}

// `A(a, b)` (a block, zero outside the pattern) and `A(a, :)` / `A(:, b)`.
Value Interpreter::matrix_read(const ast::TensorRead& r, const Value& mv) {
  const SystemMatrix& m = *mv.matrix();
  if (r.indices.size() != 2) fail(r.span, "system matrices take two indices");
  auto index = [&](int k, int size) { return static_cast<int>(index_value(*r.indices[k], size)); };
  const int br = m.block_rows(), bc = m.block_cols();
  if (r.indices[0] && r.indices[1]) {
    const int i = index(0, m.rows()), j = index(1, m.cols());
    if (r.type && r.type->kind == Type::Kind::Scalar)
      return matrix_component(m, static_cast<int64_t>(i) * br, static_cast<int64_t>(j) * bc);
    Tensor t(m.kind(), shape_of(*r.type, r.span));
    read_block(m, i, j, block_layout(m, t.shape()), t, 0);
    return Value::of_tensor(std::move(t));
  }
  // A row or column: one block per element of the other set.
  Tensor t(m.kind(), shape_of(*r.type, r.span));
  const Shape block = t.shape().block();
  const std::vector<int32_t> at = block_layout(m, block);
  if (r.indices[0]) {
    const int i = index(0, m.rows());
    for (int j = 0; j < m.cols(); ++j) read_block(m, i, j, at, t, j * at.size());
  } else {
    const int j = index(1, m.cols());
    for (int i = 0; i < m.rows(); ++i) read_block(m, i, j, at, t, i * at.size());
  }
  return Value::of_tensor(std::move(t));
}

Value Interpreter::solver_intrinsic(const ast::Call& c, std::vector<Value>& args) {
  using frontend::Intrinsic;
  if (options_.distribution)
    not_distributed(c.span, "the factorisation or solve '" + c.callee + "'");
  auto matrix = [&](const Value& v) -> const SystemMatrix& {
    if (v.kind() != Value::Kind::Matrix) fail(c.span, "expected a system matrix");
    return *v.matrix();
  };
  auto handle = [&]() -> SolverHandle& {
    if (args[0].kind() != Value::Kind::Opaque || !args[0].opaque())
      fail(c.span, "expected a factorisation");
    SolverHandle& h = *args[0].opaque();
    if (std::holds_alternative<std::monostate>(h.factor))
      fail(c.span, "the factorisation was already freed");
    return h;
  };
  auto vector_solve = [&](auto& factor) {
    auto b = floats(args[1]);
    if (static_cast<int64_t>(b.size()) != factor.size())
      fail(c.span, "the right-hand side has " + std::to_string(b.size()) +
                       " components but the factorised matrix has " +
                       std::to_string(factor.size()) + " rows");
    Tensor x(ComponentKind::Float, shape_of(*c.type, c.span));
    if (static_cast<int64_t>(x.size()) != factor.size())
      fail(c.span, "the result has " + std::to_string(x.size()) +
                       " components but the factorised matrix has " +
                       std::to_string(factor.size()) + " rows");
    factor.solve(b, {x.mutable_floats(), x.size()});
    return Value::of_tensor(std::move(x));
  };
  try {
    switch (c.intrinsic) {
      case Intrinsic::Lu:
      case Intrinsic::Chol: {
        const SystemMatrix& a = matrix(args[0]);
        if (a.scalar_rows() != a.scalar_cols())
          fail(c.span, "cannot factorise a non-square matrix");
        auto h = std::make_shared<SolverHandle>();
        if (c.intrinsic == Intrinsic::Lu)
          h->factor.emplace<runtime::LuFactor>(a);
        else
          h->factor.emplace<runtime::CholeskyFactor>(a);
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
        if (!b.is_float())
          fail(c.span, std::string("the right-hand side must have float components, not ") +
                           runtime::component_name(b.kind()));
        SystemMatrix x;
        if (auto* lu = std::get_if<runtime::LuFactor>(&h.factor)) {
          if (b.scalar_rows() != lu->size())
            fail(c.span, "the right-hand side has the wrong number of rows");
          x = lu->solve(b);
        } else {
          auto& ch = std::get<runtime::CholeskyFactor>(h.factor);
          if (b.scalar_rows() != ch.size())
            fail(c.span, "the right-hand side has the wrong number of rows");
          x = ch.solve(b);
        }
        return matrix_value(std::move(x));
      }
      case Intrinsic::LuFree:
      case Intrinsic::CholFree: handle().factor = std::monostate{}; return {};
      case Intrinsic::TriangularSolve: {
        const SystemMatrix& a = matrix(args[0]);
        auto b = floats(args[1]);
        if (static_cast<int64_t>(b.size()) != a.scalar_rows())
          fail(c.span, "the right-hand side has " + std::to_string(b.size()) +
                           " components but the matrix has " + std::to_string(a.scalar_rows()) +
                           " rows");
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
