// What both tracers share: giving up with a located reason, and the leaf constructors of
// loop-IR expressions.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "frontend/source.h"
#include "jit/loop_ir.h"

namespace simit::jit {

// A tracer gives up: the site or loop stays interpreted, with this reason.
struct GiveUp {
  std::string reason;
};
[[noreturn]] inline void give_up(const frontend::SourceSpan& at, const std::string& why) {
  std::string where;
  if (at.valid()) where = " (line " + std::to_string(at.start().line) + ")";
  throw GiveUp{why + where};
}

inline ExprRef make(Expr e) { return std::make_shared<const Expr>(std::move(e)); }

// An operation node as it is (no folding, no looseness: jit/zero_fold.h).
inline ExprRef node(ExprKind k, Ty ty, uint8_t op, std::vector<ExprRef> ops,
                    const frontend::SourceSpan& at = {}) {
  Expr e;
  e.kind = k;
  e.ty = ty;
  e.op = op;
  e.ops = std::move(ops);
  e.span = at;
  return make(std::move(e));
}

// `local = value` at `at`.
inline Stmt set_local(int local, ExprRef value, const frontend::SourceSpan& at) {
  Stmt s;
  s.kind = StmtKind::SetLocal;
  s.slot = local;
  s.value = std::move(value);
  s.span = at;
  return s;
}

inline ExprRef fconst(double v) {
  Expr e;
  e.kind = ExprKind::Const;
  e.ty = Ty::F64;
  e.f = v;
  return make(std::move(e));
}

inline ExprRef iconst(int64_t v, Ty ty = Ty::I32) {
  Expr e;
  e.kind = ExprKind::Const;
  e.ty = ty;
  e.i = v;
  return make(std::move(e));
}

}  // namespace simit::jit
