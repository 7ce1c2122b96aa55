// A compiled loop's view of a system matrix without its all-zero blocks: products over it
// stream only the blocks that hold values. Dropping a zero block drops terms 0 * x, which
// change no sum that starts at +0.0 while x is finite (docs/jit.md), so the loop's results
// stay the interpreter's bit for bit for finite vectors.
#pragma once

#include <cstdint>
#include <vector>

#include "jit/loop_ir.h"
#include "runtime/lazy_sum.h"
#include "runtime/system_matrix.h"
#include "runtime/system_ops.h"

namespace simit::jit {

// Whether a loop's products read the binary32 copy of a matrix of `block` x `block` blocks
// (values slot `values`) two rows at a time (PrunedMatrix::pairs): under --float32 on the
// CPU, for blocks of 2 to 4 rows, where a row's binary32 sums fill half a vector of 4 or 8
// lanes. The controller makes the copy and the emitter reads it by this one rule.
inline bool rows_in_pairs(const SystemTrace& t, const ArraySlot& values, int block) {
  return t.float32 && values.single && !t.matrices_in_place && !t.device && block >= 2 &&
         block <= 4;
}

struct PrunedMatrix {
  std::vector<int32_t> row_ptr, cols;
  // Each block column-major (square blocks only); the arrays hold the `kept` non-zero blocks
  // and no more (their storage is reused across calls). The values have bit_ceil(n) - n more
  // at the end: a compiled product reads each n-component column as a vector of bit_ceil(n)
  // lanes, the last column of the last block reaching into them.
  std::vector<double> values;
  // Under --float32 every value a program makes is a binary32 value (docs/arithmetic.md), so
  // the copy holds them as binary32, laid out as `values`: half the bytes a product streams.
  std::vector<float> values32;
  int64_t kept = 0, total = 0;  // blocks
  // Rows in pairs (rows_in_pairs; binary32 only): row_ptr[q] is the first block pair of rows
  // 2q and 2q + 1, which hold max(kept blocks of each) pairs; cols holds two columns per pair
  // (row 2q's, then row 2q + 1's), and values32 each pair's columns j = 0 .. n-1 in turn, row
  // 2q's n values then row 2q + 1's (2 n^2 values a pair), so that one load of 2 bit_ceil(n)
  // values and one shuffle give both rows' column j. The shorter row of a pair is padded with
  // zero blocks at its last kept column (column 0 when it has none, or for the missing row
  // after an odd last row): a term 0 * x = +-0 changes no sum that starts at +0.0 while x is
  // finite, as for a dropped block.
  bool pairs = false;
  bool single = false;  // values32 holds the values (else values)
  // Where each block of the matrix went: its slot in the copy (in pairs 2 q + side, q the
  // block pair), or -1 when it was dropped. A later assign on the same pattern with the same
  // layout copies each value to its slot in one pass, and builds again only when a dropped
  // block is no longer zero (a kept block that is zero now adds +-0, as padding does).
  std::vector<int32_t> slot;
  runtime::PatternPtr built_for;
  int built_block = 0;
  int64_t refreshed = 0;  // assigns that reused the layout (for tests)

  // Rebuilds the arrays from `m` (float components), reusing their storage while it fits:
  // into values32 when `single`, else into values; in pairs of rows when `pairs` (and
  // `single`, with 2 to 4 rows a block). False (and the arrays not to be used) when `single`
  // and some value of `m` is not a binary32 value (a matrix the host bound with binary64
  // values), which a binary32 copy would change.
  // `for_each` runs the passes' tasks (ranges of rows) on the executor's threads. With `sum`
  // (a fused sum pending in m's values: jit/pending_sums.h) the values are the sum's, each
  // block summed as it is copied, and m's own are not read.
  bool assign(const runtime::SystemMatrix& m, bool single = false,
              const runtime::ForEachTask& for_each = {}, bool pairs = false,
              const runtime::LazySum* sum = nullptr);
};

}  // namespace simit::jit
