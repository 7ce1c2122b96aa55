// The tracer's expression constructors: loop-IR nodes built with constants folded as they
// go, and products and sums by known zeros folded by the trace's ZeroFold (jit/zero_fold.h)
// when it has one.
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include "frontend/source.h"
#include "jit/loop_ir.h"
#include "jit/zero_fold.h"

namespace simit::jit::trace_detail {

inline bool is_const(const ExprRef& e) { return e->kind == ExprKind::Const; }

// Component `index` of scratch array `array` as it is (jit/trace/tracer.h marks the reads of
// a loose array loose).
ExprRef scratch_read(int array, ExprRef index, const frontend::SourceSpan& at);

class Builder {
 public:
  // `fold`: this builder folds products by zeros; every trace has its own folding state.
  explicit Builder(bool fold) {
    if (fold) fold_.emplace();
  }
  Builder(const Builder&) = delete;
  Builder& operator=(const Builder&) = delete;

  // The zero folding of the trace being built, or null when it is traced without it.
  ZeroFold* fold() { return fold_ ? &*fold_ : nullptr; }

  ExprRef unary(UnOp op, Ty ty, ExprRef a, frontend::SourceSpan at = {});
  ExprRef binary(BinOp op, Ty ty, ExprRef a, ExprRef b, frontend::SourceSpan at = {});
  ExprRef compare(CmpOp op, ExprRef a, ExprRef b, frontend::SourceSpan at = {});
  ExprRef math(MathFn f, std::vector<ExprRef> args, frontend::SourceSpan at);
  static ExprRef leaf(ExprKind k, Ty ty, int slot);
  // I32 index arithmetic: a + k (a itself for k = 0), a * k.
  ExprRef i32_add(ExprRef a, int64_t k, const frontend::SourceSpan& at);
  ExprRef i32_mul(ExprRef a, int64_t k, const frontend::SourceSpan& at);

 private:
  // A folded constant that keeps its operands' looseness where it is a zero.
  ExprRef folded(double v, const ExprRef& a, const ExprRef& b = nullptr);
  // A node whose looseness follows from its operands.
  ExprRef made(Expr e);

  std::optional<ZeroFold> fold_;
};

}  // namespace simit::jit::trace_detail
