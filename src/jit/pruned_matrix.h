// A compiled loop's view of a system matrix without its all-zero blocks: products over it
// stream only the blocks that hold values. Dropping a zero block drops terms 0 * x, which
// change no sum that starts at +0.0 while x is finite (docs/jit.md), so the loop's results
// stay the interpreter's bit for bit for finite vectors.
#pragma once

#include <cstdint>
#include <vector>

#include "runtime/system_matrix.h"
#include "runtime/system_ops.h"

namespace simit::jit {

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

  // Rebuilds the arrays from `m` (float components), reusing their storage while it fits:
  // into values32 when `single`, else into values. False (and the arrays not to be used)
  // when `single` and some value of `m` is not a binary32 value (a matrix the host bound
  // with binary64 values), which a binary32 copy would change.
  // `for_each` runs the passes' tasks (ranges of rows) on the executor's threads.
  bool assign(const runtime::SystemMatrix& m, bool single = false,
              const runtime::ForEachTask& for_each = {});
};

}  // namespace simit::jit
