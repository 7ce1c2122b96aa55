// atan2, asin and acos (docs/math.md), all from one atan of a quotient n/d <= 1 kept as a
// double-double: atan t = atan c + atan((t - c)/(1 + t c)) with c = j/64 from a table, and a
// short odd polynomial for the second term; asin and acos are atan2 of x and sqrt(1 - x^2).
#include "runtime/math/atan_fast.h"
#include "runtime/math/dd.h"
#include "runtime/math/math_functions.h"
#include "runtime/math/tables.h"

#include <cmath>  // std::sqrt only: correctly rounded by IEEE 754, an instruction everywhere

namespace simit::math {

namespace {

using namespace detail;
namespace tb = tables;

constexpr DD kPio2{tb::kPio2Hi, tb::kPio2Lo};
constexpr DD kPi{tb::kPiHi, tb::kPiLo};

DD negate(DD a) { return {-a.hi, -a.lo}; }

// atan(n/d) for 0 <= n <= d, d > 0, n/d >= 2^-1000 or 0 (no quotient near underflow),
// relative error near 2^-67.
DD atan_core(DD n, DD d) {
  constexpr double kShift = 0x1.8p52;
  const double jd = (n.hi / d.hi * 64.0 + kShift) - kShift;
  const int j = static_cast<int>(jd);
  const double c = jd * 0x1p-6;
  // v = (n/d - c)/(1 + c n/d) = (n - c d)/(d + c n), |v| <= 2^-7. n.hi - c d.hi cancels
  // exactly (c d.hi is within a factor 2 of n.hi, or zero).
  double p, pe;
  two_prod(c, d.hi, p, pe);
  DD num;
  two_sum(n.hi - p, (n.lo - pe) - c * d.lo, num.hi, num.lo);
  two_prod(c, n.hi, p, pe);
  DD den;
  double t;
  two_sum(d.hi, p, den.hi, t);
  fast_two_sum(den.hi, t + pe + d.lo + c * n.lo, den.hi, den.lo);
  const DD v = div(num, den);
  // atan v - v = v^3 (-1/3 + v^2/5 - v^4/7 + v^6/9), at most 2^-22.6 v: a double suffices.
  const double v2 = v.hi * v.hi;
  const double* a = tb::kAtanPoly;
  const double tail = v.hi * v2 * (a[0] + v2 * (a[1] + v2 * (a[2] + v2 * a[3])));
  double h;
  two_sum(tb::kAtan[2 * j], v.hi, h, t);
  const double l = t + (tb::kAtan[2 * j + 1] + v.lo + tail);
  DD out;
  fast_two_sum(h, l, out.hi, out.lo);
  return out;
}

// pi/2 - a (a in [0, pi/4]) or pi - a (a in [0, pi/2]): no cancellation below half.
DD minus(DD constant, DD a) { return add(constant, negate(a)); }

// atan(n/d) for n, d >= 0 not both zero, either order; the larger is the divisor.
DD atan_ratio(DD n, DD d) {
  if (n.hi > d.hi) return minus(kPio2, atan_core(d, n));
  return atan_core(n, d);
}

// sqrt(1 - x^2) for 0 <= ax <= 1 as a double-double: 1 - x^2 is formed exactly enough
// ((1 - ax)(1 + ax) near 1, where 1 - ax is exact), then one Newton step on sqrt.
DD sqrt_one_minus_square(double ax) {
  DD w;
  if (ax >= 0.5) {
    DD b;
    fast_two_sum(1.0, ax, b.hi, b.lo);
    w = mul(b, 1.0 - ax);
  } else {
    double p, e, t;
    two_prod(ax, ax, p, e);
    fast_two_sum(1.0, -p, w.hi, t);
    w.lo = t - e;
  }
  if (w.hi == 0.0) return {0.0, 0.0};
  const double s = std::sqrt(w.hi);
  double p, e;
  two_prod(s, s, p, e);
  DD out;
  fast_two_sum(s, (((w.hi - p) - e) + w.lo) / (2.0 * s), out.hi, out.lo);
  return out;
}

int biased_exponent(double x) { return static_cast<int>((bits_of(x) & kAbsMask) >> 52); }

// ---- The accurate path: the double-double evaluation above, about 2^-67 ----

[[gnu::noinline]] double atan2_accurate(double y, double x) {
  if (is_nan(x) || is_nan(y)) return x + y;
  const bool left = sign_of(x);  // -0 counts as left of the axis, as Annex F says
  double ay = abs_of(y), ax = abs_of(x);
  DD a;
  if (ay == infinity() || ax == infinity()) {
    if (ay != infinity()) {
      a = left ? kPi : DD{0.0, 0.0};
    } else if (ax != infinity()) {
      a = kPio2;
    } else {  // pi/4 or 3pi/4
      const DD quarter{0.5 * tb::kPio2Hi, 0.5 * tb::kPio2Lo};
      a = left ? minus(kPi, quarter) : quarter;
    }
    return with_sign(a.hi + a.lo, sign_of(y));
  }
  if (ay == 0.0 && ax == 0.0) {
    a = left ? kPi : DD{0.0, 0.0};
    return with_sign(a.hi + a.lo, sign_of(y));
  }
  const bool swap = ay > ax;
  double n = swap ? ax : ay, d = swap ? ay : ax;
  if (d < 0x1p-900) {  // both tiny: scale up (exactly) before looking at exponents
    n *= 0x1p600;
    d *= 0x1p600;
  }
  if (n == 0.0) {
    a = {0.0, 0.0};
  } else if (biased_exponent(d) - biased_exponent(n) > 60) {
    a = {n / d, 0.0};  // atan q = q (1 - q^2/3): q rounded is atan q rounded
  } else {
    // d into [1, 2) and n with it (n stays normal: within 2^61 of d).
    const int k = 1023 - biased_exponent(d);
    a = atan_core({scale(n, k), 0.0}, {scale(d, k), 0.0});
  }
  if (swap) a = minus(kPio2, a);
  if (left) a = minus(kPi, a);
  return with_sign(a.hi + a.lo, sign_of(y));
}

[[gnu::noinline]] double asin_accurate(double x) {
  if (is_nan(x)) return x + x;
  const double ax = abs_of(x);
  if (ax > 1.0) return nan_of(x);
  if (ax < 0x1p-26) return x;  // asin x = x + x^3/6 rounds to x (and keeps -0)
  const DD a = atan_ratio({ax, 0.0}, sqrt_one_minus_square(ax));
  return with_sign(a.hi + a.lo, sign_of(x));
}

[[gnu::noinline]] double acos_accurate(double x) {
  if (is_nan(x)) return x + x;
  const double ax = abs_of(x);
  if (ax > 1.0) return nan_of(x);
  DD a = atan_ratio(sqrt_one_minus_square(ax), {ax, 0.0});
  if (sign_of(x)) a = minus(kPi, a);
  return a.hi + a.lo;
}

// ---- The fast path (Ziv's strategy): the same reduction in plain doubles, an error bound,
// and a rounding test; the few results it cannot round go to the accurate path above ----

// The result is K + s atan(n/d) with n <= d: octant bit 0 says that n/d is the reciprocal
// of the ratio asked for (pi/2 - atan), bit 1 that the angle is pi minus that.
struct Octant {
  double k_hi, k_lo, s;
};
constexpr Octant kOctants[4] = {{0.0, 0.0, 1.0},
                                {tb::kPio2Hi, tb::kPio2Lo, -1.0},
                                {tb::kPiHi, tb::kPiLo, -1.0},
                                {tb::kPio2Hi, tb::kPio2Lo, 1.0}};

// atan_fast (runtime/math/atan_fast.h) in `octant`: true with the correctly rounded result in
// out, false when the rounding test cannot tell.
template <bool kWithLo>
[[gnu::always_inline]] inline bool atan_fast(double q, double n, double d, double n_lo, double d_lo,
                                             int octant, double& out) {
  const Octant& o = kOctants[octant];
  double other;
  const double result = detail::atan_fast<kWithLo>(q, n, d, n_lo, d_lo, o.k_hi, o.k_lo, o.s, other);
  if (result != other) return false;
  out = result;
  return true;
}

// a where c holds, else b, by bits: the selections of the fast paths of asin and acos depend
// on the argument, and as branches they are mispredicted for most argument sequences.
inline double pick(bool c, double a, double b) {
  const uint64_t m = uint64_t{0} - static_cast<uint64_t>(c);
  return from_bits((bits_of(a) & m) | (bits_of(b) & ~m));
}

// For 2^-30 <= ax < 1: s + s_lo = sqrt(1 - ax^2) within 2^-78, |s_lo| <= 2.5 2^-53 s, and
// q = min(ax, s) / max(ax, s) within a few ulp. s is the square root of (1 - ax)(1 + ax)
// rounded (within 3 ulp of 1 - ax^2 even near 1, where 1 - ax is exact); the Newton step
// takes the residual from 1 - ax^2 = (1 - p - t) - pe exactly, with p + pe = ax^2 (Dekker's
// product) and 1 - p = w1 + t: w1 is within 2^-27 of s^2, so w1 - s^2 is exact. 1/s is s/w.
// The divisions start early, beside the square root.
[[gnu::always_inline]] inline void sqrt_one_minus_square_fast(double ax, double& s, double& s_lo,
                                                              double& q) {
  const double inv_ax = 1.0 / ax;
  const double w = (1.0 - ax) * (1.0 + ax);
  s = std::sqrt(w);
  const double inv_w = 1.0 / w;
  double p, pe, w1, t, sq, sqe;
  two_prod(ax, ax, p, pe);
  fast_two_sum(1.0, -p, w1, t);  // 1 >= ax^2
  two_prod(s, s, sq, sqe);
  const double inv_s = s * inv_w;
  s_lo = (((w1 - sq) + (t - pe)) - sqe) * (0.5 * inv_s);
  // s/ax and ax/s: the one below 1 (or either, where both are about 1).
  const double a = s * inv_ax, b = ax * inv_s;
  q = a < b ? a : b;
}

}  // namespace

double atan2(double y, double x) {
  // Both finite, between 2^-900 and 2^901 in magnitude, within a factor 2^60 of each other:
  // the fast path; everything else (and what it cannot round) on the accurate path.
  const int ey = biased_exponent(y), ex = biased_exponent(x);
  if (static_cast<unsigned>(ey - 123) <= 1800u && static_cast<unsigned>(ex - 123) <= 1800u &&
      static_cast<unsigned>(ey - ex + 60) <= 120u) {
    const double ay = abs_of(y), ax = abs_of(x);
    const double n = ay < ax ? ay : ax, d = ay < ax ? ax : ay;
    const int octant = static_cast<int>(ay > ax) | (static_cast<int>(sign_of(x)) << 1);
    double out;
    if (atan_fast<false>(n / d, n, d, 0.0, 0.0, octant, out)) return with_sign(out, sign_of(y));
  }
  return atan2_accurate(y, x);
}

double asin(double x) {
  const double ax = abs_of(x);
  if (ax >= 0x1p-26 && ax < 1.0) {  // asin x = atan(ax / sqrt(1 - x^2)), signed
    double s, s_lo, q, out;
    sqrt_one_minus_square_fast(ax, s, s_lo, q);
    const bool swap = ax > s;
    if (atan_fast<true>(q, pick(swap, s, ax), pick(swap, ax, s), pick(swap, s_lo, 0.0),
                        pick(swap, 0.0, s_lo), static_cast<int>(swap), out)) {
      return with_sign(out, sign_of(x));
    }
  }
  return asin_accurate(x);
}

double acos(double x) {
  const double ax = abs_of(x);
  if (ax >= 0x1p-30 && ax < 1.0) {  // acos x = atan(sqrt(1 - x^2) / ax), or pi minus it
    double s, s_lo, q, out;
    sqrt_one_minus_square_fast(ax, s, s_lo, q);
    const bool swap = s > ax;
    const int octant = static_cast<int>(swap) | (static_cast<int>(sign_of(x)) << 1);
    if (atan_fast<true>(q, pick(swap, ax, s), pick(swap, s, ax), pick(swap, 0.0, s_lo),
                        pick(swap, s_lo, 0.0), octant, out)) {
      return out;
    }
  }
  return acos_accurate(x);
}

}  // namespace simit::math

// The C names (math_functions.h), here beside the functions so that the object that
// defines a function the interpreter calls also defines the name compiled code links to.
extern "C" {
double simit_math_asin(double x) { return simit::math::asin(x); }
double simit_math_acos(double x) { return simit::math::acos(x); }
double simit_math_atan2(double y, double x) { return simit::math::atan2(y, x); }
}
