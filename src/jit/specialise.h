// Specialised result patterns: a map's matrix result assembled on a pattern of only the
// blocks its element function writes, recorded on a compiled run (docs/jit.md).
//
// A map over tets assembles into the pattern of every pair of a tet's vertices, but the fem
// stiffness writes no block that touches a pinned vertex: on the bunny 55% of the blocks are
// never written. Zeroing them, adding them into M - h^2 K and streaming them through every
// product of the solve costs time and memory for nothing. A compiled run on the full pattern
// marks each block it writes; the controller keeps those, remaps the pattern's per-element
// table onto them (-1 for each block left out, which no write reaches while the inputs that
// decide the writes are unchanged: jit/write_guard.h), and later runs assemble on the kept
// pattern.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "runtime/system_matrix.h"

namespace simit::jit {

struct SpecialisedPattern {
  runtime::PatternPtr full;     // the pattern specialised
  runtime::PatternPtr pattern;  // its blocks that were written
  std::vector<int32_t> table;   // full->assembly().table with positions in `pattern`, or -1
  int64_t kept = 0, total = 0;  // blocks
  double build_ms = 0.0;
};

// The specialisation of `full` (a pattern with an assembly index) to its blocks marked
// written (a byte per block), or nothing when it would keep more than `max_kept` of them.
// With keep_diagonal, the blocks (r, r) of the full pattern are kept written or not (a fused
// sum adds a diagonal matrix into the result's storage: jit/matrix_sum.h).
std::optional<SpecialisedPattern> specialise(const runtime::PatternPtr& full,
                                             const std::vector<uint8_t>& marks, double max_kept,
                                             bool keep_diagonal = false);
// Whether two specialisations keep the same blocks of the same pattern.
bool same_blocks(const SpecialisedPattern& a, const SpecialisedPattern& b);

}  // namespace simit::jit
