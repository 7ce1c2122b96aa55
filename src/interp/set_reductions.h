// Which of the interpreter's sums are reductions over a set: those run in the blocked order of
// runtime/blocked_sum.h (docs/arithmetic.md, "Sums"), every other sum left to right. The
// distinction is static (the operands' types), as the JIT's system tracer makes it.
#pragma once

#include "frontend/ast.h"

namespace simit::interp {

// A global vector: a vector whose dimension is a set, or a generic parameter (which a call
// may bind to a set). Null (an untyped expression) is not one.
bool is_set_vector(const frontend::Type* t);
// `u' * v` of two global vectors.
bool is_set_inner_product(const frontend::ast::Binary& b);

}  // namespace simit::interp
