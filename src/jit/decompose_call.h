// The runtime's decompositions (svd, eig, polar, project_spd), callable from compiled code:
// a kernel stores its argument's components, calls this, and reads the results back, so the
// bits are the interpreter's (it calls the same functions).
#pragma once

#include <cstdint>

namespace simit::jit {

// fn: a jit::Decomposition; in: the n x n matrix, row-major; out: the results one after
// another (decomposition_results). Returns 0, or 1 when the matrix is not symmetric enough
// for eig or project_spd (the interpreter reports that error).
extern "C" int32_t simit_jit_decompose(int32_t fn, int32_t n, int32_t float32, const double* in,
                                       double* out);

}  // namespace simit::jit
