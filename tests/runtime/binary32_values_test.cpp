// The binary32 checks and rounding of system matrices and vectors (runtime/system_ops.h,
// binary32_values.cpp), chunk by chunk: every chunk decided, NaNs as binary32 values.
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <span>
#include <vector>

#include "runtime/system_ops.h"

namespace simit::runtime {
namespace {

// is_binary32 of values, chunk by chunk: binary32 values (infinities and NaNs whatever their
// payload included) are; one binary64 value anywhere is not.
TEST(IsBinary32, EveryValueOfEveryChunkOrNot) {
  std::vector<double> v(5000);
  for (size_t i = 0; i < v.size(); ++i)
    v[i] = static_cast<float>(std::sin(0.37 * static_cast<double>(i)));
  v[10] = std::numeric_limits<double>::infinity();
  // A NaN with payload bits a binary32 NaN cannot hold: the rounding changes its bits.
  v[2100] = std::bit_cast<double>(uint64_t{0x7ff8000000000001});
  EXPECT_NE(std::bit_cast<uint64_t>(static_cast<double>(static_cast<float>(v[2100]))),
            std::bit_cast<uint64_t>(v[2100]));
  EXPECT_TRUE(is_binary32(std::span<const double>(v)));
  for (size_t at : {size_t{0}, size_t{2047}, size_t{2048}, size_t{4999}}) {
    std::vector<double> w = v;
    w[at] = 0.1;
    EXPECT_FALSE(is_binary32(std::span<const double>(w))) << at;
  }
}

TEST(RoundToFloat32, RoundsEveryValueOfEveryChunk) {
  // A block-tridiagonal matrix of 400 rows of 3 x 3 blocks: 10,782 values, several chunks of
  // the rounding's pass.
  std::vector<int32_t> row_ptr{0}, cols;
  for (int r = 0; r < 400; ++r) {
    for (int c = std::max(0, r - 1); c <= std::min(399, r + 1); ++c) cols.push_back(c);
    row_ptr.push_back(static_cast<int32_t>(cols.size()));
  }
  SystemMatrix m(MatrixPattern::from_csr(400, 400, row_ptr, cols), 3, 3);
  for (size_t i = 0; i < m.value_count(); ++i)
    m.values()[i] = std::sin(0.37 * static_cast<double>(i));
  ASSERT_GT(m.value_count(), 3u * 2048);
  // Chunk 0 binary32 values already but one, chunk 1 all binary32, the rest as they are.
  for (size_t i = 0; i < 2 * 2048; ++i) m.values()[i] = static_cast<float>(m.values()[i]);
  m.values()[1000] = 0.1;
  m.values()[3000] = std::numeric_limits<double>::quiet_NaN();
  const std::vector<double> before(m.values(), m.values() + m.value_count());
  round_to_float32(m);
  size_t changed = 0;
  for (size_t i = 0; i < before.size(); ++i) {
    const double want = static_cast<float>(before[i]);
    if (std::isnan(want)) {
      EXPECT_TRUE(std::isnan(m.values()[i])) << i;
      continue;
    }
    EXPECT_EQ(m.values()[i], want) << i;
    changed += m.values()[i] != before[i] ? 1 : 0;
  }
  EXPECT_EQ(m.values()[1000], static_cast<double>(0.1f));
  EXPECT_GT(changed, before.size() / 2);  // the values past chunk 1 were binary64 values
}

}  // namespace
}  // namespace simit::runtime
