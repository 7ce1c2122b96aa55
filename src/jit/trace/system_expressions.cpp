// The system tracer's expressions (jit/trace/system_tracer.h): scalar expressions, the
// components of vector expressions, dot products as reduction passes, and the lengths and
// blocks of vectors.
#include "jit/trace/system_tracer.h"

namespace simit::jit::trace_detail {

int SystemTracer::length_of(const ast::Expr& e) {
  if (const auto* r = e.as<ast::VarRef>()) {
    if (auto it = size_of_.find(r->var); it != size_of_.end()) return it->second;
  }
  if (const auto* f = e.as<ast::FieldRead>(); f && f->of_set) return field_size_.at(field_key(*f));
  if (const auto* t = e.as<ast::Transpose>()) return length_of(*t->operand);
  if (const auto* b = e.as<ast::Binary>()) {
    const bool lv = b->lhs->type && is_vector(*b->lhs->type);
    return length_of(lv ? *b->lhs : *b->rhs);
  }
  if (const auto* u = e.as<ast::Unary>()) return length_of(*u->operand);
  give_up(e.span, AbortReason::VectorLength);
}

// Components per element of a vector expression: the runs an inner product sums first.
int SystemTracer::group_of(const ast::Expr& e) {
  if (const auto* f = e.as<ast::FieldRead>(); f && f->of_set) return field_block_.at(field_key(*f));
  if (const auto* r = e.as<ast::VarRef>()) {
    if (auto it = block_of_.find(r->var); it != block_of_.end()) return it->second;
  }
  if (const auto* t = e.as<ast::Transpose>()) return group_of(*t->operand);
  if (const auto* b = e.as<ast::Binary>()) {
    const bool lv = b->lhs->type && is_vector(*b->lhs->type);
    return group_of(lv ? *b->lhs : *b->rhs);
  }
  if (const auto* u = e.as<ast::Unary>()) return group_of(*u->operand);
  give_up(e.span, AbortReason::VectorBlocks);
}

// u' * v, dot(u, v): a reduction pass into a new local, from +0.0 in storage order, each
// element's block summed first.
ExprRef SystemTracer::dot(const ast::Expr& u, const ast::Expr& v, const SourceSpan& at) {
  const int n = length_of(u);
  if (length_of(v) != n) give_up(at, AbortReason::DotLengths);
  const int group = group_of(u);
  if (group_of(v) != group || group < 1) give_up(at, AbortReason::DotBlocks);
  const int t = temp(Ty::F64);
  // The sum starts at +0.0 at the top of every iteration, so that no scalar op stands
  // between the start and its pass: fuse_passes may move the pass up to another loop.
  starts_.push_back(jit::set_local(t, fconst(0.0), at));
  ExprRef a = component(u), b = component(v);
  VectorOp pass;
  pass.kind = VectorOp::Kind::Pass;
  pass.length = n;
  pass.group = group;
  pass.sums = {t};
  pass.body.push_back(jit::set_local(
      t,
      node(ExprKind::Binary, Ty::F64, static_cast<uint8_t>(BinOp::Add),
           {local(t, Ty::F64),
            node(ExprKind::Binary, Ty::F64, static_cast<uint8_t>(BinOp::Mul), {a, b}, at)},
           at),
      at));
  push_op(std::move(pass), at);
  return local(t, Ty::F64);
}

// An operator's, call's or literal's value as the interpreter's float32 mode leaves it.
ExprRef SystemTracer::rounded(ExprRef v, const SourceSpan& at) const {
  if (!float32_ || v->ty != Ty::F64) return v;
  if (v->kind == ExprKind::Const) return fconst(static_cast<double>(static_cast<float>(v->f)));
  return node(ExprKind::Unary, Ty::F64, static_cast<uint8_t>(UnOp::Round32), {std::move(v)}, at);
}

Ty SystemTracer::scalar_ty(const ast::Expr& e) {
  if (!e.type || e.type->kind != Type::Kind::Scalar) give_up(e.span, AbortReason::NotScalar);
  switch (e.type->scalar) {
    case frontend::ScalarKind::Float: return Ty::F64;
    case frontend::ScalarKind::Int: return Ty::I32;
    case frontend::ScalarKind::Bool: return Ty::Bool;
    default: give_up(e.span, AbortReason::ScalarType);
  }
}

ExprRef SystemTracer::scalar(const ast::Expr& e) {
  const Ty ty = scalar_ty(e);
  switch (e.kind) {
    case ast::NodeKind::IntLit:
      return iconst(static_cast<int32_t>(e.as<ast::IntLit>()->value), Ty::I32);
    case ast::NodeKind::FloatLit: return rounded(fconst(e.as<ast::FloatLit>()->value), e.span);
    case ast::NodeKind::BoolLit: return iconst(e.as<ast::BoolLit>()->value, Ty::Bool);
    case ast::NodeKind::VarRef: {
      const ast::Variable& v = *e.as<ast::VarRef>()->var;
      if (v.kind == ast::Variable::Kind::GlobalConst) {
        const Value& g = in_.global(v);
        if (g.kind() == Value::Kind::Float) return fconst(g.as_float());
        if (g.kind() == Value::Kind::Int) return iconst(g.as_int(), Ty::I32);
        if (g.kind() == Value::Kind::Bool) return iconst(g.as_bool(), Ty::Bool);
        give_up(e.span, AbortReason::ConstantKind);
      }
      auto it = scalar_local_.find(&v);
      if (it == scalar_local_.end()) give_up(e.span, AbortReason::VariableNotScalar, v.name);
      return local(it->second, ty);
    }
    case ast::NodeKind::Unary: {
      const auto& u = *e.as<ast::Unary>();
      ExprRef x = scalar(*u.operand);
      if (u.op == ast::Unary::Op::Plus) return x;
      if (u.op == ast::Unary::Op::Not)
        return node(ExprKind::Unary, Ty::Bool, static_cast<uint8_t>(UnOp::Not), {x}, e.span);
      if (ty == Ty::F64)
        return node(ExprKind::Unary, Ty::F64, static_cast<uint8_t>(UnOp::Neg), {x}, e.span);
      give_up(e.span, AbortReason::InLoop, "integer negation");
    }
    case ast::NodeKind::Binary: {
      const auto& b = *e.as<ast::Binary>();
      using Op = ast::Binary::Op;
      if (b.op == Op::Mul && is_row(*b.lhs) && b.rhs->type && is_vector(*b.rhs->type))
        return rounded(dot(*b.lhs, *b.rhs, e.span), e.span);
      ExprRef l = scalar(*b.lhs), r = scalar(*b.rhs);
      if (l->ty != r->ty) give_up(e.span, AbortReason::OperandTypesDiffer);
      BinOp op;
      switch (b.op) {
        case Op::Add: op = BinOp::Add; break;
        case Op::Sub: op = BinOp::Sub; break;
        case Op::Mul:
        case Op::ElemMul: op = BinOp::Mul; break;
        case Op::Div:
        case Op::ElemDiv:
          if (ty == Ty::I32)
            check_divisor(r, "integer division by zero", e.span);
          else if (ty != Ty::F64)
            give_up(e.span, AbortReason::InLoop, "division");
          op = BinOp::Div;
          break;
        case Op::And: op = BinOp::And; break;
        case Op::Or: op = BinOp::Or; break;
        case Op::Xor: op = BinOp::Xor; break;
        default: give_up(e.span, AbortReason::InLoop, "operator");
      }
      return rounded(node(ExprKind::Binary, l->ty, static_cast<uint8_t>(op), {l, r}, e.span),
                     e.span);
    }
    case ast::NodeKind::Compare: {
      const auto& c = *e.as<ast::Compare>();
      std::vector<ExprRef> v;
      for (const auto& o : c.operands) v.push_back(scalar(*o));
      ExprRef result;
      for (size_t i = 0; i < c.ops.size(); ++i) {
        if (v[i]->ty != v[i + 1]->ty || v[i]->ty == Ty::Bool)
          give_up(e.span, AbortReason::InLoop, "comparison");
        ExprRef one = node(ExprKind::Compare, Ty::Bool, static_cast<uint8_t>(c.ops[i]),
                           {v[i], v[i + 1]}, e.span);
        result = result ? node(ExprKind::Binary, Ty::Bool, static_cast<uint8_t>(BinOp::And),
                               {one, result}, e.span)
                        : one;
      }
      return result;
    }
    case ast::NodeKind::Call: {
      const auto& c = *e.as<ast::Call>();
      using frontend::Intrinsic;
      if (c.intrinsic == Intrinsic::Dot)
        return rounded(dot(*c.args[0], *c.args[1], e.span), e.span);
      if (c.intrinsic == Intrinsic::Norm) {
        ExprRef d = dot(*c.args[0], *c.args[0], e.span);
        return rounded(
            node(ExprKind::Math, Ty::F64, static_cast<uint8_t>(MathFn::Sqrt), {d}, e.span), e.span);
      }
      if (c.intrinsic == Intrinsic::Mod) {
        ExprRef x = scalar(*c.args[0]), y = scalar(*c.args[1]);
        if (x->ty != Ty::I32 || y->ty != Ty::I32) give_up(e.span, AbortReason::ModOfNonIntegers);
        check_divisor(y, "mod by zero", e.span);
        return node(ExprKind::Binary, Ty::I32, static_cast<uint8_t>(BinOp::Mod), {x, y}, e.span);
      }
      MathFn f;
      switch (c.intrinsic) {
        case Intrinsic::Sqrt: f = MathFn::Sqrt; break;
        case Intrinsic::Abs: f = MathFn::Abs; break;
        case Intrinsic::Log: f = MathFn::Log; break;
        case Intrinsic::Exp: f = MathFn::Exp; break;
        case Intrinsic::Max: f = MathFn::Max; break;
        case Intrinsic::Min: f = MathFn::Min; break;
        case Intrinsic::Pow: f = MathFn::Pow; break;
        default: give_up(e.span, AbortReason::InLoop, "call");
      }
      std::vector<ExprRef> args;
      for (const auto& a : c.args) {
        args.push_back(scalar(*a));
        if (args.back()->ty != Ty::F64) give_up(e.span, AbortReason::MathOfNonFloat);
      }
      return rounded(
          node(ExprKind::Math, Ty::F64, static_cast<uint8_t>(f), std::move(args), e.span), e.span);
    }
    default: break;
  }
  give_up(e.span, AbortReason::ExpressionKindInLoop, ast::node_kind_name(e.kind));
}

// Component k of a vector expression (ExprKind::Element is k).
ExprRef SystemTracer::component(const ast::Expr& e) {
  if (!e.type || !is_vector(*e.type)) return scalar(e);
  switch (e.kind) {
    case ast::NodeKind::VarRef: {
      auto it = vector_slot_.find(e.as<ast::VarRef>()->var);
      if (it == vector_slot_.end()) give_up(e.span, AbortReason::UnknownVector);
      check_has_value(*e.as<ast::VarRef>()->var, e.span);
      return load(it->second, e.span);
    }
    case ast::NodeKind::FieldRead:
      if (!e.as<ast::FieldRead>()->of_set) break;
      return load(field_slot_.at(field_key(*e.as<ast::FieldRead>())), e.span);
    case ast::NodeKind::Transpose: return component(*e.as<ast::Transpose>()->operand);
    case ast::NodeKind::Unary: {
      const auto& u = *e.as<ast::Unary>();
      ExprRef x = component(*u.operand);
      if (u.op == ast::Unary::Op::Plus) return x;
      if (u.op == ast::Unary::Op::Neg)
        return node(ExprKind::Unary, Ty::F64, static_cast<uint8_t>(UnOp::Neg), {x}, e.span);
      break;
    }
    case ast::NodeKind::Binary: {
      const auto& b = *e.as<ast::Binary>();
      using Op = ast::Binary::Op;
      if (b.op == Op::Mul && b.lhs->type && is_matrix(*b.lhs->type)) return product(b, e.span);
      const bool lv = is_vector(*b.lhs->type), rv = is_vector(*b.rhs->type);
      BinOp op;
      switch (b.op) {
        case Op::Add: op = BinOp::Add; break;
        case Op::Sub: op = BinOp::Sub; break;
        case Op::Mul:
        case Op::ElemMul:
          if (b.op == Op::Mul && lv && rv) give_up(e.span, AbortReason::VectorProductInVector);
          op = BinOp::Mul;
          break;
        case Op::Div:
        case Op::ElemDiv: op = BinOp::Div; break;
        default: give_up(e.span, AbortReason::InLoop, "operator on vectors");
      }
      if ((op == BinOp::Add || op == BinOp::Sub) && !(lv && rv))
        give_up(e.span, AbortReason::VectorPlusScalar);
      if (lv && rv && length_of(*b.lhs) != length_of(*b.rhs))
        give_up(e.span, AbortReason::VectorLengths);
      ExprRef l = component(*b.lhs), r = component(*b.rhs);
      if (l->ty != Ty::F64 || r->ty != Ty::F64) give_up(e.span, AbortReason::VectorOfNonFloats);
      return rounded(node(ExprKind::Binary, Ty::F64, static_cast<uint8_t>(op), {l, r}, e.span),
                     e.span);
    }
    default: break;
  }
  give_up(e.span, AbortReason::VectorExpressionKind, ast::node_kind_name(e.kind));
}

ExprRef SystemTracer::load(int slot, const SourceSpan& at) {
  Expr l;
  l.kind = ExprKind::Load;
  l.ty = Ty::F64;
  l.slot = slot;
  l.ops = {element()};
  l.span = at;
  return make(std::move(l));
}

// The visited component of a pass.
ExprRef SystemTracer::element() {
  Expr k;
  k.kind = ExprKind::Element;
  k.ty = Ty::I32;
  return make(k);
}

}  // namespace simit::jit::trace_detail
