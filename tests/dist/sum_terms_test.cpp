// A distributed reduction's contributions (dist/sum_terms.h): however the terms of a set are
// owned by the ranks (whole chunks, chunks shared, interleaved, a rank with nothing), the sum
// every rank combines has the bits of the one-process blocked sum (runtime::blocked_dot), on
// terms chosen so that another grouping rounds differently.
#include "dist/sum_terms.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <random>
#include <stdexcept>
#include <vector>

#include "runtime/blocked_sum.h"

namespace simit::dist {
namespace {

// Terms of widely spread magnitudes and both signs: their sum depends on the grouping.
std::vector<double> terms_of(size_t n, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> mantissa(-1.0, 1.0);
  std::uniform_int_distribution<int> exponent(-30, 30);
  std::vector<double> t(n);
  for (double& x : t) x = std::ldexp(mantissa(rng), exponent(rng));
  return t;
}

// The one-process sum: blocked_dot of the terms with ones, one term per element.
double one_process(const std::vector<double>& t) {
  const std::vector<double> ones(t.size(), 1.0);
  return runtime::blocked_dot(t.data(), ones.data(), t.size(), 1);
}

// The sum the ranks combine when term g belongs to rank owner[g].
double on_ranks(const std::vector<double>& t, const std::vector<int>& owner, int ranks) {
  std::vector<double> all;
  // Contributions concatenated in reverse rank order: the combination must not care.
  for (int r = ranks - 1; r >= 0; --r) {
    std::vector<int64_t> global;
    std::vector<double> mine;
    for (size_t g = 0; g < t.size(); ++g)
      if (owner[g] == r) {
        global.push_back(static_cast<int64_t>(g));
        mine.push_back(t[g]);
      }
    const std::vector<double> c = sum_contribution(global, mine, static_cast<int64_t>(t.size()));
    all.insert(all.end(), c.begin(), c.end());
  }
  return combine_contributions(all);
}

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

TEST(SumTerms, EveryOwnershipGivesTheOneProcessBits) {
  for (size_t n : {0u, 1u, 3u, 31u, 256u, 257u, 1000u, 2600u}) {
    const std::vector<double> t = terms_of(n, static_cast<uint32_t>(n) + 7);
    const double expected = one_process(t);
    const size_t chunk = runtime::kSumChunk;
    std::vector<std::vector<int>> owners;
    owners.emplace_back(n, 0);  // one rank owns all
    owners.emplace_back(n);     // whole chunks, 3 ranks
    for (size_t g = 0; g < n; ++g) owners.back()[g] = static_cast<int>((g / chunk) % 3);
    owners.emplace_back(n);  // interleaved terms
    for (size_t g = 0; g < n; ++g) owners.back()[g] = static_cast<int>(g % 3);
    owners.emplace_back(n);  // a cut inside a chunk
    for (size_t g = 0; g < n; ++g) owners.back()[g] = g < n / 2 + 5 ? 0 : 2;  // rank 1: none
    std::mt19937 rng(static_cast<uint32_t>(n));
    owners.emplace_back(n);  // at random
    for (size_t g = 0; g < n; ++g) owners.back()[g] = static_cast<int>(rng() % 3);
    for (size_t o = 0; o < owners.size(); ++o)
      EXPECT_TRUE(same_bits(on_ranks(t, owners[o], 3), expected))
          << n << " terms, ownership " << o << ": " << on_ranks(t, owners[o], 3) << " against "
          << expected;
  }
}

TEST(SumTerms, AWholeChunkIsSentAsItsPartialAndASharedOneTermByTerm) {
  const std::vector<double> t = terms_of(300, 1);  // chunk 0: 256 terms, chunk 1: 44
  std::vector<int64_t> global(300);
  for (size_t g = 0; g < 300; ++g) global[g] = static_cast<int64_t>(g);
  // All of chunk 0, and terms 256..259 of chunk 1 (the rest another rank's).
  const std::vector<double> c =
      sum_contribution(std::span(global).first(260), std::span(t).first(260), 300);
  ASSERT_EQ(c.size(), 2u + 2u * 4u);
  EXPECT_EQ(c[0], 0.0);
  const std::vector<double> ones(256, 1.0);
  EXPECT_TRUE(same_bits(c[1], runtime::chunk_partial(t.data(), ones.data(), 1, 0, 256)));
  for (size_t i = 0; i < 4; ++i) {
    EXPECT_EQ(c[2 + 2 * i], -1.0 - static_cast<double>(256 + i));
    EXPECT_TRUE(same_bits(c[3 + 2 * i], t[256 + i]));
  }
  // The whole short last chunk, owned by one rank, is a partial too.
  const std::vector<double> last =
      sum_contribution(std::span(global).subspan(256), std::span(t).subspan(256), 300);
  ASSERT_EQ(last.size(), 2u);
  EXPECT_EQ(last[0], 1.0);
}

TEST(SumTerms, AnOrderThatWouldChangeTheBitsIsTheContracts) {
  // 1, then 2^-53 twice, in one chunk's lanes 0, 1, 2: the tree adds lane 0 + lane 2 first
  // ((1 + 2^-53) rounds to 1), then lane 1: 1. With term 0 on rank 1 and the others on rank 0,
  // summing each rank's terms and then the ranks' sums would give 2^-52 + 1 = 1 + 2^-52.
  const std::vector<double> t = {1.0, std::ldexp(1.0, -53), std::ldexp(1.0, -53)};
  const std::vector<int> owner = {1, 0, 0};
  EXPECT_EQ(one_process(t), 1.0);
  EXPECT_EQ(on_ranks(t, owner, 2), 1.0);
  EXPECT_EQ((t[1] + t[2]) + t[0], 1.0 + std::ldexp(1.0, -52));
}

TEST(SumTerms, BadInputIsAnError) {
  const std::vector<int64_t> unordered = {2, 1};
  const std::vector<double> two = {1.0, 2.0};
  EXPECT_THROW(sum_contribution(unordered, two, 3), std::invalid_argument);
  const std::vector<int64_t> outside = {0, 3};
  EXPECT_THROW(sum_contribution(outside, two, 3), std::invalid_argument);
  EXPECT_THROW(sum_contribution(std::vector<int64_t>{0}, two, 3), std::invalid_argument);
  EXPECT_THROW(combine_contributions(std::vector<double>{1.0}), std::invalid_argument);
  // Chunk 1's partial without chunk 0's.
  EXPECT_THROW(combine_contributions(std::vector<double>{1.0, 5.0}), std::invalid_argument);
}

}  // namespace
}  // namespace simit::dist
