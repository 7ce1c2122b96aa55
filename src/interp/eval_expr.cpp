// Expression evaluation: one dispatch over the node kinds of the typed AST.
#include <cstring>
#include <new>

#include "interp/frame.h"
#include "interp/interpreter.h"
#include "interp/operators.h"
#include "interp/set_reductions.h"
#include "runtime/fault.h"
#include "runtime/system_ops.h"

namespace simit::interp {

namespace ast = frontend::ast;
using frontend::Type;

namespace {

bool is_row(const Type& t) { return t.kind == Type::Kind::Tensor && t.dims.size() == 1 && t.row; }

// The float fast path of binary operators: both operands are float scalars.
bool float_arith(ast::Binary::Op op, double x, double y, double& out) {
  using Op = ast::Binary::Op;
  switch (op) {
    case Op::Add: out = x + y; return true;
    case Op::Sub: out = x - y; return true;
    case Op::Mul:
    case Op::ElemMul: out = x * y; return true;
    case Op::Div:
    case Op::ElemDiv: out = x / y; return true;
    default: return false;
  }
}

}  // namespace

Value Interpreter::eval_node(const ast::Expr& e) {
  switch (e.kind) {
    case ast::NodeKind::IntLit:
      return Value::of_int(static_cast<int32_t>(static_cast<const ast::IntLit&>(e).value));
    case ast::NodeKind::FloatLit: {
      Value v = Value::of_float(static_cast<const ast::FloatLit&>(e).value);
      if (options_.float32) round_to_float32(v);
      return v;
    }
    case ast::NodeKind::BoolLit: return Value::of_bool(static_cast<const ast::BoolLit&>(e).value);
    case ast::NodeKind::StringLit:
      return Value::of_string(static_cast<const ast::StringLit&>(e).value);
    case ast::NodeKind::ComplexLit: {
      Value v = Value::of_complex(static_cast<const ast::ComplexLit&>(e).value);
      if (options_.float32) round_to_float32(v);
      return v;
    }
    case ast::NodeKind::DenseLit: return eval_dense(static_cast<const ast::DenseLit&>(e));
    case ast::NodeKind::VarRef: return read_var(*static_cast<const ast::VarRef&>(e).var, e);
    case ast::NodeKind::Call: return eval_call(static_cast<const ast::Call&>(e));
    case ast::NodeKind::TensorRead: return eval_tensor_read(static_cast<const ast::TensorRead&>(e));
    case ast::NodeKind::Unary: return eval_unary(static_cast<const ast::Unary&>(e));
    case ast::NodeKind::Binary: return eval_binary(static_cast<const ast::Binary&>(e));
    case ast::NodeKind::Compare: return eval_compare(static_cast<const ast::Compare&>(e));
    case ast::NodeKind::Transpose: {
      Value scratch;
      const Value& x = operand(*static_cast<const ast::Transpose&>(e).operand, scratch);
      if (x.kind() == Value::Kind::Matrix) {
        // Its owned rows would need the other ranks' columns (interp/distribution.h).
        if (options_.distribution) not_distributed(e.span, "the transpose of a system matrix");
        return Value::of_matrix(
            std::make_shared<runtime::SystemMatrix>(runtime::transposed(*x.matrix(), &patterns_)));
      }
      // A vector's transpose has the same components: a temporary is passed on as it is.
      if (&x == &scratch && (!x.is_tensor() || x.tensor().shape().order() == 1)) return scratch;
      return transpose_value(x);
    }
    case ast::NodeKind::TupleRead: return eval_tuple_read(static_cast<const ast::TupleRead&>(e));
    case ast::NodeKind::FieldRead: return eval_field_read(static_cast<const ast::FieldRead&>(e));
    case ast::NodeKind::SetRead: return eval_set_read(static_cast<const ast::SetRead&>(e));
    case ast::NodeKind::Map: {
      std::vector<Value> values = eval_map(static_cast<const ast::Map&>(e));
      if (values.empty()) return {};
      return std::move(values[0]);
    }
    default: break;
  }
  fail(e.span, std::string("cannot evaluate a ") + ast::node_kind_name(e.kind) + " node");
}

Value Interpreter::eval_dense(const ast::DenseLit& d) {
  Shape shape = Shape::of(d.shape);
  const size_t n = d.component == frontend::ScalarKind::Int     ? d.ints.size()
                   : d.component == frontend::ScalarKind::Float ? d.floats.size()
                                                                : d.complexes.size();
  if (n != shape.size())
    fail(d.span, "dense literal has " + std::to_string(n) + " entries for shape " + shape.str());
  switch (d.component) {
    case frontend::ScalarKind::Int: {
      Tensor t(ComponentKind::Int, shape);
      int32_t* out = t.mutable_ints();
      for (size_t i = 0; i < d.ints.size(); ++i) out[i] = static_cast<int32_t>(d.ints[i]);
      return Value::of_tensor(std::move(t));
    }
    case frontend::ScalarKind::Float: {
      Tensor t(ComponentKind::Float, shape);
      std::memcpy(t.mutable_floats(), d.floats.data(), d.floats.size() * sizeof(double));
      Value v = Value::of_tensor(std::move(t));
      if (options_.float32) round_to_float32(v);
      return v;
    }
    case frontend::ScalarKind::Complex: {
      Tensor t(ComponentKind::Complex, shape);
      std::copy(d.complexes.begin(), d.complexes.end(), t.mutable_complexes());
      Value v = Value::of_tensor(std::move(t));
      if (options_.float32) round_to_float32(v);
      return v;
    }
    default: break;
  }
  fail(d.span, "dense literal of an unexpected component type");
}

// `A + s * B`, `A - s * B` (either factor order) of float system matrices, as one sum over the
// union pattern: A + (-1) * (s * B) and A + (-s) * B give the same bits (negation is exact),
// and the product's copy of B is never made. Not under float32 or --check-finite, which look
// at the product's value on its own.
bool Interpreter::scaled_matrix_sum(const ast::Binary& b, Value& out) {
  using Op = ast::Binary::Op;
  if (post_process_ || (b.op != Op::Add && b.op != Op::Sub)) return false;
  const auto* m = b.rhs->as<ast::Binary>();
  if (!m || m->op != Op::Mul || !m->lhs->type || !m->rhs->type) return false;
  const bool scalar_first = m->lhs->type->kind == frontend::Type::Kind::Scalar;
  const ast::Expr& s_expr = scalar_first ? *m->lhs : *m->rhs;
  const ast::Expr& k_expr = scalar_first ? *m->rhs : *m->lhs;
  auto system_matrix = [](const ast::Expr& e) {
    const frontend::Type* t = e.type.get();
    return t && t->kind == frontend::Type::Kind::Tensor && t->dims.size() == 2 &&
           t->dims[0].kind != frontend::IndexSet::Kind::Fixed &&
           t->dims[1].kind != frontend::IndexSet::Kind::Fixed;
  };
  if (s_expr.type->kind != frontend::Type::Kind::Scalar ||
      s_expr.type->scalar != frontend::ScalarKind::Float || !system_matrix(*b.lhs) ||
      !system_matrix(k_expr))
    return false;
  Value as, ss, ks;
  const Value& a = operand(*b.lhs, as);
  if (a.kind() != Value::Kind::Matrix || !a.matrix()->is_float()) return false;
  const Value& s = operand(s_expr, ss);
  const Value& k = operand(k_expr, ks);
  if (k.kind() != Value::Kind::Matrix || !k.matrix()->is_float() || s.kind() != Value::Kind::Float)
    return false;
  const double f = b.op == Op::Add ? s.as_float() : -s.as_float();
  out = Value::of_matrix(std::make_shared<runtime::SystemMatrix>(
      runtime::add(*a.matrix(), *k.matrix(), 1.0, f, &patterns_)));
  return true;
}

Value Interpreter::eval_binary(const ast::Binary& b) {
  if (Value v; scaled_matrix_sum(b, v)) return v;
  // Operands may be read by reference: calls nested in the statement's expression have
  // all run before it is computed (hoisting), so nothing changes a variable meanwhile.
  Value ls, rs;
  const Value& l = operand(*b.lhs, ls);
  const Value& r = operand(*b.rhs, rs);
  double x;
  if (l.kind() == Value::Kind::Float && r.kind() == Value::Kind::Float &&
      float_arith(b.op, l.as_float(), r.as_float(), x)) {
    Value v = Value::of_float(x);
    finish(v, b);
    return v;
  }
  if (l.kind() == Value::Kind::Matrix || r.kind() == Value::Kind::Matrix ||
      b.op == ast::Binary::Op::LeftDiv || is_set_inner_product(b)) {
    Value v;
    if (system_binary(b, l, r, v)) {
      finish(v, b);
      return v;
    }
  }
  Value v = binary_op(b.op, l, is_row(*b.lhs->type), r, is_row(*b.rhs->type), options_.float32);
  finish(v, b);
  return v;
}

Value Interpreter::eval_unary(const ast::Unary& u) {
  Value scratch;
  const Value& x = operand(*u.operand, scratch);
  switch (u.op) {
    case ast::Unary::Op::Neg:
      if (x.kind() == Value::Kind::Matrix)
        return Value::of_matrix(
            std::make_shared<runtime::SystemMatrix>(runtime::scaled(-1.0, *x.matrix())));
      return negate(x);
    case ast::Unary::Op::Plus: return x;
    case ast::Unary::Op::Not: return Value::of_bool(!x.as_bool());
  }
  return x;
}

Value Interpreter::eval_compare(const ast::Compare& c) {
  // Every operand is evaluated once, left to right, and none is skipped (§6.9).
  std::vector<Value> values;
  values.reserve(c.operands.size());
  for (const auto& o : c.operands) values.push_back(eval(*o));
  bool result = true;
  for (size_t i = 0; i < c.ops.size(); ++i)
    result = compare(c.ops[i], values[i], values[i + 1]) && result;
  return Value::of_bool(result);
}

size_t Interpreter::index_value(const ast::Expr& index, int size) {
  Value scratch;
  return checked_index(operand(index, scratch), index, size);
}

size_t Interpreter::checked_index(const Value& v, const ast::Expr& index, int size) {
  int32_t i = 0;
  if (v.kind() == Value::Kind::Element)
    i = v.index();
  else if (v.kind() == Value::Kind::Int)
    i = v.as_int();
  else
    fail(index.span, "index is neither an int nor an element");
  if (i < 0 || i >= size)
    fail(index.span, "index " + std::to_string(i) + " is out of range for a dimension of size " +
                         std::to_string(size));
  return static_cast<size_t>(i);
}

Value Interpreter::eval_tensor_read(const ast::TensorRead& r) {
  Value scratch;
  const Value& base = operand(*r.base, scratch);
  for (const auto& index : r.indices)
    if (!index) return eval_slice(r, base);
  if (base.kind() == Value::Kind::Matrix) return matrix_read(r, base);
  if (!base.is_tensor()) unsupported(r.span, "reads of sets and other non-tensor values");
  const Tensor& t = base.tensor();
  const Shape& s = t.shape();
  if (static_cast<int>(r.indices.size()) != s.order())
    fail(r.span, "expected " + std::to_string(s.order()) + " indices but got " +
                     std::to_string(r.indices.size()));
  size_t outer = 0;
  for (size_t k = 0; k < r.indices.size(); ++k)
    outer =
        outer * s.dim(static_cast<int>(k)) + index_value(*r.indices[k], s.dim(static_cast<int>(k)));
  if (!s.is_blocked()) return Value::component(t, outer);
  Shape block = s.block();
  return Value::of_tensor(t.range(outer * block.size(), block));
}

// `M(i, :)`, `T(k, :, :)`: the kept dimensions in order, blocks kept whole (§6.3.4).
Value Interpreter::eval_slice(const ast::TensorRead& r, const Value& base) {
  if (base.kind() == Value::Kind::Matrix) return matrix_read(r, base);
  if (!base.is_tensor()) unsupported(r.span, "slices of non-tensor values");
  const Tensor& t = base.tensor();
  const Shape& s = t.shape();
  const int order = s.order();
  if (static_cast<int>(r.indices.size()) != order) fail(r.span, "wrong number of indices in slice");
  if (order == 2 && !s.is_blocked() && t.kind() == ComponentKind::Float &&
      (r.indices[0] == nullptr) != (r.indices[1] == nullptr)) {
    // A row `M(i, :)` or a column `M(:, j)` of a matrix: the common case, without the
    // general walk below.
    const int rows = s.dim(0), cols = s.dim(1);
    const bool row = r.indices[0] != nullptr;
    const int n = row ? cols : rows;
    const size_t fixed = row ? index_value(*r.indices[0], rows) : index_value(*r.indices[1], cols);
    Value out = Value::uninit_tensor(ComponentKind::Float, Shape{n});
    double* o = out.tensor().mutable_floats();
    const double* x = t.floats();
    for (int k = 0; k < n; ++k) o[k] = row ? x[fixed * cols + k] : x[k * cols + fixed];
    return out;
  }
  std::vector<int> fixed(order, -1), kept;
  for (int k = 0; k < order; ++k) {
    if (r.indices[k])
      fixed[k] = static_cast<int>(index_value(*r.indices[k], s.dim(k)));
    else
      kept.push_back(s.dim(k));
  }
  const Shape block = s.block();
  const size_t bsize = block.size();
  Tensor out(t.kind(), Shape::blocked(kept, block));
  std::vector<int> idx(order, 0);
  for (int k = 0; k < order; ++k)
    if (fixed[k] >= 0) idx[k] = fixed[k];
  const size_t count = out.shape().outer_count();
  for (size_t n = 0; n < count; ++n) {
    size_t outer = 0;
    for (int k = 0; k < order; ++k) outer = outer * s.dim(k) + idx[k];
    out.write_range(n * bsize, t.range(outer * bsize, block));
    for (int k = order - 1; k >= 0; --k) {  // next position of the kept dimensions
      if (fixed[k] >= 0) continue;
      if (++idx[k] < s.dim(k)) break;
      idx[k] = 0;
    }
  }
  return Value::of_tensor(std::move(out));
}

}  // namespace simit::interp
