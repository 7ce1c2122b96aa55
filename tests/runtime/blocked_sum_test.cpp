// The blocked order of reductions over sets (runtime/blocked_sum.h) against a reference written
// here from the words of docs/arithmetic.md, bit for bit, and against the left-to-right order
// it replaces (which it must not give).
#include "runtime/blocked_sum.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <complex>
#include <cstdint>
#include <random>
#include <vector>

#include "runtime/dense_linalg.h"
#include "runtime/system_ops.h"

namespace simit::runtime {
namespace {

using Complex = std::complex<double>;

uint64_t bits(double v) { return std::bit_cast<uint64_t>(v); }

// The contract's order, written out with its own numbers: element sums from +0.0; chunks of
// 256 elements; in a chunk, lane l (of 32, starting at +0.0) adds the chunk's elements l,
// l + 32, l + 64, ... in turn; the lanes halve (a[i] + a[i + half]) down to one; the total
// adds the chunks' results to +0.0 in order.
template <class T>
T reference_dot(const std::vector<T>& x, const std::vector<T>& y, size_t group) {
  const size_t elements = x.size() / group;
  std::vector<T> t(elements);
  for (size_t e = 0; e < elements; ++e) {
    T s{};
    for (size_t c = 0; c < group; ++c) s += x[e * group + c] * y[e * group + c];
    t[e] = s;
  }
  T total{};
  for (size_t start = 0; start < elements; start += 256) {
    const size_t stop = std::min(elements, start + 256);
    std::vector<T> lanes(32, T{});
    for (size_t l = 0; l < 32; ++l)
      for (size_t e = start + l; e < stop; e += 32) lanes[l] += t[e];
    while (lanes.size() > 1) {
      const size_t half = lanes.size() / 2;
      std::vector<T> next(half);
      for (size_t i = 0; i < half; ++i) next[i] = lanes[i] + lanes[i + half];
      lanes = next;
    }
    total += lanes[0];
  }
  return total;
}

// Element sums added one after another: the order of dense vectors (and formerly of all).
double left_to_right(const std::vector<double>& x, const std::vector<double>& y, size_t group) {
  double total = 0.0;
  for (size_t k = 0; k < x.size(); k += group) {
    double part = 0.0;
    for (size_t c = 0; c < group; ++c) part += x[k + c] * y[k + c];
    total += part;
  }
  return total;
}

// Values of both signs over some twenty binary orders of magnitude, so that the order of the
// additions shows in the last bits. A fixed engine and a conversion written out, so that the
// values are the same with every standard library.
std::vector<double> values(size_t n, uint64_t seed) {
  std::mt19937_64 g(seed);
  std::vector<double> v(n);
  for (double& x : v) {
    const double unit = static_cast<double>(g() >> 11) * 0x1p-53;  // [0, 1)
    const int exponent = static_cast<int>(g() % 21) - 10;
    x = std::ldexp(unit - 0.5, exponent);
  }
  return v;
}

TEST(BlockedSum, TheContractsNumbers) {
  EXPECT_EQ(kSumLanes, 32u);
  EXPECT_EQ(kSumChunk, 256u);
  EXPECT_EQ(sum_chunks(0), 0u);
  EXPECT_EQ(sum_chunks(1), 1u);
  EXPECT_EQ(sum_chunks(256), 1u);
  EXPECT_EQ(sum_chunks(257), 2u);
}

TEST(BlockedSum, MatchesTheReferenceBitForBit) {
  int differ = 0;
  for (size_t group : {1u, 3u})
    for (size_t n : {0u, 1u, 31u, 32u, 33u, 255u, 256u, 257u, 1000u}) {
      SCOPED_TRACE("group " + std::to_string(group) + ", " + std::to_string(n) + " elements");
      const std::vector<double> x = values(n * group, 7 + n), y = values(n * group, 1000 + n);
      const double got = blocked_dot(x.data(), y.data(), x.size(), group);
      EXPECT_EQ(bits(got), bits(reference_dot(x, y, group))) << got;
      EXPECT_EQ(bits(dot(x, y, group)), bits(got));  // the runtime's global-vector dot
      if (bits(got) != bits(left_to_right(x, y, group))) ++differ;
    }
  // The data tells the orders apart: the test fails should the order regress.
  EXPECT_GE(differ, 4);
}

TEST(BlockedSum, DiffersFromTheLeftToRightSum) {
  // Lanes 0, 1, 2 hold 1e16, 1, -1e16: the tree adds lane 2 to lane 0 first (0), then lane 1
  // (1). Left to right, 1e16 + 1 rounds to 1e16 and the 1 is lost.
  const std::vector<double> x = {1e16, 1.0, -1e16}, ones(3, 1.0);
  EXPECT_EQ(blocked_dot(x.data(), ones.data(), 3, 1), 1.0);
  EXPECT_EQ(left_to_right(x, ones, 1), 0.0);
  // Elements 1 and 33 share lane 1 (1 + 1 = 2, exact), which the tree adds to lane 0's 1e16
  // (1e16 + 2, exact); element 256 starts the second chunk, whose partial -1e16 comes last: 2.
  // Left to right each 1 is lost against 1e16 (a tie, rounded to the even 1e16): 0.
  std::vector<double> big(257, 0.0), ones257(257, 1.0);
  big[0] = 1e16;
  big[1] = 1.0;
  big[33] = 1.0;
  big[256] = -1e16;
  EXPECT_EQ(blocked_dot(big.data(), ones257.data(), big.size(), 1), 2.0);
  EXPECT_EQ(left_to_right(big, ones257, 1), 0.0);
}

TEST(BlockedSum, ChunkPartialsCombineInChunkOrder) {
  const size_t group = 3, elements = 1000;
  const std::vector<double> x = values(elements * group, 1), y = values(elements * group, 2);
  // As a threaded caller would: the chunks in any order (here the last first), each into its
  // own slot, then combined in chunk order.
  std::vector<double> partials(sum_chunks(elements));
  for (size_t k = partials.size(); k-- > 0;)
    partials[k] = chunk_partial(x.data(), y.data(), group, k * kSumChunk,
                                std::min(elements, (k + 1) * kSumChunk));
  const double combined = combine_partials(partials.data(), partials.size());
  EXPECT_EQ(bits(combined), bits(blocked_dot(x.data(), y.data(), x.size(), group)));
  EXPECT_EQ(bits(combine_partials(nullptr, 0)), bits(0.0));
}

TEST(BlockedSum, SignOfZeroAndEmptySums) {
  // Every sum starts from +0.0: products -0.0 give +0.0, and so does an empty set.
  const std::vector<double> x = {-0.0, -0.0}, y = {1.0, 1.0};
  EXPECT_EQ(bits(blocked_dot(x.data(), y.data(), 2, 1)), bits(0.0));
  EXPECT_EQ(bits(blocked_dot(x.data(), y.data(), 0, 1)), bits(0.0));
  double lanes[kSumLanes];
  std::fill(lanes, lanes + kSumLanes, -0.0);
  EXPECT_EQ(bits(fold_lanes(lanes)), bits(-0.0));  // the tree itself adds no +0.0
}

TEST(BlockedSum, ComplexComponents) {
  const size_t group = 2, elements = 300;
  const std::vector<double> re = values(2 * elements * group, 3);
  std::vector<Complex> x(elements * group), y(elements * group);
  for (size_t i = 0; i < x.size(); ++i) {
    x[i] = Complex(re[2 * i], re[2 * i + 1]);
    y[i] = Complex(re[2 * i + 1], -re[2 * i]);
  }
  const Complex got = blocked_dot(x.data(), y.data(), x.size(), group);
  const Complex want = reference_dot(x, y, group);
  EXPECT_EQ(bits(got.real()), bits(want.real()));
  EXPECT_EQ(bits(got.imag()), bits(want.imag()));
}

TEST(BlockedSum, SetInnerProductOfTensors) {
  // A global vector of 3-blocks sums in the blocked order; the same components as a dense
  // vector keep the left-to-right order.
  const size_t elements = 300;
  const std::vector<double> x = values(3 * elements, 11), y = values(3 * elements, 12);
  Tensor u(ComponentKind::Float, Shape::blocked({static_cast<int>(elements)}, Shape{3}));
  Tensor v(ComponentKind::Float, u.shape());
  std::copy(x.begin(), x.end(), u.mutable_floats());
  std::copy(y.begin(), y.end(), v.mutable_floats());
  EXPECT_EQ(bits(set_inner_product(u, v).floats()[0]), bits(reference_dot(x, y, 3)));
  EXPECT_EQ(bits(inner_product(u, v).floats()[0]), bits(left_to_right(x, y, 3)));
  EXPECT_NE(bits(reference_dot(x, y, 3)), bits(left_to_right(x, y, 3)));
}

}  // namespace
}  // namespace simit::runtime
