// ZeroFold (jit/zero_fold.h): the folding rules, looseness, and the finiteness checks.
#include "jit/zero_fold.h"

#include <cmath>

#include "jit/ir_build.h"
#include "jit/trace/abort_reasons.h"

namespace simit::jit {

namespace {

bool is_f64_const(const ExprRef& e) { return e->kind == ExprKind::Const && e->ty == Ty::F64; }
bool is_zero(const ExprRef& e) { return is_f64_const(e) && e->f == 0.0; }
bool is_one(const ExprRef& e) { return is_f64_const(e) && e->f == 1.0 && !e->loose; }
// -0.0 from a literal: x + (-0.0) and x - (+0.0) are x exactly, signed zeros included.
bool exact_negative_zero(const ExprRef& e) { return is_zero(e) && !e->loose && std::signbit(e->f); }
bool exact_positive_zero(const ExprRef& e) {
  return is_zero(e) && !e->loose && !std::signbit(e->f);
}

}  // namespace

ExprRef ZeroFold::loosened(const ExprRef& e) {
  if (e->loose || (e->kind == ExprKind::Const && e->f != 0.0)) return e;
  Expr copy = *e;
  copy.loose = true;
  return make(std::move(copy));
}

ExprRef ZeroFold::zero_times(const ExprRef& x) {
  used_ = true;
  List& l = lists_.back();
  const std::pair<int, const void*> key = x->kind == ExprKind::Local
                                              ? std::pair<int, const void*>{x->slot, nullptr}
                                              : std::pair<int, const void*>{-1, x.get()};
  if (l.seen.insert(key).second) l.factors.push_back(x);
  return loosened(fconst(0.0));
}

// x + z for a zero z: x exactly when z is a literal -0.0.
ExprRef ZeroFold::plus_zero(const ExprRef& x, const ExprRef& z) {
  if (exact_negative_zero(z)) return x;
  if (z->loose || x->loose) return loosened(x);
  return nullptr;
}

ExprRef ZeroFold::binary(BinOp op, const ExprRef& a, const ExprRef& b) {
  if (a->ty != Ty::F64) return nullptr;
  switch (op) {
    case BinOp::Mul:
      if (is_zero(a)) return zero_times(b);
      if (is_zero(b)) return zero_times(a);
      if (is_one(a)) return b;  // x * 1 is x, bit for bit
      if (is_one(b)) return a;
      return nullptr;
    // +0.0 + x is x except that -0.0 becomes +0.0: a sum's exact +0.0 start keeps its
    // addition, or every sum would make its value loose; a loose zero, or a loose x, folds.
    case BinOp::Add:
      if (is_zero(b)) return plus_zero(a, b);
      if (is_zero(a)) return plus_zero(b, a);
      return nullptr;
    case BinOp::Sub:
      if (exact_positive_zero(b)) return a;    // x - (+0.0) is x
      if (is_zero(b)) return plus_zero(a, b);  // x - (-0.0) is x + (+0.0)
      if (is_zero(a) && (a->loose || b->loose)) {
        Expr n;
        n.kind = ExprKind::Unary;
        n.ty = Ty::F64;
        n.op = static_cast<uint8_t>(UnOp::Neg);
        n.ops = {b};
        n.loose = true;  // 0 - 0 is +0, -(0) is -0
        return make(std::move(n));
      }
      return nullptr;
    default: return nullptr;
  }
}

void ZeroFold::propagate(Expr& e) const {
  auto any_loose = [&] {
    for (const ExprRef& o : e.ops)
      if (o->loose) return true;
    return false;
  };
  switch (e.kind) {
    case ExprKind::Unary: e.loose = e.ty == Ty::F64 && e.ops[0]->loose; break;
    case ExprKind::Binary:
      if (e.ty != Ty::F64) break;
      if (static_cast<BinOp>(e.op) == BinOp::Div && e.ops[1]->loose)
        throw FoldConflict{abort_message(AbortReason::FoldDivisionByLoose)};
      e.loose = any_loose();
      break;
    case ExprKind::Select: e.loose = e.ty == Ty::F64 && (e.ops[1]->loose || e.ops[2]->loose); break;
    case ExprKind::Math:
      switch (static_cast<MathFn>(e.op)) {
        case MathFn::Atan2:
        case MathFn::Pow:
          if (any_loose()) throw FoldConflict{abort_message(AbortReason::FoldLooseAtan2OrPow)};
          break;
        case MathFn::Abs:  // these give the same value for +0 and -0
        case MathFn::Cos:
        case MathFn::Exp:
        case MathFn::Log:
        case MathFn::Acos: e.loose = false; break;
        default: e.loose = any_loose(); break;
      }
      break;
    default: break;
  }
  if (e.kind == ExprKind::Const && e.ty == Ty::F64 && e.f != 0.0) e.loose = false;
}

void ZeroFold::require_exact(const std::vector<ExprRef>& values, const std::string& what) {
  for (const ExprRef& v : values)
    if (v->loose) throw FoldConflict{abort_message(AbortReason::FoldLooseOperand, what)};
}

void ZeroFold::open() { lists_.emplace_back(); }

// The check: the sum of x - x over the folded factors is 0 when every one is finite and NaN
// otherwise (it cannot overflow, unlike a sum of the factors themselves).
std::optional<Stmt> ZeroFold::close(std::vector<ErrorSite>& errors,
                                    const frontend::SourceSpan& at) {
  List l = std::move(lists_.back());
  lists_.pop_back();
  if (l.factors.empty()) return std::nullopt;
  ExprRef sum;
  for (const ExprRef& x : l.factors) {
    ExprRef d = node(ExprKind::Binary, Ty::F64, static_cast<uint8_t>(BinOp::Sub), {x, x});
    sum = sum ? node(ExprKind::Binary, Ty::F64, static_cast<uint8_t>(BinOp::Add), {sum, d}) : d;
  }
  errors.push_back({at, "a factor of a product folded to zero is not finite"});
  Stmt s;
  s.kind = StmtKind::Check;
  s.value = node(ExprKind::Compare, Ty::Bool, static_cast<uint8_t>(CmpOp::Eq), {sum, fconst(0.0)});
  s.error = static_cast<int>(errors.size() - 1);
  s.span = at;
  return s;
}

}  // namespace simit::jit
