// The parser of LANGUAGE.md §3: tokens to an AST with a span on every node.
#pragma once

#include <memory>
#include <vector>

#include "frontend/ast.h"
#include "frontend/diagnostics.h"
#include "frontend/token.h"

namespace simit::frontend {

// Parses a whole program. Syntax errors are reported and the parser recovers at
// statement and program-element boundaries; the returned tree holds what parsed.
std::unique_ptr<ast::Program> parse(const std::vector<Token>& tokens, Diagnostics& diags);

}  // namespace simit::frontend
