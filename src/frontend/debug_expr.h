// Debugger expressions (`print EXPR`, `display EXPR`, `break ... if COND`): Simit
// expressions typed by the real checker in the scope of one point of a function.
//
// Differences from program text: calls of user functions and maps are refused (evaluating
// them would run statements inside a paused run); a comparison accepts an element where an
// int is expected, comparing the element's index (`t == 17`, `v(0) != 3`); and an int may
// index a set dimension, naming the element by its index (`verts.x(3)`).
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "frontend/ast.h"
#include "frontend/source.h"

namespace simit::frontend {

struct DebugExpression {
  std::unique_ptr<SourceFile> source;  // the expression's text; spans point into it
  ast::ExprPtr expr;                   // typed; null when it did not check
  std::string error;                   // the first diagnostic's message otherwise
  bool ok() const { return expr != nullptr; }
};

// The parameters, results, generic parameters and locals of `func` visible at byte `offset`
// of its source: declared by statements that end at or before `offset` in the blocks that
// enclose it (loop variables inside their loops), outermost first; a later entry with the
// same name hides an earlier one. Before a statement, pass its span's begin; after it, its
// end; in a caller, the begin of the call it is making.
std::vector<const ast::Variable*> visible_variables(const ast::FuncDecl& func, uint32_t offset);

// Lexes, parses and checks `text` over the globals of `program`, the intrinsics, and the
// variables of `func` (may be null) visible at `offset`.
DebugExpression check_debug_expression(const ast::Program& program, const ast::FuncDecl* func,
                                       uint32_t offset, const std::string& text);

}  // namespace simit::frontend
