// Assembly writes into the blocks of system matrices and their dense form, for every
// component kind they hold.
#pragma once

#include <cstddef>

#include "interp/value.h"

namespace simit::interp {

// Stores (or with `accumulate`, adds) `v` — a scalar broadcast over the part, or a tensor of
// `count` components — into components [offset, offset + count) of m's value array. The
// value's component kind must be m's; under float32 each addition rounds to binary32. Faults
// on a mismatch.
void write_matrix_part(runtime::SystemMatrix& m, size_t offset, size_t count, const Value& v,
                       bool accumulate, bool float32);

// Copies components [from, from + count) of `src` (of m's component kind) into components
// [offset, offset + count) of m's value array.
void store_tensor_part(runtime::SystemMatrix& m, size_t offset, const Tensor& src, size_t from,
                       size_t count);

// The logical unblocked matrix as a dense tensor of m's component kind (for printing).
Tensor dense_of(const runtime::SystemMatrix& m);

}  // namespace simit::interp
