// Specialised result patterns: a map's matrix result assembled on a pattern of only the
// blocks its element function writes, measured on a compiled run (docs/jit.md).
//
// A map over tets assembles into the pattern of every pair of a tet's vertices, but the fem
// stiffness writes no block that touches a pinned vertex: on the bunny 55% of the blocks stay
// zero. Zeroing them, adding them into M - h^2 K and streaming them through every product of
// the solve costs time and memory for nothing. After a compiled run on the full pattern, the
// controller keeps the blocks that hold a non-zero component (or a NaN) and remaps the
// pattern's per-element table onto them, -1 for each block left out. Later runs assemble on
// the kept pattern; a write whose table entry is -1 (the conditions changed: a vertex
// unpinned) stops the kernel, and the site runs again on the full pattern, for good.
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

// The specialisation of `m` (assembled on a pattern with an assembly index) to its blocks that
// are not all zero, or nothing when it would keep more than `max_kept` of them.
std::optional<SpecialisedPattern> specialise(const runtime::SystemMatrix& m, double max_kept);

}  // namespace simit::jit
