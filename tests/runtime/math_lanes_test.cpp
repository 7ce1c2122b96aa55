// atan2 and log by four lanes (runtime/math/lanes.cpp) against the one-value functions: the
// same bits in every lane, whichever path each lane takes and whatever its neighbours are.
#include <gtest/gtest.h>

#include <cfloat>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
#include <utility>
#include <vector>

#include "runtime/math/math_functions.h"

namespace simit::math {
namespace {

uint64_t bits(double x) {
  uint64_t b;
  std::memcpy(&b, &x, sizeof b);
  return b;
}

// Runs every four consecutive pairs as one call (the last group padded with its first pair)
// and compares each lane with atan2 of that pair alone; returns how many lanes differ.
int lanes_that_differ(const std::vector<std::pair<double, double>>& yx) {
  int differ = 0;
  for (size_t i = 0; i < yx.size(); i += 4) {
    double y[4], x[4], out[4];
    for (size_t l = 0; l < 4; ++l) {
      const auto& p = yx[i + l < yx.size() ? i + l : i];
      y[l] = p.first;
      x[l] = p.second;
    }
    atan2_x4(y, x, out);
    for (int l = 0; l < 4; ++l) {
      const double one = atan2(y[l], x[l]);
      if (bits(one) != bits(out[l])) {
        ++differ;
        ADD_FAILURE() << "atan2(" << y[l] << ", " << x[l] << "): lane " << l << " gives " << out[l]
                      << ", one value at a time " << one;
      }
    }
  }
  return differ;
}

TEST(MathLanes, EveryAtan2LaneHasTheBitsOfAtan2) {
  const double inf = std::numeric_limits<double>::infinity();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  // Special values and the edges of the fast path's domain (exponents 123 and 1923, a
  // factor 2^60 apart), each beside ordinary pairs so that lanes of both paths share a call.
  std::vector<std::pair<double, double>> yx = {
      {0.0, 0.0},
      {-0.0, -0.0},
      {0.0, -1.0},
      {-0.0, 1.0},
      {1.0, 0.0},
      {-1.0, -0.0},
      {inf, -inf},
      {-inf, inf},
      {nan, 1.0},
      {1.0, nan},
      {1.0, 1.0},
      {-1.0, -1.0},
      {0x1p-900, 1.0},
      {0x1p-901, 1.0},
      {0x1p900, 1.0},
      {0x1p901, 0x1p900},
      {1.0, 0x1p-60},
      {1.0, 0x1p-61},
      {0x1p-60, -1.0},
      {0x1p-61, -1.0},
      {DBL_MAX, DBL_MAX},
      {0x1p-1074, 0x1p-1074},
      {1e-310, -1.0},
      {3.0, 4.0},
      // Near halfway between two doubles (runtime/math_test.cpp): the rounding test fails
      // and the lane goes the accurate way.
      {-0x1.c2af397e0adb6p-1, -0x1.53e002c53397cp-1},
      {-0x1.ab9a1eda7e06cp-1, 0x1.fdc636564fd6cp-1}};
  std::mt19937_64 g(17);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  for (int i = 0; i < 400000; ++i) {
    double y, x;
    switch (i % 4) {
      case 0: {  // any bits at all
        const uint64_t a = g(), b = g();
        std::memcpy(&y, &a, sizeof y);
        std::memcpy(&x, &b, sizeof x);
        break;
      }
      case 1:  // magnitudes over a wide range of ratios
        y = std::ldexp(unit(g), static_cast<int>(g() % 200) - 100);
        x = std::ldexp(unit(g), static_cast<int>(g() % 200) - 100);
        break;
      default:  // the angles of a simulation's vectors
        y = unit(g);
        x = unit(g);
    }
    yx.push_back({y, x});
  }
  EXPECT_EQ(lanes_that_differ(yx), 0);
}

// Every four consecutive arguments as one call of log_x4 (the last group padded with its
// first), each lane against log of that argument alone; returns how many lanes differ.
int log_lanes_that_differ(const std::vector<double>& xs) {
  int differ = 0;
  for (size_t i = 0; i < xs.size(); i += 4) {
    double x[4], out[4];
    for (size_t l = 0; l < 4; ++l) x[l] = xs[i + l < xs.size() ? i + l : i];
    log_x4(x, out);
    for (int l = 0; l < 4; ++l) {
      const double one = log(x[l]);
      if (bits(one) != bits(out[l])) {
        ++differ;
        ADD_FAILURE() << "log(" << x[l] << "): lane " << l << " gives " << out[l]
                      << ", one value at a time " << one;
      }
    }
  }
  return differ;
}

TEST(MathLanes, EveryLogLaneHasTheBitsOfLog) {
  const double inf = std::numeric_limits<double>::infinity();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  // Special values and the edges of the lanes' domain (the smallest normal, the largest
  // finite, 1 and the neighbours of the table's halving point 1.5), beside ordinary values.
  std::vector<double> xs = {0.0,     -0.0,      -1.0,          inf,
                            -inf,    nan,       DBL_MIN,       DBL_MIN / 2,
                            DBL_MAX, 1.0,       1.5,           std::nextafter(1.5, 0.0),
                            0.75,    0x1p-1074, 1.0 + 0x1p-52, 1.0 - 0x1p-53};
  std::mt19937_64 g(23);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int i = 0; i < 400000; ++i) {
    double x;
    switch (i % 4) {
      case 0: {  // any bits at all
        const uint64_t a = g();
        std::memcpy(&x, &a, sizeof x);
        break;
      }
      case 1:  // a wide range of magnitudes
        x = std::ldexp(unit(g), static_cast<int>(g() % 2200) - 1100);
        break;
      default:  // near 1, as the determinant of a deformation gradient
        x = 0.5 + unit(g);
    }
    xs.push_back(x);
  }
  EXPECT_EQ(log_lanes_that_differ(xs), 0);
}

// Eight lanes (a --float32 kernel's) in one call: each lane the one-value function's bits.
TEST(MathLanes, EightLanesInOneCallHaveTheBitsOfEachValue) {
  const double y[8] = {1.0, -2.0, 0.5, 1e-300, -0.0, 3.0, 1e300, -7.25};
  const double x[8] = {2.0, 3.0, -0.25, -1.0, 0.75, 1.0 + 0x1p-52, 0x1p-1074, 1.5};
  double a[8], c[8];
  simit_math_atan2_x8(y, x, a);
  simit_math_log_x8(x, c);
  for (int l = 0; l < 8; ++l) {
    EXPECT_EQ(bits(a[l]), bits(atan2(y[l], x[l]))) << l;
    EXPECT_EQ(bits(c[l]), bits(log(x[l]))) << l;
  }
}

// The C names that compiled kernels call compute the same.
TEST(MathLanes, TheCNamesAreTheSameFunctions) {
  const double y[4] = {1.0, -2.0, 0.5, 1e-300}, x[4] = {2.0, 3.0, -0.25, -1.0};
  double a[4], b[4], c[4], d[4];
  atan2_x4(y, x, a);
  simit_math_atan2_x4(y, x, b);
  log_x4(x, c);
  simit_math_log_x4(x, d);
  for (int l = 0; l < 4; ++l) {
    EXPECT_EQ(bits(a[l]), bits(b[l])) << l;
    EXPECT_EQ(bits(a[l]), bits(atan2(y[l], x[l]))) << l;
    EXPECT_EQ(bits(c[l]), bits(d[l])) << l;
    EXPECT_EQ(bits(c[l]), bits(log(x[l]))) << l;
  }
}

}  // namespace
}  // namespace simit::math
