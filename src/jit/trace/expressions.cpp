// The tracer's expressions (jit/trace/tracer.h): literals, variables, fields, reads of
// tensors, operators and comparisons, each evaluated into the components of a Sym.
#include <algorithm>

#include "jit/trace/tracer.h"

namespace simit::jit::trace_detail {

int64_t Tracer::const_int(const ast::Expr& e) {
  Sym s = eval(e);
  if (!s.scalar() || !is_const(s.c[0]) || s.ty != Ty::I32)
    give_up(e.span, AbortReason::IndexNotConstant);
  return s.c[0]->i;
}

Sym Tracer::eval(const ast::Expr& e) {
  switch (e.kind) {
    case ast::NodeKind::IntLit:
      return scalar(Ty::I32,
                    iconst(static_cast<int32_t>(static_cast<const ast::IntLit&>(e).value)));
    case ast::NodeKind::FloatLit:
      return round(scalar(Ty::F64, fconst(static_cast<const ast::FloatLit&>(e).value)), e.span);
    case ast::NodeKind::BoolLit:
      return scalar(Ty::Bool, iconst(static_cast<const ast::BoolLit&>(e).value, Ty::Bool));
    case ast::NodeKind::DenseLit: {
      const auto& d = static_cast<const ast::DenseLit&>(e);
      check_components(d.component == ScalarKind::Float ? d.floats.size() : d.ints.size(), e.span);
      std::vector<ExprRef> c;
      if (d.component == ScalarKind::Float) {
        for (double v : d.floats) c.push_back(fconst(v));
        return round(tensor(Ty::F64, d.shape, std::move(c)), e.span);
      }
      if (d.component == ScalarKind::Int) {
        for (long long v : d.ints) c.push_back(iconst(static_cast<int32_t>(v)));
        return tensor(Ty::I32, d.shape, std::move(c));
      }
      give_up(e.span, AbortReason::ComplexLiteral);
    }
    case ast::NodeKind::VarRef: return eval_var(static_cast<const ast::VarRef&>(e));
    case ast::NodeKind::FieldRead: return eval_field(static_cast<const ast::FieldRead&>(e));
    case ast::NodeKind::TupleRead: return eval_tuple(static_cast<const ast::TupleRead&>(e));
    case ast::NodeKind::TensorRead: return eval_read(static_cast<const ast::TensorRead&>(e));
    case ast::NodeKind::Unary: {
      const auto& u = static_cast<const ast::Unary&>(e);
      Sym x = eval(*u.operand);
      if (x.kind != Sym::Kind::Tensor) give_up(e.span, AbortReason::UnaryOfNonTensor);
      if (u.op == ast::Unary::Op::Plus) return x;
      if (u.op == ast::Unary::Op::Not) {
        if (x.ty != Ty::Bool) give_up(e.span, AbortReason::NotOfNonBoolean);
        for (ExprRef& c : x.c) c = build_.unary(UnOp::Not, Ty::Bool, c, e.span);
        return x;
      }
      if (x.ty == Ty::Bool) give_up(e.span, AbortReason::NegationOfBoolean);
      for (ExprRef& c : x.c) c = build_.unary(UnOp::Neg, x.ty, c, e.span);
      return x;
    }
    case ast::NodeKind::Binary: return eval_binary(static_cast<const ast::Binary&>(e));
    case ast::NodeKind::Compare: return eval_compare(static_cast<const ast::Compare&>(e));
    case ast::NodeKind::Transpose: {
      Sym x = eval(*static_cast<const ast::Transpose&>(e).operand);
      if (x.kind != Sym::Kind::Tensor) give_up(e.span, AbortReason::TransposeOfNonTensor);
      if (x.dims.size() <= 1) return x;
      if (x.dims.size() != 2) give_up(e.span, AbortReason::TransposeOfHighOrder);
      if (x.blocked() && !has_logical_form(x)) give_up(e.span, AbortReason::TransposeOfOddBlocks);
      // A blocked matrix swaps its blocks and each block's dimensions (runtime::transpose):
      // the transpose of its unblocked form.
      const Sym l = x.blocked() ? unblocked(x) : x;
      const int m = l.dims[0], n = l.dims[1];
      std::vector<ExprRef> c(l.c.size());
      for (int i = 0; i < m; ++i)
        for (int j = 0; j < n; ++j)
          c[static_cast<size_t>(j) * m + i] = l.c[static_cast<size_t>(i) * n + j];
      Sym t = tensor(x.ty, {n, m}, std::move(c));
      if (!x.blocked()) return t;
      return reblocked(t, {x.dims[1], x.dims[0]}, {x.block[1], x.block[0]});
    }
    case ast::NodeKind::Call: return eval_call(static_cast<const ast::Call&>(e));
    default: break;
  }
  give_up(e.span, AbortReason::ExpressionKind, ast::node_kind_name(e.kind));
}

Sym Tracer::eval_var(const ast::VarRef& r) {
  const ast::Variable& v = *r.var;
  using K = ast::Variable::Kind;
  if (v.kind == K::GlobalConst || v.kind == K::Extern) {
    const interp::Value* g = in_.global(v);
    if (!g || g->empty()) give_up(r.span, AbortReason::GlobalWithoutValue, v.name);
    Sym s = const_of(*g, r.span);
    if (v.kind == K::Extern)  // externs may change between calls: read them at each call
      for (size_t i = 0; i < s.c.size(); ++i)
        s.c[i] = scalar_arg(s.ty, {-1, &v, static_cast<int>(i)});
    return s;
  }
  auto it = frame().vars.find(&v);
  if (it == frame().vars.end()) give_up(r.span, AbortReason::ReadBeforeSet, v.name);
  if (it->second.kind == Sym::Kind::Result) give_up(r.span, AbortReason::ResultRead);
  return it->second;
}

Sym Tracer::eval_field(const ast::FieldRead& f) {
  if (f.of_set) give_up(f.span, AbortReason::SetFieldRead);
  Sym base = eval(*f.base);
  if (base.kind != Sym::Kind::Element) give_up(f.span, AbortReason::FieldOfNonMember);
  const int slot = field_array(base.member, f.field, f.span);
  return load_tensor(slot, base.member, dims_of(*f.type, f.span), f.span);
}

Sym Tracer::eval_tuple(const ast::TupleRead& t) {
  Sym base = eval(*t.base);
  if (base.kind != Sym::Kind::Tuple) give_up(t.span, AbortReason::TupleNotEndpoints);
  const int64_t k = t.index ? const_int(*t.index) : t.member_index;
  if (k < 0 || k >= trace_.arity) give_up(t.span, AbortReason::EndpointOutOfRange);
  Sym s;
  s.kind = Sym::Kind::Element;
  s.member = static_cast<int>(k) + 1;
  return s;
}

Sym Tracer::eval_read(const ast::TensorRead& r) {
  if (r.index_notation) give_up(r.span, AbortReason::IndexNotation);
  Sym base = eval(*r.base);
  if (base.kind == Sym::Kind::Vector) {
    // `f(p)`: the block of a global vector argument at a member.
    if (r.indices.size() != 1 || !r.indices[0]) give_up(r.span, AbortReason::VectorReadNotAtMember);
    Sym at = eval(*r.indices[0]);
    if (at.kind != Sym::Kind::Element) give_up(r.span, AbortReason::VectorReadNotAtMember);
    return load_tensor(base.slot, at.member, dims_of(*r.type, r.span), r.span);
  }
  if (base.kind == Sym::Kind::Matrix) return read_matrix_block(base, r);
  if (base.kind != Sym::Kind::Tensor) give_up(r.span, AbortReason::ReadFromValue);
  if (r.indices.size() != base.dims.size()) give_up(r.span, AbortReason::IndexCount);
  if (base.blocked()) return read_block(base, r);
  // Constant indices and slices: the result keeps the sliced dimensions.
  std::vector<int64_t> fixed(r.indices.size(), -1);
  std::vector<int> out_dims;
  for (size_t k = 0; k < r.indices.size(); ++k) {
    if (r.indices[k])
      fixed[k] = const_int(*r.indices[k]);
    else
      out_dims.push_back(base.dims[k]);
  }
  std::vector<ExprRef> c;
  std::vector<int64_t> idx(fixed.size(), 0);
  for (size_t k = 0; k < fixed.size(); ++k) idx[k] = fixed[k] >= 0 ? fixed[k] : 0;
  while (true) {
    c.push_back(base.c[offset_of(base.dims, idx, r.span)]);
    int k = static_cast<int>(idx.size()) - 1;
    for (; k >= 0; --k) {
      if (fixed[k] >= 0) continue;
      if (++idx[k] < base.dims[k]) break;
      idx[k] = 0;
    }
    if (k < 0) break;
  }
  return tensor(base.ty, std::move(out_dims), std::move(c));
}

// `A(i, j)`: one block of a blocked tensor, as a tensor of the block's shape.
Sym Tracer::read_block(const Sym& base, const ast::TensorRead& r) {
  std::vector<int64_t> idx;
  for (const auto& i : r.indices) {
    if (!i) give_up(r.span, AbortReason::BlockedSlice);
    idx.push_back(const_int(*i));
  }
  const size_t bs = base.block_size(), first = offset_of(base.dims, idx, r.span) * bs;
  return tensor(base.ty, base.block,
                std::vector<ExprRef>(base.c.begin() + static_cast<std::ptrdiff_t>(first),
                                     base.c.begin() + static_cast<std::ptrdiff_t>(first + bs)));
}

// `A(p, q)` of a global matrix argument at two members of the element: the block where the
// controller's position table finds it in A's pattern, zero outside it (as the interpreter).
Sym Tracer::read_matrix_block(const Sym& matrix, const ast::TensorRead& r) {
  if (r.indices.size() != 2 || !r.indices[0] || !r.indices[1])
    give_up(r.span, AbortReason::MatrixReadNotBlock);
  const Sym row = eval(*r.indices[0]), col = eval(*r.indices[1]);
  if (row.kind != Sym::Kind::Element || col.kind != Sym::Kind::Element)
    give_up(r.span, AbortReason::MatrixReadNotAtMembers);
  const int arg = trace_.arrays[matrix.slot].index;
  const std::string name = trace_.arrays[matrix.slot].name + ".positions";
  const int table = array({ArraySlot::Kind::Positions, 0, arg, Ty::I32, false, false, 0, name, {}});
  std::vector<std::pair<int, int>>& reads = trace_.arrays[table].reads;
  const std::pair<int, int> pair{row.member, col.member};
  auto found = std::find(reads.begin(), reads.end(), pair);
  const int comp = static_cast<int>(found - reads.begin());
  if (found == reads.end()) reads.push_back(pair);
  trace_.arrays[table].components = static_cast<int>(reads.size());
  const ExprRef pos = load(table, 0, comp, r.span);
  const int bs = trace_.arrays[matrix.slot].components;
  std::vector<int> locals;
  std::vector<ExprRef> c;
  for (int k = 0; k < bs; ++k) {
    locals.push_back(new_local(Ty::F64, true));
    set_local(locals.back(), fconst(0.0), r.span);
  }
  emit_if(build_.compare(CmpOp::Ge, pos, iconst(0), r.span), r.span, [&] {
    for (int k = 0; k < bs; ++k) {
      Expr e;
      e.kind = ExprKind::Load;
      e.ty = Ty::F64;
      e.slot = matrix.slot;
      e.comp = k;
      e.ops = {pos};
      e.span = r.span;
      set_local(locals[static_cast<size_t>(k)], make(std::move(e)), r.span);
    }
  });
  for (int l : locals) c.push_back(read_local(l));
  Sym out = tensor(Ty::F64, dims_of(*r.type, r.span), std::move(c));
  if (out.size() != static_cast<size_t>(bs)) give_up(r.span, AbortReason::MatrixBlockShape);
  return out;
}

Sym Tracer::elementwise(BinOp op, const Sym& l, const Sym& r, const SourceSpan& at) {
  if (l.ty != r.ty) give_up(at, AbortReason::OperandTypesDiffer);
  if (!l.scalar() && !r.scalar() && !l.same_shape(r)) give_up(at, AbortReason::ElementwiseShapes);
  if (Sym tiled; tiled_elementwise(op, l, r, at, tiled)) return tiled;
  const Sym& shape = l.scalar() ? r : l;
  std::vector<ExprRef> c;
  for (size_t i = 0; i < shape.size(); ++i)
    c.push_back(
        build_.binary(op, l.ty, l.scalar() ? l.c[0] : l.c[i], r.scalar() ? r.c[0] : r.c[i], at));
  return tensor(l.ty, shape.dims, std::move(c), shape.block);
}

Sym Tracer::eval_binary(const ast::Binary& b) {
  using Op = ast::Binary::Op;
  Sym l = eval(*b.lhs), r = eval(*b.rhs);
  if (l.kind != Sym::Kind::Tensor || r.kind != Sym::Kind::Tensor)
    give_up(b.span, AbortReason::SystemTensorOperator);
  // Operands used more than once (products, broadcasts) are computed once.
  l = settle(std::move(l), b.span);
  r = settle(std::move(r), b.span);
  auto is_row = [](const ast::Expr& e) {
    return e.type && e.type->kind == Type::Kind::Tensor && e.type->dims.size() == 1 && e.type->row;
  };
  Sym v;
  switch (b.op) {
    case Op::Add: v = elementwise(BinOp::Add, l, r, b.span); break;
    case Op::Sub: v = elementwise(BinOp::Sub, l, r, b.span); break;
    case Op::ElemMul: v = elementwise(BinOp::Mul, l, r, b.span); break;
    case Op::ElemDiv:
    case Op::Div:
      if (l.ty == Ty::I32)
        check_divisors(r, "integer division by zero", b.span);
      else if (l.ty != Ty::F64)
        give_up(b.span, AbortReason::DivisionOfNonNumbers);
      v = elementwise(BinOp::Div, l, r, b.span);
      break;
    case Op::Mul:
      if (l.scalar() || r.scalar())
        v = elementwise(BinOp::Mul, l, r, b.span);
      else if (l.blocked() || r.blocked())
        v = blocked_product(l, is_row(*b.lhs), r, is_row(*b.rhs), b.span);
      else
        v = product(l, is_row(*b.lhs), r, is_row(*b.rhs), b.span);
      break;
    case Op::And:
    case Op::Or:
    case Op::Xor:
      if (l.ty != Ty::Bool || !l.scalar() || !r.scalar())
        give_up(b.span, AbortReason::LogicOnNonBooleans);
      v = elementwise(b.op == Op::And  ? BinOp::And
                      : b.op == Op::Or ? BinOp::Or
                                       : BinOp::Xor,
                      l, r, b.span);
      break;
    default: give_up(b.span, AbortReason::Operator, ast::binary_op_spelling(b.op));
  }
  return finite(round(std::move(v), b.span), b.span);
}

Sym Tracer::eval_compare(const ast::Compare& c) {
  std::vector<Sym> v;
  for (const auto& o : c.operands) {
    v.push_back(eval(*o));
    if (!v.back().scalar()) give_up(c.span, AbortReason::CompareNonScalars);
  }
  ExprRef result = iconst(1, Ty::Bool);
  for (size_t i = 0; i < c.ops.size(); ++i) {
    if (v[i].ty != v[i + 1].ty) give_up(c.span, AbortReason::CompareTypesDiffer);
    if (v[i].ty == Ty::Bool && c.ops[i] != ast::Compare::Op::Eq && c.ops[i] != ast::Compare::Op::Ne)
      give_up(c.span, AbortReason::OrderingOfBooleans);
    ExprRef a = v[i].c[0], b = v[i + 1].c[0];
    if (v[i].ty == Ty::Bool) {  // compare truth values as integers
      a = make(Expr{ExprKind::Select, Ty::I32, 0, 0, 0, 0.0, 0, {a, iconst(1), iconst(0)}, c.span});
      b = make(Expr{ExprKind::Select, Ty::I32, 0, 0, 0, 0.0, 0, {b, iconst(1), iconst(0)}, c.span});
    }
    ExprRef one = build_.compare(static_cast<CmpOp>(c.ops[i]), a, b, c.span);
    result = i == 0 ? one : build_.binary(BinOp::And, Ty::Bool, one, result, c.span);
  }
  return scalar(Ty::Bool, result);
}

}  // namespace simit::jit::trace_detail
