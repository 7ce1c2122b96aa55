// PrunedMatrix (jit/pruned_matrix.h): the copy drops zero blocks, holds the others by columns
// and is padded; its passes over ranges of rows, run as tasks in any order, make the copy a
// serial pass makes, block for block, in binary64 and in binary32, and the binary32 copy says
// when a value is not a binary32 value.
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstring>
#include <functional>
#include <memory>

#include "jit/pruned_matrix.h"
#include "jit/thread_pool.h"
#include "runtime/lazy_sum.h"

namespace simit::jit {
namespace {

// A block-tridiagonal matrix of `rows` rows of 3 x 3 blocks, every seventh block zero.
runtime::SystemMatrix tridiagonal(int rows, bool binary32_values) {
  std::vector<int32_t> row_ptr{0}, cols;
  for (int r = 0; r < rows; ++r) {
    for (int c = std::max(0, r - 1); c <= std::min(rows - 1, r + 1); ++c) cols.push_back(c);
    row_ptr.push_back(static_cast<int32_t>(cols.size()));
  }
  runtime::SystemMatrix k(runtime::MatrixPattern::from_csr(rows, rows, row_ptr, cols), 3, 3);
  for (size_t b = 0; b < cols.size(); ++b)
    for (int i = 0; i < 9; ++i) {
      const double x = b % 7 == 3 ? 0.0 : std::sin(0.37 * static_cast<double>(9 * b + i));
      k.block(static_cast<int64_t>(b))[i] = binary32_values ? static_cast<float>(x) : x;
    }
  return k;
}

// A solver loop's copy of a matrix drops its zero blocks (of either sign; a block with a
// subnormal, a NaN or an infinity is kept), holds the others by columns, and is padded so that
// a 3-component column loads as one 4-lane vector.
TEST(PrunedMatrix, TheCopyDropsZeroBlocksHoldsColumnsAndIsPadded) {
  std::vector<int32_t> row_ptr{0}, cols;
  for (int r = 0; r < 5; ++r) {
    for (int c = std::max(0, r - 1); c <= std::min(4, r + 1); ++c) cols.push_back(c);
    row_ptr.push_back(static_cast<int32_t>(cols.size()));
  }
  runtime::SystemMatrix k(runtime::MatrixPattern::from_csr(5, 5, row_ptr, cols), 3, 3);
  for (size_t i = 0; i < k.value_count(); ++i)
    k.values()[i] = 0.1 * static_cast<double>(i % 17) - 0.7;
  for (int i = 0; i < 9; ++i) k.block(1)[i] = i == 4 ? -0.0 : 0.0;  // block (0, 1): dropped
  // Zeros but for one subnormal, one NaN, one -infinity: kept; all -0.0: dropped.
  const double odd[3] = {std::numeric_limits<double>::denorm_min(),
                         std::numeric_limits<double>::quiet_NaN(),
                         -std::numeric_limits<double>::infinity()};
  for (int b = 0; b < 3; ++b)
    for (int i = 0; i < 9; ++i) k.block(3 + b)[i] = i == 8 - b ? odd[b] : -0.0;
  for (int i = 0; i < 9; ++i) k.block(6)[i] = -0.0;  // block (2, 2): dropped
  PrunedMatrix p;
  p.assign(k);
  EXPECT_EQ(p.total, 13);
  EXPECT_EQ(p.kept, 11);
  EXPECT_EQ(p.row_ptr, (std::vector<int32_t>{0, 1, 4, 6, 9, 11}));
  EXPECT_EQ(p.cols[0], 0);
  EXPECT_EQ(p.cols[1], 0);        // row 1 starts with block (1, 0)
  ASSERT_EQ(p.cols.size(), 11u);  // the kept blocks only
  ASSERT_EQ(p.values.size(), 11u * 9 + 1);
  // Block (1, 0), by columns: component (i, j) at 3 j + i.
  const double* b = k.block(2);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) EXPECT_EQ(p.values[9 + 3 * j + i], b[3 * i + j]) << i << j;
}

// Runs the tasks last to first, as threads might finish them.
void backwards(int64_t tasks, const std::function<void(int64_t)>& task) {
  for (int64_t t = tasks - 1; t >= 0; --t) task(t);
}

TEST(PrunedMatrix, TasksOfRowsInAnyOrderMakeTheSerialCopy) {
  const runtime::SystemMatrix k = tridiagonal(10000, false);  // three tasks of rows
  PrunedMatrix serial, tasks;
  EXPECT_TRUE(serial.assign(k));
  EXPECT_TRUE(tasks.assign(k, false, backwards));
  EXPECT_EQ(serial.kept, tasks.kept);
  EXPECT_LT(serial.kept, serial.total);  // zero blocks were dropped
  EXPECT_EQ(serial.row_ptr, tasks.row_ptr);
  EXPECT_EQ(serial.cols, tasks.cols);
  EXPECT_EQ(serial.values, tasks.values);
  // Every kept block is a non-zero block of k, by columns, in row order.
  int64_t at = 0;
  for (int64_t b = 0; b < k.pattern().nnz(); ++b) {
    const double* blk = k.block(b);
    bool zero = true;
    for (int i = 0; i < 9; ++i) zero = zero && blk[i] == 0.0;
    if (zero) continue;
    ASSERT_LT(at, tasks.kept);
    EXPECT_EQ(tasks.cols[static_cast<size_t>(at)], k.pattern().col_idx()[static_cast<size_t>(b)]);
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        EXPECT_EQ(tasks.values[static_cast<size_t>(at) * 9 + 3 * j + i], blk[3 * i + j]);
    ++at;
  }
  EXPECT_EQ(at, tasks.kept);
}

TEST(PrunedMatrix, TheBinary32CopyHoldsTheValuesOrSaysItCannot) {
  const runtime::SystemMatrix k = tridiagonal(10000, true);
  PrunedMatrix wide, narrow;
  EXPECT_TRUE(wide.assign(k));
  EXPECT_TRUE(narrow.assign(k, true, backwards));
  ASSERT_EQ(narrow.values32.size(), wide.values.size());
  for (size_t i = 0; i + 1 < wide.values.size(); ++i)  // the last: padding
    EXPECT_EQ(static_cast<double>(narrow.values32[i]), wide.values[i]) << i;
  const runtime::SystemMatrix w = tridiagonal(10000, false);
  PrunedMatrix refused;
  EXPECT_FALSE(refused.assign(w, true, backwards));
}

// A NaN counts as a binary32 value whatever its payload: one whose payload the rounding
// changes sends its task to the value-by-value check, which finds a binary64 value beside it
// too; in a build and in a refresh, in single rows and in pairs.
TEST(PrunedMatrix, ANaNWhosePayloadRoundingChangesIsStillABinary32Value) {
  const double nan = std::bit_cast<double>(uint64_t{0x7ff8000000000001});
  ASSERT_NE(std::bit_cast<uint64_t>(static_cast<double>(static_cast<float>(nan))),
            std::bit_cast<uint64_t>(nan));
  for (const bool in_pairs : {false, true}) {
    runtime::SystemMatrix k = tridiagonal(3001, true);
    PrunedMatrix p;
    ASSERT_TRUE(p.assign(k, true, {}, in_pairs));
    k.block(4)[2] = nan;  // a kept block
    EXPECT_TRUE(p.assign(k, true, {}, in_pairs)) << in_pairs;
    EXPECT_EQ(p.refreshed, 1);
    PrunedMatrix built;
    EXPECT_TRUE(built.assign(k, true, backwards, in_pairs)) << in_pairs;
    k.block(5)[1] = 0.1;
    EXPECT_FALSE(p.assign(k, true, {}, in_pairs)) << in_pairs;
    EXPECT_EQ(p.refreshed, 2);
    PrunedMatrix again;
    EXPECT_FALSE(again.assign(k, true, backwards, in_pairs)) << in_pairs;
  }
}

// In pairs of rows (binary32): rows 2q and 2q + 1 side by side, each block pair's column j
// row 2q's values then row 2q + 1's, the shorter row padded with zero blocks at its last
// column, an odd last row paired with nothing (column 0, zeros).
TEST(PrunedMatrix, InPairsTheRowsLieSideBySide) {
  // 5 rows of 3 x 3 blocks; row 1 has blocks at columns 0 and 2, the others only (r, r);
  // block (1, 0) is zero and dropped.
  const std::vector<int32_t> row_ptr{0, 1, 3, 4, 5, 6}, cols{0, 0, 2, 2, 3, 4};
  runtime::SystemMatrix k(runtime::MatrixPattern::from_csr(5, 5, row_ptr, cols), 3, 3);
  for (size_t i = 0; i < k.value_count(); ++i)
    k.values()[i] = static_cast<float>(0.25 * static_cast<double>(i + 1));
  for (int i = 0; i < 9; ++i) k.block(1)[i] = 0.0;
  PrunedMatrix p;
  ASSERT_TRUE(p.assign(k, true, {}, true));
  EXPECT_TRUE(p.pairs);
  EXPECT_EQ(p.kept, 5);
  // Pairs (0, 1), (2, 3), (4, -): one block pair each.
  EXPECT_EQ(p.row_ptr, (std::vector<int32_t>{0, 1, 2, 3}));
  EXPECT_EQ(p.cols, (std::vector<int32_t>{0, 2, 2, 3, 4, 0}));
  ASSERT_EQ(p.values32.size(), 3u * 18 + 2);
  // Pair q's block for row 2q + side, component (i, j), lies at 18 q + 6 j + 3 side + i.
  auto expect_block = [&](int q, int side, const double* blk) {
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        EXPECT_EQ(
            static_cast<double>(p.values32[static_cast<size_t>(18 * q + 6 * j + 3 * side + i)]),
            blk ? blk[3 * i + j] : 0.0)
            << q << side << i << j;
  };
  expect_block(0, 0, k.block(0));
  expect_block(0, 1, k.block(2));
  expect_block(1, 0, k.block(3));
  expect_block(1, 1, k.block(4));
  expect_block(2, 0, k.block(5));
  expect_block(2, 1, nullptr);
  // A row of two blocks beside a row of one: the shorter is padded.
  const std::vector<int32_t> row_ptr2{0, 2, 3}, cols2{0, 1, 1};
  runtime::SystemMatrix m(runtime::MatrixPattern::from_csr(2, 2, row_ptr2, cols2), 2, 2);
  for (size_t i = 0; i < m.value_count(); ++i) m.values()[i] = static_cast<double>(i + 1);
  PrunedMatrix q;
  ASSERT_TRUE(q.assign(m, true, {}, true));
  EXPECT_EQ(q.row_ptr, (std::vector<int32_t>{0, 2}));
  EXPECT_EQ(q.cols, (std::vector<int32_t>{0, 1, 1, 1}));  // row 1's padding at its column 1
  ASSERT_EQ(q.values32.size(), 2u * 8);
  // Block pair 1: row 0's block (0, 1) by columns, then zeros for row 1.
  EXPECT_EQ(std::vector<float>(q.values32.begin() + 8, q.values32.end()),
            (std::vector<float>{5, 7, 0, 0, 6, 8, 0, 0}));
  // Not in pairs: binary64, or blocks of one row.
  PrunedMatrix wide;
  ASSERT_TRUE(wide.assign(k, false, {}, true));
  EXPECT_FALSE(wide.pairs);
}

TEST(PrunedMatrix, InPairsTasksInAnyOrderOrOnThreadsMakeTheSerialCopy) {
  const runtime::SystemMatrix k = tridiagonal(20001, true);
  ThreadPool pool(3);
  const auto on_pool = [&pool](int64_t tasks, const std::function<void(int64_t)>& task) {
    pool.run(tasks, task);
  };
  PrunedMatrix serial, backward, threaded, single;
  EXPECT_TRUE(serial.assign(k, true, {}, true));
  EXPECT_TRUE(backward.assign(k, true, backwards, true));
  EXPECT_TRUE(threaded.assign(k, true, on_pool, true));
  EXPECT_TRUE(single.assign(k, true));
  EXPECT_EQ(serial.kept, single.kept);
  for (const PrunedMatrix* other : {&backward, &threaded}) {
    EXPECT_EQ(serial.row_ptr, other->row_ptr);
    EXPECT_EQ(serial.cols, other->cols);
    EXPECT_EQ(serial.values32, other->values32);
  }
  // Each row's blocks are the single-row copy's, in order, then padding.
  for (size_t r = 0; r < 20001; ++r) {
    const size_t q = r / 2, side = r % 2;
    int32_t at = serial.row_ptr[q];
    for (int32_t b = single.row_ptr[r]; b < single.row_ptr[r + 1]; ++b, ++at) {
      ASSERT_LT(at, serial.row_ptr[q + 1]);
      EXPECT_EQ(serial.cols[2 * static_cast<size_t>(at) + side],
                single.cols[static_cast<size_t>(b)]);
      for (int j = 0; j < 3; ++j)
        for (int i = 0; i < 3; ++i)
          ASSERT_EQ(serial.values32[static_cast<size_t>(at) * 18 + static_cast<size_t>(6 * j) +
                                    3 * side + static_cast<size_t>(i)],
                    single.values32[static_cast<size_t>(b) * 9 + static_cast<size_t>(3 * j + i)]);
    }
  }
}

// A later copy of the same pattern reuses the layout: new values go to their slots in one
// pass; a kept block that became zero stays (its zeros add +-0), and a dropped block that is
// no longer zero makes the copy build again, the copy a first build makes.
TEST(PrunedMatrix, ALaterCopyOfThePatternReusesTheLayoutWhileTheDroppedBlocksStayZero) {
  for (const bool in_pairs : {false, true}) {
    runtime::SystemMatrix k = tridiagonal(3001, true);  // every seventh block zero
    PrunedMatrix p;
    ASSERT_TRUE(p.assign(k, true, backwards, in_pairs));
    EXPECT_EQ(p.pairs, in_pairs);
    EXPECT_EQ(p.refreshed, 0);
    // New values, the same zero blocks: the copy a first build makes of them.
    for (size_t i = 0; i < k.value_count(); ++i)
      if (k.values()[i] != 0.0) k.values()[i] = static_cast<float>(k.values()[i] * 1.5 + 0.25);
    ASSERT_TRUE(p.assign(k, true, backwards, in_pairs));
    EXPECT_EQ(p.refreshed, 1);
    PrunedMatrix fresh;
    ASSERT_TRUE(fresh.assign(k, true, {}, in_pairs));
    EXPECT_EQ(p.row_ptr, fresh.row_ptr);
    EXPECT_EQ(p.cols, fresh.cols);
    EXPECT_EQ(p.values32, fresh.values32);
    // Block 1 (kept) zero now: still there, as zeros; the layout stays.
    for (int i = 0; i < 9; ++i) k.block(1)[i] = 0.0;
    ASSERT_TRUE(p.assign(k, true, {}, in_pairs));
    EXPECT_EQ(p.refreshed, 2);
    EXPECT_EQ(p.cols, fresh.cols);
    EXPECT_EQ(p.kept, fresh.kept);
    // Block 3 (dropped) holds a value now: built again, as a first build.
    k.block(3)[4] = 0.5;
    ASSERT_TRUE(p.assign(k, true, {}, in_pairs));
    EXPECT_EQ(p.refreshed, 2);
    PrunedMatrix again;
    ASSERT_TRUE(again.assign(k, true, {}, in_pairs));
    EXPECT_EQ(p.kept, again.kept);
    EXPECT_EQ(p.row_ptr, again.row_ptr);
    EXPECT_EQ(p.cols, again.cols);
    EXPECT_EQ(p.values32, again.values32);
    // A binary64 copy of the same pattern is another layout: built, not refreshed.
    ASSERT_TRUE(p.assign(k, false, {}, false));
    EXPECT_EQ(p.refreshed, 2);
    EXPECT_FALSE(p.pairs);
    // A value that is not a binary32 value is still found by a refresh.
    ASSERT_TRUE(p.assign(k, true, {}, in_pairs));
    k.block(0)[0] = 0.1;
    EXPECT_FALSE(p.assign(k, true, {}, in_pairs));
    EXPECT_EQ(p.refreshed, 3);
  }
}

// A fused sum left pending (jit/pending_sums.h): the copy sums each block as it reads it and
// is the copy of the sum written out, built and then refreshed, in pairs, in single rows and
// in binary64, on a pool of threads; the matrix's own values are not written.
TEST(PrunedMatrix, APendingSumIsCopiedAsTheSumWrittenOut) {
  ThreadPool pool(3);
  const auto on_pool = [&pool](int64_t tasks, const std::function<void(int64_t)>& task) {
    pool.run(tasks, task);
  };
  std::vector<int32_t> diag_ptr{0}, diag_idx;
  for (int r = 0; r < 3001; ++r) {
    diag_idx.push_back(r);
    diag_ptr.push_back(r + 1);
  }
  auto m = std::make_shared<runtime::SystemMatrix>(
      runtime::MatrixPattern::from_csr(3001, 3001, diag_ptr, diag_idx), 3, 3);
  for (size_t i = 0; i < m->value_count(); ++i)
    m->values()[i] = static_cast<float>(1.0 + 0.01 * static_cast<double>(i % 17));
  for (const int layout : {0, 1, 2}) {  // pairs, single rows, binary64
    const bool single = layout < 2, in_pairs = layout == 0;
    runtime::SystemMatrix k = tridiagonal(3001, true);
    PrunedMatrix lazy, eager;
    for (int call = 0; call < 2; ++call) {
      runtime::SystemMatrix want = k;
      ASSERT_TRUE(runtime::add_into(*m, 1.0, want, -0.01, {}, single));
      const runtime::SystemMatrix before = k;
      const runtime::LazySum sum(m, 1.0, k.shared_pattern(), k.raw_values(), 9, -0.01, single);
      ASSERT_TRUE(eager.assign(want, single, {}, in_pairs)) << layout;
      ASSERT_TRUE(lazy.assign(k, single, on_pool, in_pairs, &sum)) << layout;
      EXPECT_EQ(lazy.refreshed, call) << layout;
      EXPECT_EQ(lazy.pairs, in_pairs);
      EXPECT_EQ(lazy.kept, eager.kept) << layout;
      EXPECT_EQ(lazy.row_ptr, eager.row_ptr) << layout;
      EXPECT_EQ(lazy.cols, eager.cols) << layout;
      EXPECT_EQ(lazy.values, eager.values) << layout;
      EXPECT_EQ(lazy.values32, eager.values32) << layout;
      EXPECT_EQ(std::memcmp(k.values(), before.values(), k.value_count() * sizeof(double)), 0);
      // New values for the second call, the same zero blocks.
      for (size_t i = 0; i < k.value_count(); ++i)
        if (k.values()[i] != 0.0) k.values()[i] = static_cast<float>(k.values()[i] * 0.5 - 0.125);
    }
  }
  // A binary64 sum into a binary32 copy: its values are checked, and are not binary32 values.
  runtime::SystemMatrix k = tridiagonal(3001, true);
  const runtime::LazySum wide(m, 1.0, k.shared_pattern(), k.raw_values(), 9, -0.01, false);
  PrunedMatrix p;
  EXPECT_FALSE(p.assign(k, true, {}, true, &wide));
}

// On a pool of threads (ThreadSanitizer runs this: scripts/sanitize.sh --thread).
TEST(PrunedMatrix, OnThreadsTheCopyIsTheSerialOne) {
  const runtime::SystemMatrix k = tridiagonal(20000, true);
  ThreadPool pool(3);
  const auto on_pool = [&pool](int64_t tasks, const std::function<void(int64_t)>& task) {
    pool.run(tasks, task);
  };
  PrunedMatrix serial, threaded;
  EXPECT_TRUE(serial.assign(k, true));
  EXPECT_TRUE(threaded.assign(k, true, on_pool));
  EXPECT_EQ(serial.row_ptr, threaded.row_ptr);
  EXPECT_EQ(serial.cols, threaded.cols);
  EXPECT_EQ(serial.values32, threaded.values32);
}

}  // namespace
}  // namespace simit::jit
