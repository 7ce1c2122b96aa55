// LazySum (runtime/lazy_sum.h): add_into's sum read block by block gives add_into's bits, on
// one pattern and on a sub-pattern (a diagonal within a band), in binary64 and under
// --float32, for 1 x 1 to 4 x 4 blocks; write() sums into b's own storage.
#include "runtime/lazy_sum.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <memory>
#include <stdexcept>
#include <vector>

#include "runtime/system_ops.h"

namespace simit::runtime {
namespace {

// A band of rows r, r + 1 and r + 3 (mod n) with n x n blocks, and the diagonal within it.
struct Band {
  std::shared_ptr<SystemMatrix> band, diagonal;
};

Band band(int rows, int n) {
  std::vector<int32_t> row_ptr{0}, col_idx, diag_ptr{0}, diag_idx;
  for (int r = 0; r < rows; ++r) {
    std::vector<int32_t> cols{r, (r + 1) % rows, (r + 3) % rows};
    std::sort(cols.begin(), cols.end());
    col_idx.insert(col_idx.end(), cols.begin(), cols.end());
    row_ptr.push_back(static_cast<int32_t>(col_idx.size()));
    diag_idx.push_back(r);
    diag_ptr.push_back(r + 1);
  }
  Band b;
  b.band =
      std::make_shared<SystemMatrix>(MatrixPattern::from_csr(rows, rows, row_ptr, col_idx), n, n);
  b.diagonal =
      std::make_shared<SystemMatrix>(MatrixPattern::from_csr(rows, rows, diag_ptr, diag_idx), n, n);
  // Values that are not binary32 values, a -0.0 and a block of zeros among them.
  for (size_t i = 0; i < b.band->value_count(); ++i) b.band->values()[i] = std::sin(0.1 * i) * 1e3;
  for (size_t i = 0; i < b.diagonal->value_count(); ++i)
    b.diagonal->values()[i] = std::cos(0.7 * i) / 3;
  b.band->values()[0] = -0.0;
  for (int c = 0; c < n * n; ++c) b.band->values()[static_cast<size_t>(n * n + c)] = 0.0;
  return b;
}

// Every block of the sum as row() gives it, written out in b's layout.
std::vector<double> read_rows(const LazySum& s, size_t values) {
  std::vector<double> out(values, 1234.5);
  const size_t bs = static_cast<size_t>(s.block_size());
  int32_t last = -1;
  for (int32_t r = 0; r < s.pattern().rows(); ++r)
    s.row(r, [&](int32_t k, const double* block) {
      EXPECT_EQ(k, last + 1);  // every block, in order
      last = k;
      std::memcpy(out.data() + static_cast<size_t>(k) * bs, block, bs * sizeof(double));
    });
  return out;
}

bool same_bits(const double* a, const double* b, size_t n) {
  return std::memcmp(a, b, n * sizeof(double)) == 0;
}

TEST(LazySum, GivesAddIntosBits) {
  for (int n : {1, 2, 3, 4})
    for (bool float32 : {false, true})
      for (bool same_pattern : {false, true}) {
        Band b = band(37, n);
        const std::shared_ptr<const SystemMatrix> a = same_pattern ? band(37, n).band : b.diagonal;
        SystemMatrix want = *b.band;
        ASSERT_TRUE(fits_into(*a, want));
        ASSERT_TRUE(add_into(*a, 1.5, want, -0.37, {}, float32));
        const LazySum s(a, 1.5, b.band->shared_pattern(), b.band->raw_values(),
                        b.band->block_size(), -0.37, float32);
        const std::string at = "n " + std::to_string(n) + (float32 ? " float32" : "") +
                               (same_pattern ? " same pattern" : " diagonal");
        const std::vector<double> rows = read_rows(s, want.value_count());
        EXPECT_TRUE(same_bits(rows.data(), want.values(), want.value_count())) << at;
        // b's values are only read until write() sums into them.
        const SystemMatrix before = *band(37, n).band;
        EXPECT_TRUE(same_bits(b.band->values(), before.values(), before.value_count())) << at;
        s.write(b.band->values());
        EXPECT_TRUE(same_bits(b.band->values(), want.values(), want.value_count())) << at;
      }
}

// b summed into itself (A = K + s K): each block reads only itself, before it is written.
TEST(LazySum, SumsAMatrixIntoItself) {
  Band b = band(20, 3);
  SystemMatrix want = *b.band;
  ASSERT_TRUE(add_into(SystemMatrix(*b.band), 1.0, want, 0.25, {}, true));
  const LazySum s(b.band, 1.0, b.band->shared_pattern(), b.band->raw_values(), b.band->block_size(),
                  0.25, true);
  s.write(b.band->values());
  EXPECT_TRUE(same_bits(b.band->values(), want.values(), want.value_count()));
}

// Blocks larger than its stack array are refused, not summed past it.
TEST(LazySum, RefusesBlocksLargerThanItSums) {
  Band b = band(4, 9);  // 81 values a block
  EXPECT_THROW(
      LazySum(b.diagonal, 1.0, b.band->shared_pattern(), b.band->raw_values(), 81, 0.5, true),
      std::invalid_argument);
}

TEST(LazySum, FitsOnlyWhereAddIntoSums) {
  Band b = band(12, 2);
  EXPECT_TRUE(fits_into(*b.diagonal, *b.band));
  EXPECT_FALSE(fits_into(*b.band, *b.diagonal));  // the band's blocks are not in the diagonal
  SystemMatrix other_block(b.band->shared_pattern(), 3, 3);
  EXPECT_FALSE(fits_into(*b.diagonal, other_block));
}

}  // namespace
}  // namespace simit::runtime
