// The defer-assembly pass: a map that adds into shared blocks (`reduce +` into a global vector
// or matrix) is rewritten so that chunks of its elements can run apart and still give the
// blocks the interpreter's bits (docs/arithmetic.md: a block sums its contributions in element
// order).
//
// Every assembly write then finds its block through a per-element table (a matrix's pattern
// table already; a vector gets one per member written), and a table entry -1 - k sends the
// write to the result's deferred block k instead. For a split of the elements into chunks,
// the entries of a block's first chunk point at the block, so that chunk adds in place in
// element order; the later chunks' contributions land in deferred blocks, one per (element,
// block), and are added to their blocks in element order once every chunk has run
// (jit/deferred_plan.h). Run with plain tables, the kernel computes what it did before.
#pragma once

#include <string>

#include "jit/loop_ir.h"

namespace simit::jit {

// Rewrites `t` (Trace::deferred set) and returns "", or returns why it cannot be (then `t`
// is unchanged): writes that are not additions, a field stored at another element, a vector
// written at an index that is not a member, or a block component written twice in one call.
std::string defer_assembly(Trace& t);

}  // namespace simit::jit
