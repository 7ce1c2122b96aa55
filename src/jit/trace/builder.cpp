// The tracer's expression constructors (jit/trace/builder.h).
#include "jit/trace/builder.h"

#include "jit/ir_build.h"
#include "jit/trace/abort_reasons.h"

namespace simit::jit::trace_detail {

using frontend::SourceSpan;

ExprRef Builder::folded(double v, const ExprRef& a, const ExprRef& b) {
  ExprRef c = fconst(v);
  if (fold_ && v == 0.0 && (a->loose || (b && b->loose))) {
    Expr e = *c;
    e.loose = true;
    return make(std::move(e));
  }
  return c;
}

ExprRef Builder::made(Expr e) {
  if (fold_) fold_->propagate(e);
  return make(std::move(e));
}

ExprRef Builder::unary(UnOp op, Ty ty, ExprRef a, SourceSpan at) {
  if (is_const(a)) {
    switch (op) {
      case UnOp::Neg:
        if (ty == Ty::F64) return folded(-a->f, a);
        return iconst(static_cast<int32_t>(0u - static_cast<uint32_t>(a->i)));
      case UnOp::Not: return iconst(!a->i, Ty::Bool);
      case UnOp::Round32: return folded(static_cast<double>(static_cast<float>(a->f)), a);
      case UnOp::ToF64: return fconst(static_cast<double>(a->i));
    }
  }
  // A binary32 value rounds to itself: a sum's last rounding (--float32) and its operator's.
  if (op == UnOp::Round32 && a->kind == ExprKind::Unary && static_cast<UnOp>(a->op) == op) return a;
  Expr e;
  e.kind = ExprKind::Unary;
  e.ty = ty;
  e.op = static_cast<uint8_t>(op);
  e.ops = {std::move(a)};
  e.span = at;
  return made(std::move(e));
}

ExprRef Builder::binary(BinOp op, Ty ty, ExprRef a, ExprRef b, SourceSpan at) {
  if (is_const(a) && is_const(b)) {
    if (ty == Ty::F64) {
      if (fold_ && op == BinOp::Div && b->loose)
        throw FoldConflict{abort_message(AbortReason::FoldDivisionByLoose)};
      switch (op) {
        case BinOp::Add: return folded(a->f + b->f, a, b);
        case BinOp::Sub: return folded(a->f - b->f, a, b);
        case BinOp::Mul: return folded(a->f * b->f, a, b);
        case BinOp::Div: return folded(a->f / b->f, a, b);
        default: break;
      }
    } else if (ty == Ty::I32) {
      const uint32_t x = static_cast<uint32_t>(a->i), y = static_cast<uint32_t>(b->i);
      switch (op) {
        case BinOp::Add: return iconst(static_cast<int32_t>(x + y));
        case BinOp::Sub: return iconst(static_cast<int32_t>(x - y));
        case BinOp::Mul: return iconst(static_cast<int32_t>(x * y));
        // A zero divisor is not folded: its check fails when the code runs.
        case BinOp::Div:
          if (b->i == -1) return iconst(static_cast<int32_t>(0u - x));
          if (b->i != 0) return iconst(a->i / b->i);
          break;
        case BinOp::Mod:
          if (b->i == -1) return iconst(0);
          if (b->i != 0) return iconst(a->i % b->i);
          break;
        default: break;
      }
    } else {
      switch (op) {
        case BinOp::And: return iconst(a->i && b->i, Ty::Bool);
        case BinOp::Or: return iconst(a->i || b->i, Ty::Bool);
        case BinOp::Xor: return iconst((a->i != 0) != (b->i != 0), Ty::Bool);
        default: break;
      }
    }
  }
  if (fold_ && ty == Ty::F64 && !(is_const(a) && is_const(b)))
    if (ExprRef f = fold_->binary(op, a, b)) return f;
  Expr e;
  e.kind = ExprKind::Binary;
  e.ty = ty;
  e.op = static_cast<uint8_t>(op);
  e.ops = {std::move(a), std::move(b)};
  e.span = at;
  return made(std::move(e));
}

ExprRef Builder::compare(CmpOp op, ExprRef a, ExprRef b, SourceSpan at) {
  if (is_const(a) && is_const(b)) {
    const bool f = a->ty == Ty::F64;
    const double x = f ? a->f : static_cast<double>(a->i), y = f ? b->f : static_cast<double>(b->i);
    bool r = false;
    switch (op) {
      case CmpOp::Eq: r = x == y; break;
      case CmpOp::Ne: r = x != y; break;
      case CmpOp::Lt: r = x < y; break;
      case CmpOp::Gt: r = x > y; break;
      case CmpOp::Le: r = x <= y; break;
      case CmpOp::Ge: r = x >= y; break;
    }
    return iconst(r, Ty::Bool);
  }
  Expr e;
  e.kind = ExprKind::Compare;
  e.ty = Ty::Bool;
  e.op = static_cast<uint8_t>(op);
  e.ops = {std::move(a), std::move(b)};
  e.span = at;
  return make(std::move(e));
}

ExprRef Builder::math(MathFn f, std::vector<ExprRef> args, SourceSpan at) {
  Expr e;
  e.kind = ExprKind::Math;
  e.ty = Ty::F64;
  e.op = static_cast<uint8_t>(f);
  e.ops = std::move(args);
  e.span = at;
  return made(std::move(e));
}

ExprRef Builder::leaf(ExprKind k, Ty ty, int slot) {
  Expr e;
  e.kind = k;
  e.ty = ty;
  e.slot = slot;
  return make(std::move(e));
}

ExprRef scratch_read(int array, ExprRef index, const SourceSpan& at) {
  Expr e;
  e.kind = ExprKind::Scratch;
  e.ty = Ty::F64;
  e.slot = array;
  e.ops = {std::move(index)};
  e.span = at;
  return make(std::move(e));
}

ExprRef Builder::i32_add(ExprRef a, int64_t k, const SourceSpan& at) {
  return k == 0 ? a : binary(BinOp::Add, Ty::I32, std::move(a), iconst(k), at);
}
ExprRef Builder::i32_mul(ExprRef a, int64_t k, const SourceSpan& at) {
  return binary(BinOp::Mul, Ty::I32, std::move(a), iconst(k), at);
}

}  // namespace simit::jit::trace_detail
