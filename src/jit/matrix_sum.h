// Fused matrix sums: `A = M - s * K` computed in the storage that K's map assembled, where K
// is a local that holds only that map's result and nothing reads it afterwards.
//
// The arithmetic contract fixes each block of the sum as 0.0 + M_b, then + (-s) * K_b, after
// K_b has summed every element's contribution, so the sum cannot move into the assembly's
// element loop; what the fusion saves is a third matrix: the sum overwrites K's blocks in
// place (runtime::add_into), and K's map keeps the diagonal blocks in its specialised pattern
// so that a lumped mass matrix lies within it (docs/jit.md, "Fused matrix sums").
#pragma once

#include <map>
#include <set>

#include "frontend/ast.h"

namespace simit::jit {

struct FusedSum {
  const frontend::ast::Variable* target = nullptr;    // A
  const frontend::ast::Variable* base = nullptr;      // M
  const frontend::ast::Variable* scaled = nullptr;    // K, dead after the statement
  const frontend::ast::Expr* factor = nullptr;        // s
  bool subtract = false;                              // M - s * K (else M + s * K)
  const frontend::ast::Assembly* producer = nullptr;  // the map K = map ... assembles
  int producer_line = 0;
};

struct FusedSums {
  std::map<const frontend::ast::Stmt*, FusedSum> at;  // by the sum's statement
  // The maps whose matrix a fused sum overwrites: their specialised patterns keep the diagonal.
  std::set<const frontend::ast::Assembly*> keep_diagonal;
};

// Every statement of the program's function bodies (outside loops) that can be fused so: an
// assignment `A = M + s * K`, `A = M - s * K` (or `K * s`) of float system matrices, the
// interpreter's one-pass scaled sum (Interpreter::scaled_matrix_sum), where an earlier
// statement of the same block is `K = map ...` and K is read nowhere else in the function.
FusedSums find_fused_sums(const frontend::ast::Program& program);

}  // namespace simit::jit
