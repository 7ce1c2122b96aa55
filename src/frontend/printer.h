// Printers of the AST: as re-parsable Simit source, and as readable trees for --dump.
#pragma once

#include <string>

#include "frontend/ast.h"

namespace simit::frontend {

// Simit source text that parses back to an equal tree (print(parse(print(p))) == print(p)).
std::string print_source(const ast::Program& program);
// An indented tree of nodes with spans (`--dump=ast`).
std::string dump_ast(const ast::Program& program);
// The same tree with the checker's annotations: types, resolved names, slots (`--dump=typed`).
std::string dump_typed(const ast::Program& program);

}  // namespace simit::frontend
