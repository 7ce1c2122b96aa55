// Analysis pass: the loops an index-notation assignment (LANGUAGE.md §7.2) runs, and where
// each index variable's range comes from.
#pragma once

#include "frontend/ast.h"

namespace simit::frontend {

// Fills Assign::loop_free, loop_reduction and ranging_reads of every index-notation
// assignment: the free variables (each once, in order), the reduction variables that are
// not also free, and the outermost index-notation reads of the target and then of the
// value, whose dimensions (known only when the statement runs) give each variable's range.
// Runs once per checked program.
void plan_index_ranges(ast::Program& program);

}  // namespace simit::frontend
