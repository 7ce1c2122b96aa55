// The project's transcendental functions (runtime/math) against a binary128 reference
// (libquadmath): every argument within 1 ulp, special values exactly as C99 Annex F says.
// Each accuracy test prints its function's largest error in ulps, the share of results not
// correctly rounded (by the reference), and the share that differ from the C library's.
#include <gtest/gtest.h>

#include <bit>
#include <cfloat>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <random>
#include <string>
#include <utility>
#include <vector>

extern "C" {
#include <quadmath.h>
}

#include "runtime/math/math_functions.h"

namespace simit::math {
namespace {

using Quad = __float128;

// |got - ref| in units of the spacing of doubles at ref (2^-1074 below 2^-1022). A result of
// inf counts as 2^1024: right when ref rounds to inf, else as far as 2^1024 is from ref.
double ulp_error(double got, Quad ref) {
  if (isnanq(ref) || std::isnan(got)) return isnanq(ref) && std::isnan(got) ? 0.0 : HUGE_VAL;
  if (isinfq(ref)) return got == static_cast<double>(ref) ? 0.0 : HUGE_VAL;
  const Quad aref = fabsq(ref);
  int e = 0;
  frexpq(aref, &e);  // aref = f 2^e, f in [1/2, 1)
  const int ulp_exp = (e - 1 < -1022 ? -1022 : e - 1) - 52;
  Quad g = got;
  if (std::isinf(got)) {
    if (static_cast<double>(ref) == got) return 0.0;
    g = got > 0 ? ldexpq(Quad(1), 1024) : -ldexpq(Quad(1), 1024);
  }
  return static_cast<double>(fabsq(g - ref) / ldexpq(Quad(1), ulp_exp));
}

bool same_bits(double a, double b) {
  return (std::isnan(a) && std::isnan(b)) ||
         std::bit_cast<uint64_t>(a) == std::bit_cast<uint64_t>(b);
}

// The errors of one function over many arguments.
struct Stats {
  explicit Stats(std::string n) : name(std::move(n)) {}
  std::string name;
  long count = 0, not_correctly_rounded = 0, differ_from_libc = 0, over_one_ulp = 0;
  double max_error = 0.0;
  std::string worst;

  void add(double got, Quad ref, double libc, const std::string& args) {
    ++count;
    const double err = ulp_error(got, ref);
    if (!same_bits(got, static_cast<double>(ref))) ++not_correctly_rounded;
    if (!same_bits(got, libc)) ++differ_from_libc;
    if (err > 1.0) {
      if (++over_one_ulp <= 5) ADD_FAILURE() << name << args << ": " << err << " ulp";
    }
    if (err > max_error) max_error = err, worst = args;
  }

  // The summary, printed and recorded in the test's report.
  void report() const {
    char line[512];
    std::snprintf(line, sizeof line,
                  "%-6s %8ld args: max %.6f ulp at %s; not correctly rounded %.5f%% (%ld); "
                  "differ from the C library %.4f%%",
                  name.c_str(), count, max_error, worst.c_str(),
                  100.0 * not_correctly_rounded / count, not_correctly_rounded,
                  100.0 * differ_from_libc / count);
    std::printf("%s\n", line);
    ::testing::Test::RecordProperty("max_ulp_error", std::to_string(max_error));
    ::testing::Test::RecordProperty("differ_from_libc_fraction",
                                    std::to_string(1.0 * differ_from_libc / count));
    EXPECT_EQ(over_one_ulp, 0) << name;
    EXPECT_LE(max_error, 1.0) << name;
  }
};

std::string hex(double x) {
  char b[64];
  std::snprintf(b, sizeof b, "%a", x);
  return b;
}

// A fixed-seed source of arguments; its own distributions, so that the arguments are the
// same with every standard library.
class Args {
 public:
  explicit Args(uint64_t seed) : rng_(seed) {}
  // Uniform in [0, 1).
  double unit() { return static_cast<double>(rng_() >> 11) * 0x1p-53; }
  double uniform(double lo, double hi) { return lo + (hi - lo) * unit(); }
  // A magnitude with its binary exponent uniform in [lo, hi] and a random significand.
  double log_uniform(int lo, int hi) {
    const int e = lo + static_cast<int>(rng_() % static_cast<uint64_t>(hi - lo + 1));
    return std::ldexp(1.0 + unit(), e);
  }
  double sign() { return (rng_() & 1) ? -1.0 : 1.0; }
  // Any positive finite double, subnormals included (uniform in the bits).
  double any_positive() {
    for (;;) {
      const double x = std::bit_cast<double>(rng_() & 0x7fffffffffffffffull);
      if (std::isfinite(x) && x > 0) return x;
    }
  }
  uint64_t next() { return rng_(); }

 private:
  std::mt19937_64 rng_;
};

// Random arguments per function (a build may ask for more, for a longer search).
#ifndef SIMIT_MATH_TEST_RANDOM
#define SIMIT_MATH_TEST_RANDOM 300000
#endif
constexpr int kRandom = SIMIT_MATH_TEST_RANDOM;

using Fn1 = double (*)(double);
using Quad1 = Quad (*)(Quad);

void run1(Stats& s, Fn1 f, Quad1 ref, Fn1 libc, const std::vector<double>& xs) {
  for (double x : xs) s.add(f(x), ref(x), libc(x), "(" + hex(x) + ")");
}

void run2(Stats& s, const std::vector<std::pair<double, double>>& xy, bool atan2_order) {
  for (auto [a, b] : xy) {
    const double got = atan2_order ? simit::math::atan2(a, b) : simit::math::pow(a, b);
    const Quad ref = atan2_order ? atan2q(a, b) : powq(a, b);
    const double libc = atan2_order ? std::atan2(a, b) : std::pow(a, b);
    s.add(got, ref, libc, "(" + hex(a) + ", " + hex(b) + ")");
  }
}

// x and the doubles next to it.
void with_neighbours(std::vector<double>& xs, double x, int n = 2) {
  double lo = x, hi = x;
  xs.push_back(x);
  for (int i = 0; i < n; ++i) {
    lo = std::nextafter(lo, -HUGE_VAL), hi = std::nextafter(hi, HUGE_VAL);
    xs.push_back(lo), xs.push_back(hi);
  }
}

TEST(MathAccuracy, Exp) {
  std::vector<double> xs;
  // Listed by hand: clang-format would put one number a line.
  // clang-format off
  const double kHard[] = {
      0x1.62e42fefa39efp+9, 0x1.62e42fefa39f0p+9, -0x1.74385446d71c3p+9, -0x1.74910d52d3051p+9,
      -0x1.6232bdd7abcd2p+9, -0x1.6232bdd7abcd3p+9, 0x1p-54, 0x1p-53, 1.0, -1.0, 0.5, 1e-10,
      0x1p-1074, -0x1p-1074, 0x1p-1022, 709.7, -708.4, -709.5, -720.0, -740.0, -745.0,
      88.72283905206835, 0x1.62e42fefa39efp-8, 0x1.62e42fefa39efp-9, 0x1.0a2b23f3bab73p-7};
  // clang-format on
  for (double x : kHard) with_neighbours(xs, x);
  Args a(1);
  for (int i = 0; i < kRandom; ++i) {
    switch (i % 4) {
      case 0: xs.push_back(a.uniform(-745.2, 709.8)); break;
      case 1: xs.push_back(a.uniform(-2.0, 2.0)); break;
      case 2: xs.push_back(a.sign() * a.log_uniform(-60, 0)); break;
      default: xs.push_back(a.uniform(-745.2, -708.0)); break;  // subnormal results
    }
  }
  Stats s("exp");
  run1(s, simit::math::exp, expq, std::exp, xs);
  s.report();
}

TEST(MathAccuracy, Log) {
  std::vector<double> xs;
  for (double x : {1.0, 2.0, 0.5, 0.75, 1.5, 2.718281828459045, DBL_MAX, DBL_MIN, 0x1p-1074,
                   0x1.8p-1070, 0x1.fffffffffffffp-1023, 1.0 + 0x1p-7, 1.0 - 0x1p-8, 10.0})
    with_neighbours(xs, x, 3);
  for (int k = 1; k <= 60; ++k) with_neighbours(xs, 1.0 + std::ldexp(1.0, -k), 1);
  for (int k = 2; k <= 60; ++k) with_neighbours(xs, 1.0 - std::ldexp(1.0, -k), 1);
  for (int j = 0; j < 128; ++j) with_neighbours(xs, 1.0 + j / 128.0, 1);
  Args a(2);
  for (int i = 0; i < kRandom; ++i) {
    switch (i % 3) {
      case 0: xs.push_back(a.any_positive()); break;
      case 1: xs.push_back(a.uniform(0.5, 2.0)); break;
      default: xs.push_back(1.0 + a.sign() * a.log_uniform(-60, -8)); break;
    }
  }
  Stats s("log");
  run1(s, simit::math::log, logq, std::log, xs);
  s.report();
}

TEST(MathAccuracy, Pow) {
  // clang-format off
  std::vector<std::pair<double, double>> xy = {
      {2.0, 0.5}, {2.0, 1023.0}, {2.0, 1024.0}, {2.0, -1074.0}, {2.0, -1075.0}, {2.0, -1074.5},
      {2.0, -1022.5}, {0.5, 1074.0}, {10.0, 22.0}, {10.0, 23.0}, {10.0, -5.0}, {1.0000001, 1e10},
      {1.0 - 0x1p-53, 0x1p62}, {1.0 + 0x1p-52, 0x1p61}, {DBL_MAX, 0.5}, {DBL_MIN, 0.5},
      {0x1p-1074, 0.5}, {0x1p-1074, -0.5}, {-2.0, 3.0}, {-2.0, -1073.0}, {-0.5, 1075.0},
      {2.718281828459045, 709.78}, {3.0, 2.0}, {134217727.0, 2.0}, {1e-300, 1.0}, {1e300, -1.0},
      {7.0, 1.0 / 3.0}, {0x1.fffffffffffffp1023, 1.0}, {2.0, 1023.9999999999999}};
  // clang-format on
  Args a(3);
  for (int i = 0; i < kRandom; ++i) {
    double x, y;
    switch (i % 4) {
      case 0: {  // any x, y so that x^y lands anywhere in range
        x = a.any_positive();
        const double target = a.uniform(-745.0, 709.7);
        y = target / std::log(x);
        if (!std::isfinite(y)) y = 1.5;
        break;
      }
      case 1: x = a.uniform(0.0, 4.0), y = a.uniform(-40.0, 40.0); break;
      case 2:  // x near 1, y large
        x = 1.0 + a.sign() * a.log_uniform(-52, -20);
        y = a.sign() * a.log_uniform(0, 50);
        if (std::fabs(y * std::log(x)) > 700) y = 1.0 / std::log(x);
        break;
      default:  // negative x, integer y
        x = -a.uniform(0.0, 10.0);
        y = static_cast<double>(static_cast<int>(a.next() % 601) - 300);
        break;
    }
    xy.push_back({x, y});
  }
  Stats s("pow");
  run2(s, xy, false);
  s.report();
}

// Arguments for sin, cos and tan: small, near multiples of pi/2, huge.
std::vector<double> trig_args(uint64_t seed) {
  std::vector<double> xs;
  const double kHard[] = {0x1.921fb54442d18p+0, 0x1.921fb54442d18p+1, 0x1.921fb54442d18p+2,
                          0x1.921fb54442d18p-1, 0x1.2d97c7f3321d2p+1, 1e22, 0x1p1023, DBL_MAX,
                          0x1.6ac5b262ca1ffp+849, 5.319372648326541e+255, 0x1p19, 1e6, 1e15, 1e300,
                          0x1p-26, 0x1p-27, 0x1p-1074, 0x1p-1022, 1.0, 0.5, 0.8, 355.0, 103993.0,
                          104348.0, 0x1.0p52, 0x1.0p53, 1.5707963267948966e10,
                          // the doubles below 2^19 closest to multiples of pi/2 (r ~ 2^-54)
                          0x1.39c6fd67805a7p+18, 0x1.93c05c9ed3cbcp+18, 0x1.edb9bbd6273d1p+18,
                          0x1.bf9b3c6059d24p+17, 0x1.65a1dd290660fp+16};
  for (double x : kHard) with_neighbours(xs, x, 3);
  for (double k = 1; k < 2e6; k = k * 1.37 + 1)  // k pi/2 rounded, where r cancels most
    with_neighbours(xs, k * 1.5707963267948966, 1);
  Args a(seed);
  for (int i = 0; i < kRandom; ++i) {
    switch (i % 4) {
      case 0: xs.push_back(a.uniform(-10.0, 10.0)); break;
      case 1: xs.push_back(a.sign() * a.log_uniform(-30, 20)); break;
      case 2: xs.push_back(a.sign() * a.log_uniform(19, 1023)); break;
      default: {
        const double k = std::floor(a.uniform(0.0, 1e6));
        xs.push_back(std::nextafter(k * 1.5707963267948966, a.sign() * HUGE_VAL));
        break;
      }
    }
  }
  return xs;
}

TEST(MathAccuracy, Sin) {
  Stats s("sin");
  run1(s, simit::math::sin, sinq, std::sin, trig_args(4));
  s.report();
}

TEST(MathAccuracy, Cos) {
  Stats s("cos");
  run1(s, simit::math::cos, cosq, std::cos, trig_args(5));
  s.report();
}

TEST(MathAccuracy, Tan) {
  Stats s("tan");
  run1(s, simit::math::tan, tanq, std::tan, trig_args(6));
  s.report();
}

std::vector<double> unit_interval_args(uint64_t seed) {
  std::vector<double> xs;
  for (double x : {1.0, 0.5, 0x1p-26, 0x1p-27, 0.9999999, 0.7071067811865476, 0x1p-1074})
    with_neighbours(xs, x, 3), with_neighbours(xs, -x, 3);
  Args a(seed);
  for (int i = 0; i < kRandom; ++i) {
    switch (i % 3) {
      case 0: xs.push_back(a.uniform(-1.0, 1.0)); break;
      case 1: xs.push_back(a.sign() * (1.0 - a.log_uniform(-53, -2))); break;
      default: xs.push_back(a.sign() * a.log_uniform(-60, -1)); break;
    }
  }
  return xs;
}

TEST(MathAccuracy, Asin) {
  Stats s("asin");
  run1(s, simit::math::asin, asinq, std::asin, unit_interval_args(7));
  s.report();
}

TEST(MathAccuracy, Acos) {
  Stats s("acos");
  run1(s, simit::math::acos, acosq, std::acos, unit_interval_args(8));
  s.report();
}

TEST(MathAccuracy, Atan2) {
  std::vector<std::pair<double, double>> xy = {{1.0, 1.0},
                                               {1.0, -1.0},
                                               {-1.0, -1.0},
                                               {1e-300, 1e300},
                                               {1e300, 1e-300},
                                               {-1e300, -1e-300},
                                               {0x1p-1074, 0x1p-1074},
                                               {0x1p-1074, 0x1.8p-1073},
                                               {DBL_MAX, DBL_MAX},
                                               {DBL_MAX, -DBL_MAX},
                                               {1.0, 0x1p-60},
                                               {0x1p-60, -1.0},
                                               {1e-310, 1.0},
                                               {1e-310, -1.0},
                                               {3.0, 4.0},
                                               {1.0, 0x1p-1074}};
  Args a(9);
  for (int i = 0; i < kRandom; ++i) {
    const int gap = static_cast<int>(a.next() % 141) - 70;
    const int base = static_cast<int>(a.next() % 2000) - 1000;
    double y = a.sign() * a.log_uniform(base, base);
    double x = a.sign() * a.log_uniform(base + gap, base + gap);
    if (i % 3 == 0) y = a.uniform(-1.0, 1.0), x = a.uniform(-1.0, 1.0);
    xy.push_back({y, x});
  }
  Stats s("atan2");
  run2(s, xy, true);
  s.report();
}

TEST(MathAccuracy, Cbrt) {
  std::vector<double> xs;
  for (double x :
       {27.0, 8.0, 1.0, 2.0, 3.0, 4.0, DBL_MAX, DBL_MIN, 0x1p-1074, 0x1.8p-1060, 1e-300, 1e300})
    with_neighbours(xs, x, 3), with_neighbours(xs, -x, 1);
  Args a(10);
  for (int i = 0; i < 2000; ++i) {  // exact cubes
    const double n = static_cast<double>(a.next() % 200000);
    xs.push_back(a.sign() * n * n * n);
  }
  for (int i = 0; i < kRandom; ++i)
    xs.push_back(i % 2 ? a.sign() * a.any_positive() : a.uniform(-100.0, 100.0));
  Stats s("cbrt");
  run1(s, simit::math::cbrt, cbrtq, std::cbrt, xs);
  s.report();
}

// ---------------------------------------------------------------------------
// Special values, bit for bit (C99 Annex F; any NaN for a NaN).

constexpr double kInf = HUGE_VAL;
const double kNaN = std::nan("");
constexpr double kPio2 = 0x1.921fb54442d18p+0, kPi = 0x1.921fb54442d18p+1;
constexpr double kPio4 = 0x1.921fb54442d18p-1, k3Pio4 = 0x1.2d97c7f3321d2p+1;

struct Case1 {
  double x, expected;
};
struct Case2 {
  double x, y, expected;
};

void expect_cases(const char* name, Fn1 f, std::initializer_list<Case1> cases) {
  for (const Case1& c : cases)
    EXPECT_TRUE(same_bits(f(c.x), c.expected))
        << name << "(" << hex(c.x) << ") = " << hex(f(c.x)) << ", expected " << hex(c.expected);
}

void expect_cases(const char* name, double (*f)(double, double),
                  std::initializer_list<Case2> cases) {
  for (const Case2& c : cases)
    EXPECT_TRUE(same_bits(f(c.x, c.y), c.expected))
        << name << "(" << hex(c.x) << ", " << hex(c.y) << ") = " << hex(f(c.x, c.y))
        << ", expected " << hex(c.expected);
}

TEST(MathSpecialValues, ExpLog) {
  expect_cases("exp", simit::math::exp,
               {{0.0, 1.0},
                {-0.0, 1.0},
                {kInf, kInf},
                {-kInf, 0.0},
                {kNaN, kNaN},
                {710.0, kInf},
                {1e300, kInf},
                {-746.0, 0.0},
                {-1e300, 0.0},
                {0x1.62e42fefa39f0p+9, kInf},
                {-0x1.74910d52d3052p+9, 0.0},
                {-0x1.74385446d71c3p+9, 0x1p-1074},
                {1.0, 0x1.5bf0a8b145769p+1}});
  expect_cases("log", simit::math::log,
               {{1.0, 0.0},
                {0.0, -kInf},
                {-0.0, -kInf},
                {-1.0, kNaN},
                {-0x1p-1074, kNaN},
                {-kInf, kNaN},
                {kInf, kInf},
                {kNaN, kNaN},
                {2.0, 0x1.62e42fefa39efp-1},
                {0x1p-1074, -0x1.74385446d71c3p+9}});
}

TEST(MathSpecialValues, Pow) {
  expect_cases("pow", simit::math::pow,
               {// y = +-0, x = 1: 1 even for NaN
                {kNaN, 0.0, 1.0},
                {kNaN, -0.0, 1.0},
                {-kInf, 0.0, 1.0},
                {1.0, kNaN, 1.0},
                {1.0, kInf, 1.0},
                {1.0, -kInf, 1.0},
                // NaN otherwise
                {kNaN, 1.0, kNaN},
                {2.0, kNaN, kNaN},
                {-1.0, kNaN, kNaN},
                // zeros
                {0.0, -3.0, kInf},
                {-0.0, -3.0, -kInf},
                {0.0, -2.0, kInf},
                {-0.0, -2.0, kInf},
                {-0.0, -0.5, kInf},
                {-0.0, -kInf, kInf},
                {0.0, 3.0, 0.0},
                {-0.0, 3.0, -0.0},
                {-0.0, 2.0, 0.0},
                {-0.0, 0.5, 0.0},
                {-0.0, kInf, 0.0},
                // infinite y
                {-1.0, kInf, 1.0},
                {-1.0, -kInf, 1.0},
                {0.5, -kInf, kInf},
                {-0.5, -kInf, kInf},
                {2.0, -kInf, 0.0},
                {-2.0, -kInf, 0.0},
                {0.5, kInf, 0.0},
                {-0.5, kInf, 0.0},
                {2.0, kInf, kInf},
                {-2.0, kInf, kInf},
                // infinite x
                {-kInf, -3.0, -0.0},
                {-kInf, -2.0, 0.0},
                {-kInf, -0.5, 0.0},
                {-kInf, 3.0, -kInf},
                {-kInf, 2.0, kInf},
                {-kInf, 0.5, kInf},
                {kInf, -1.0, 0.0},
                {kInf, 0.5, kInf},
                // negative x: NaN for a non-integer y, the sign of an odd one
                {-2.0, 0.5, kNaN},
                {-0x1p-1074, 1.5, kNaN},
                {-2.0, 3.0, -8.0},
                {-2.0, 2.0, 4.0},
                {-2.0, -1.0, -0.5},
                {-3.0, 0x1p53, kInf},
                {-3.0, 0x1p53 + 2.0, kInf},
                {-0.5, 0x1p60, 0.0},
                {-2.0, 1025.0, -kInf},
                {-2.0, -1076.0, 0.0},
                {-2.0, -1075.0, -0.0},
                {-2.0, -1074.0, 0x1p-1074},
                {-2.0, -1073.0, -0x1p-1073},
                // exact results, overflow and underflow
                {2.0, 0.5, 0x1.6a09e667f3bcdp+0},
                {4.0, 0.5, 2.0},
                {10.0, 22.0, 1e22},
                {2.0, 1023.0, 0x1p1023},
                {2.0, 1024.0, kInf},
                {2.0, -1074.0, 0x1p-1074},
                {2.0, -1075.0, 0.0},
                {2.0, -1022.0, 0x1p-1022},
                {0.5, 1074.0, 0x1p-1074},
                {3.0, 0x1p70, kInf},
                {3.0, -0x1p70, 0.0},
                {1.0 - 0x1p-53, 0x1p70, 0.0},
                {1e300, 2.0, kInf},
                {1e-300, 2.0, 0.0},
                {9.0, 0.5, 3.0},
                {27.0, 1.0 / 3.0, 0x1.8p+1}});
}

TEST(MathSpecialValues, SinCosTan) {
  for (double x : {kInf, -kInf, kNaN}) {
    EXPECT_TRUE(std::isnan(simit::math::sin(x))) << x;
    EXPECT_TRUE(std::isnan(simit::math::cos(x))) << x;
    EXPECT_TRUE(std::isnan(simit::math::tan(x))) << x;
  }
  expect_cases("sin", simit::math::sin,
               {{0.0, 0.0},
                {-0.0, -0.0},
                {0x1p-1074, 0x1p-1074},
                {-0x1p-1074, -0x1p-1074},
                {kPio2, 1.0},
                {-kPio2, -1.0},
                {kPi, 0x1.1a62633145c07p-53},
                {1e22, -0x1.b453ab76bf397p-1}});
  expect_cases("cos", simit::math::cos,
               {{0.0, 1.0},
                {-0.0, 1.0},
                {0x1p-1074, 1.0},
                {kPio2, 0x1.1a62633145c07p-54},
                {kPi, -1.0},
                {1e22, 0x1.0be2cef01c8f4p-1}});
  expect_cases("tan", simit::math::tan,
               {{0.0, 0.0},
                {-0.0, -0.0},
                {0x1p-1074, 0x1p-1074},
                {kPio4, 0x1.fffffffffffffp-1},
                {kPio2, 0x1.d02967c31cdb5p+53}});
}

TEST(MathSpecialValues, InverseTrig) {
  expect_cases("asin", simit::math::asin,
               {{0.0, 0.0},
                {-0.0, -0.0},
                {1.0, kPio2},
                {-1.0, -kPio2},
                {0.5, 0x1.0c152382d7366p-1},
                {1.0 + 0x1p-52, kNaN},
                {-2.0, kNaN},
                {kInf, kNaN},
                {-kInf, kNaN},
                {kNaN, kNaN},
                {0x1p-1074, 0x1p-1074}});
  expect_cases("acos", simit::math::acos,
               {{1.0, 0.0},
                {-1.0, kPi},
                {0.0, kPio2},
                {-0.0, kPio2},
                {0.5, 0x1.0c152382d7366p+0},
                {1.0 + 0x1p-52, kNaN},
                {-2.0, kNaN},
                {kInf, kNaN},
                {kNaN, kNaN},
                {0x1p-1074, kPio2}});
  expect_cases("atan2", simit::math::atan2,
               {{0.0, 0.0, 0.0},        {-0.0, 0.0, -0.0},       {0.0, -0.0, kPi},
                {-0.0, -0.0, -kPi},     {0.0, -1.0, kPi},        {-0.0, -1.0, -kPi},
                {0.0, 1.0, 0.0},        {-0.0, 1.0, -0.0},       {1.0, 0.0, kPio2},
                {1.0, -0.0, kPio2},     {-1.0, 0.0, -kPio2},     {-1.0, -0.0, -kPio2},
                {1.0, -kInf, kPi},      {-1.0, -kInf, -kPi},     {1.0, kInf, 0.0},
                {-1.0, kInf, -0.0},     {kInf, 1.0, kPio2},      {-kInf, -1.0, -kPio2},
                {kInf, -kInf, k3Pio4},  {-kInf, -kInf, -k3Pio4}, {kInf, kInf, kPio4},
                {-kInf, kInf, -kPio4},  {kNaN, 1.0, kNaN},       {1.0, kNaN, kNaN},
                {1.0, 1.0, kPio4},      {-1.0, -1.0, -k3Pio4},   {0x1p-1074, 1.0, 0x1p-1074},
                {1.0, 0x1p-1074, kPio2}});
}

// Arguments whose exact results lie within 2^-22 ulp of a halfway point between two doubles
// (found by a search against binary128; the expected values are mpmath's at 300 bits, rounded
// once). The fast paths of atan2, asin and acos are good to about 2^-66 and cannot round
// these: their rounding test must pass them on to the double-double path. With an error
// bound of zero instead, the fast path alone gets 11 of these 14 wrong.
TEST(MathAccuracy, InverseTrigNearHalfway) {
  expect_cases("atan2", simit::math::atan2,
               {{-0x1.c2af397e0adb6p-1, -0x1.53e002c53397cp-1, -0x1.1bc48e54176ddp+1},
                {-0x1.ab9a1eda7e06cp-1, 0x1.fdc636564fd6cp-1, -0x1.655afa714c556p-1},
                {-0x1.d2284ab775932p-1, -0x1.aff6c3fac69dp-2, -0x1.009932489d21ep+1},
                {-0x1.a58080a89bf3cp-2, -0x1.d6b377ecc30a2p-1, -0x1.5c3d4ef1f9bb7p+1},
                {0x1.255fedcd9e7f2p+13, 0x1.5c3c1ff3a59cfp+0, 0x1.9216364c13951p+0},
                {0x1.ce666035fd089p-19, 0x1.cf70e4a95086ep+0, 0x1.fed98e9f33942p-20}});
  expect_cases("asin", simit::math::asin,
               {{-0x1.d019d0b60a4fp-4, -0x1.d11983559af58p-4},
                {-0x1.f467c7f307c78p-3, -0x1.f985f496d9359p-3},
                {0x1.ae948f2499406p-1, 0x1.ff884a26a327cp-1},
                {0x1.94427061e89dap-1, 0x1.d1f98a8866ca7p-1},
                {-0x1.ecf17a6d36562p-1, -0x1.4c0f1889b34c3p+0}});
  expect_cases("acos", simit::math::acos,
               {{-0x1.7de93185be29cp-2, 0x1.f3f75f5cbfeb6p+0},
                {-0x1.8b13600a4a68p-3, 0x1.c3d1e2675d37bp+0},
                {0x1.068702fa81bf4p-1, 0x1.084c358829e87p+0}});
}

TEST(MathSpecialValues, Cbrt) {
  expect_cases("cbrt", simit::math::cbrt,
               {{0.0, 0.0},
                {-0.0, -0.0},
                {kInf, kInf},
                {-kInf, -kInf},
                {kNaN, kNaN},
                {27.0, 3.0},
                {-27.0, -3.0},
                {-8.0, -2.0},
                {0x1p-1074, 0x1p-358},
                {0x1p-1071, 0x1p-357},
                {1e300, 0x1.249ad2594c37dp+332}});
}

// The C names are the same functions.
TEST(MathSpecialValues, CNames) {
  for (double x : {0.3, -2.5, 100.0}) {
    EXPECT_TRUE(same_bits(simit_math_exp(x), simit::math::exp(x)));
    EXPECT_TRUE(same_bits(simit_math_log(x), simit::math::log(x)));
    EXPECT_TRUE(same_bits(simit_math_pow(x, 0.7), simit::math::pow(x, 0.7)));
    EXPECT_TRUE(same_bits(simit_math_sin(x), simit::math::sin(x)));
    EXPECT_TRUE(same_bits(simit_math_cos(x), simit::math::cos(x)));
    EXPECT_TRUE(same_bits(simit_math_tan(x), simit::math::tan(x)));
    EXPECT_TRUE(same_bits(simit_math_asin(x / 100), simit::math::asin(x / 100)));
    EXPECT_TRUE(same_bits(simit_math_acos(x / 100), simit::math::acos(x / 100)));
    EXPECT_TRUE(same_bits(simit_math_atan2(x, 0.7), simit::math::atan2(x, 0.7)));
    EXPECT_TRUE(same_bits(simit_math_cbrt(x), simit::math::cbrt(x)));
  }
}

}  // namespace
}  // namespace simit::math
