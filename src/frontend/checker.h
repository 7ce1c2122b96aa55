// The type checker of LANGUAGE.md §4-10: resolves names, assigns frame slots, infers
// element sources, checks generics and annotates every expression with its type.
#pragma once

#include "frontend/ast.h"
#include "frontend/diagnostics.h"

namespace simit::frontend {

// Checks and annotates `program` in place. After it returns without diagnostics the
// tree is complete (every VarRef resolved, every Expr typed) and is treated as immutable.
void check(ast::Program& program, Diagnostics& diags);

}  // namespace simit::frontend
