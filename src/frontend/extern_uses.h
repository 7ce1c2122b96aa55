// Analysis pass: the externs each function needs bound before it can run.
#pragma once

#include "frontend/ast.h"

namespace simit::frontend {

// Fills FuncDecl::extern_uses of every function: the externs it (or anything it calls or
// maps) names, the sets that the types it uses are indexed by, and the endpoint sets of
// those sets; in declaration order. Runs once per checked program.
void plan_extern_uses(ast::Program& program);

}  // namespace simit::frontend
