// The parser of LANGUAGE.md §3: tokens to an AST with a span on every node.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "frontend/ast.h"
#include "frontend/diagnostics.h"
#include "frontend/token.h"

namespace simit::frontend {

// Parses a whole program. Syntax errors are reported and the parser recovers at
// statement and program-element boundaries; the returned tree holds what parsed.
std::unique_ptr<ast::Program> parse(const std::vector<Token>& tokens, Diagnostics& diags);

// A name a standalone expression may use (the debugger's `print` and conditions): a
// function, or a value (a tuple value is read as `t(k)` / `t.name`). Locals hide functions.
struct ExprName {
  std::string name;
  bool function = false;
  bool tuple = false;
  bool local = false;
};

// Parses all of `tokens` as one expression, with `names` declared (intrinsics always are).
// Returns null after a syntax error, which is reported.
ast::ExprPtr parse_expression(const std::vector<Token>& tokens, Diagnostics& diags,
                              const std::vector<ExprName>& names);

}  // namespace simit::frontend
