// What a Program shares with the Functions compiled from it: the checked source and tree.
#pragma once

#include <memory>
#include <vector>

#include "frontend/ast.h"
#include "frontend/frontend.h"

namespace simit::api {

struct LoadedProgram {
  std::unique_ptr<frontend::Compilation> compilation;
  const frontend::ast::Program& program() const { return *compilation->program; }
};

// The externs `func` needs bound: those it (or anything it calls or maps) names, the sets
// that types it uses are indexed by, and the endpoint sets of those sets; in declaration order.
std::vector<const frontend::ast::Variable*> externs_used_by(const frontend::ast::Program& program,
                                                            const frontend::ast::FuncDecl& func);

}  // namespace simit::api
