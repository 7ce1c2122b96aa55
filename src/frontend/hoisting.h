// Analysis pass: which user-function calls nested in a statement's expression run before
// the expression is computed (LANGUAGE.md §6.10).
#pragma once

#include "frontend/ast.h"

namespace simit::frontend {

// Fills Expr::hoisted of every root expression (a statement's value, target, condition,
// bound or argument) that has user-function calls nested below its top: those calls,
// innermost first, left to right. A call that is the whole expression is not listed (it
// runs last anyway). Runs once per checked program.
void plan_hoisting(ast::Program& program);

}  // namespace simit::frontend
