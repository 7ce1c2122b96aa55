// Analysis pass: which assignments of a function write into one of its system-tensor results
// (`f(p(0)) = t`, `K(v(i), v(j)) = B`, `K(v(i), v(j))(a, d) = x`): when the function is
// mapped, these are the writes that assemble the map's results.
#pragma once

#include "frontend/ast.h"

namespace simit::frontend {

// Sets TensorRead::assembles_result on every assignment target that indexes a result of
// its function whose type has a set dimension (directly, or one component of such a
// write's block), to that result's position. Runs once per checked program.
void mark_assembly_writes(ast::Program& program);

}  // namespace simit::frontend
