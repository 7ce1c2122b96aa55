// Zero folding: products whose factor is a zero the tracer knows (a literal, or a product with
// one) fold to zero, and sums with such a zero to the other term, while a trace is built.
//
// The interpreter computes 0 * x as +0, -0 or NaN: -0 when x is negative, NaN when x is not
// finite. The folded trace computes 0, so it needs two things (docs/jit.md, "Zero folding"):
// - every folded factor x is finite: the values multiplied by folded zeros are checked at the
//   end of the statement list that computes them, and when one is not, the call reports an
//   error and the interpreter runs it (so a folded trace is only used where nothing but the
//   results is written);
// - the sign of a zero is all that can differ: a value that may be a zero of the other sign is
//   "loose" (Expr::loose), looseness spreads through arithmetic, and an operation whose result
//   depends on the sign of a zero (a division by it, atan2, pow, a decomposition) stops the
//   folding: the site is traced again without it.
#pragma once

#include <optional>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "jit/loop_ir.h"

namespace simit::jit {

// Thrown while tracing when a loose value reaches an operation that depends on zero signs.
struct FoldConflict {
  std::string reason;
};

class ZeroFold {
 public:
  ZeroFold() { open(); }

  // `a op b` (F64, not both constants) folded when an operand is a known zero or one; null
  // when nothing folds.
  ExprRef binary(BinOp op, const ExprRef& a, const ExprRef& b);
  // Sets a newly built node's looseness from its operands (folded constants included); throws
  // FoldConflict where the sign of a zero would decide the result.
  void propagate(Expr& e) const;
  // Throws FoldConflict when one of these values (a decomposition's arguments) is loose.
  static void require_exact(const std::vector<ExprRef>& values, const std::string& what);

  // A statement list opens; when it closes, the check of its folded factors, if it has any
  // (its error is appended to `errors`).
  void open();
  std::optional<Stmt> close(std::vector<ErrorSite>& errors, const frontend::SourceSpan& at);
  bool used() const { return used_; }

 private:
  ExprRef zero_times(const ExprRef& x);
  static ExprRef plus_zero(const ExprRef& x, const ExprRef& z);
  static ExprRef loosened(const ExprRef& e);

  struct List {
    std::vector<ExprRef> factors;
    std::set<std::pair<int, const void*>> seen;  // locals by slot, other nodes by address
  };
  std::vector<List> lists_;
  bool used_ = false;
};

}  // namespace simit::jit
