// Analysis pass: which statements compute on system tensors (vectors and matrices indexed by
// sets), the statements a compiled executor may take over as a whole (interp/assembly_plan.h).
#pragma once

#include "frontend/ast.h"

namespace simit::frontend {

// Sets Stmt::system_level on every assignment, declaration or expression statement of a
// function body that reads or writes a value whose type has a set dimension (a system
// vector or matrix, `A * p`, `x = x + alpha * p`), and on every while / do-while loop whose
// body has such a statement and no call of a user function or map (a CG iteration); and
// Stmt::scalar_level on every assignment or declaration of scalars that names no system
// tensor and calls no user function (`var k = 0;`, `rr = bb;`), which may join a run of
// system-level statements. Runs once per checked program.
void mark_system_statements(ast::Program& program);

}  // namespace simit::frontend
