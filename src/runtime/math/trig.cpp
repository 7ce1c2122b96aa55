// sin, cos and tan (docs/math.md): x = k pi/2 + r with r a double-double (Cody-Waite with a
// four-part pi/2 below 2^19, Payne-Hanek with the bits of 2/pi beyond), then r = j/64 + b
// and the sums of angles on a table of sin(j/64), cos(j/64), with short polynomials in b.
#include "runtime/math/dd.h"
#include "runtime/math/math_functions.h"
#include "runtime/math/tables.h"

namespace simit::math {

namespace {

using namespace detail;
namespace tb = tables;

// |x| = k pi/2 + r, |r| <= pi/4 (a little more below 2^19, where k comes from a rounded
// product), r = hi + lo with relative error near 2^-75.
struct Reduced {
  DD r;
  int k;  // the quadrant, mod 4
};

// The high 64 bits and the low 64 bits of a * b, from 32-bit halves (no 128-bit type).
void mul_64x64(uint64_t a, uint64_t b, uint64_t& hi, uint64_t& lo) {
  const uint64_t a0 = a & 0xffffffffu, a1 = a >> 32, b0 = b & 0xffffffffu, b1 = b >> 32;
  const uint64_t p00 = a0 * b0, p01 = a0 * b1, p10 = a1 * b0, p11 = a1 * b1;
  const uint64_t mid = (p00 >> 32) + (p01 & 0xffffffffu) + (p10 & 0xffffffffu);
  lo = (mid << 32) | (p00 & 0xffffffffu);
  hi = p11 + (p01 >> 32) + (p10 >> 32) + (mid >> 32);
}

// 64 bits of 2/pi from bit g (g = 0: the place 2^63 of kTwoOverPiBits[0]).
uint64_t two_over_pi_bits(int g) {
  const int w = g >> 6, s = g & 63;
  const uint64_t* t = tb::kTwoOverPiBits;
  return s == 0 ? t[w] : (t[w] << s) | (t[w + 1] >> (64 - s));
}

// Payne-Hanek for |x| >= 2^19: x = m 2^e with m an integer of 53 bits, and x 2/pi mod 4 from
// the 192 bits of 2/pi that can reach it (the bits before give multiples of 4, those after
// less than 2^-137 of a quadrant).
Reduced reduce_huge(double ax) {
  const uint64_t ix = bits_of(ax);
  const int e = static_cast<int>(ix >> 52) - 1075;
  const uint64_t m = (ix & ((uint64_t{1} << 52) - 1)) | (uint64_t{1} << 52);
  // The bit of 2/pi of place 2^-i multiplies m 2^e into m 2^(e-i): from i = e - 1 on it
  // reaches the places below 4. G is the 192 bits from place 2^-(e-1): m G is x 2/pi mod 4
  // scaled by 2^190.
  const int g = (e - 1) + 63;  // e >= -33 here, so g >= 29
  const uint64_t g2 = two_over_pi_bits(g), g1 = two_over_pi_bits(g + 64),
                 g0 = two_over_pi_bits(g + 128);
  uint64_t h0, l0, h1, l1, h2, l2;
  mul_64x64(m, g0, h0, l0);
  mul_64x64(m, g1, h1, l1);
  mul_64x64(m, g2, h2, l2);
  (void)h2;  // multiples of 2^192: of 4 quadrants
  uint64_t p0 = l0, p1 = h0 + l1;
  uint64_t p2 = h1 + l2 + (p1 < h0 ? 1 : 0);
  // Bits 191..190 (the top of p2) are the quadrant, the 190 below the fraction. Round to the
  // nearest quadrant: a fraction of 1/2 or more counts from the next one, negative.
  int k = static_cast<int>(p2 >> 62);
  bool negative = false;
  p2 &= (uint64_t{1} << 62) - 1;
  if (p2 >> 61) {
    k += 1;
    negative = true;
    // 2^190 - fraction, in three words (two's complement of the 190-bit number).
    p0 = ~p0 + 1;
    p1 = ~p1 + (p0 == 0 ? 1 : 0);
    p2 = (~p2 + (p0 == 0 && p1 == 0 ? 1 : 0)) & ((uint64_t{1} << 62) - 1);
  }
  // The fraction's leading 128 bits, then as two doubles: (top, next) * 2^-190 * 2^shift.
  int shift = 0;  // how far the words were moved up
  while (p2 == 0 && shift < 128) {
    p2 = p1, p1 = p0, p0 = 0;
    shift += 64;
  }
  if (p2 == 0) return {{0.0, 0.0}, k};  // not reached: x 2/pi is never this close to k
  const int lz = std::countl_zero(p2);
  if (lz > 0) {
    p2 = (p2 << lz) | (p1 >> (64 - lz));
    p1 = (p1 << lz) | (p0 >> (64 - lz));
  }
  shift += lz;
  // The fraction is now about (p2 2^128 + p1 2^64) 2^(-190 - shift), p2's leading bit set:
  // its top 53 bits have their last at the place 2^(139 - 190 - shift), the next 53 below.
  const double top = static_cast<double>(p2 >> 11);
  const double next = static_cast<double>(((p2 & 0x7ff) << 42) | (p1 >> 22));
  const int top_exp = -51 - shift;
  DD f;
  f.hi = top * pow2(top_exp);
  f.lo = next * pow2(top_exp - 53);
  DD r = mul(f, DD{tb::kPio2Hi, tb::kPio2Lo});
  if (negative) r.hi = -r.hi, r.lo = -r.lo;
  return {r, k};
}

Reduced reduce(double ax) {
  if (ax <= 0x1.921fb54442d18p-1) return {{ax, 0.0}, 0};  // within pi/4 already
  if (ax >= 0x1p19) return reduce_huge(ax);
  // Cody-Waite: k < 2^19, so k times each 33-bit part of pi/2 is exact, and the first
  // difference cancels exactly; the rest is gathered in a double-double.
  constexpr double kShift = 0x1.8p52;
  const double kd = (ax * tb::kTwoOverPi + kShift) - kShift;
  const double t0 = ax - kd * tb::kPio2Part1;
  double h, l, t;
  two_sum(t0, -(kd * tb::kPio2Part2), h, l);
  two_sum(h, -(kd * tb::kPio2Part3), h, t);
  l += t;
  l -= kd * tb::kPio2Part4;
  Reduced out;
  two_sum(h, l, out.r.hi, out.r.lo);
  out.k = static_cast<int>(kd);
  return out;
}

// sin r and cos r as double-doubles (either may be null: not wanted), |r| <= 0.8, relative
// error near 2^-67: r = a + b with a = j/64 from the table and |b| <= 1/128; sin b - b and
// cos b - 1 are short polynomials.
void sin_cos(DD r, DD* sin_r, DD* cos_r) {
  const bool negative = r.hi < 0.0;
  if (negative) r.hi = -r.hi, r.lo = -r.lo;
  constexpr double kShift = 0x1.8p52;
  const double jd = (r.hi * 64.0 + kShift) - kShift;
  const int j = static_cast<int>(jd);
  const double bh = r.hi - jd * 0x1p-6;  // exact: both are multiples of ulp(r.hi) and close
  const double bl = r.lo;
  const double b2 = bh * bh;
  const double* sp = tb::kSinPoly;
  const double* cp = tb::kCosPoly;
  const double sb3 = bh * b2 * (sp[0] + b2 * (sp[1] + b2 * sp[2]));  // sin b - b
  const double cb1 = b2 * (cp[0] + b2 * (cp[1] + b2 * (cp[2] + b2 * cp[3]))) -
                     bh * bl;  // cos b - 1 (with the b.lo part of -b^2/2)
  const double* row = tb::kSinCos + 4 * j;
  const double sah = row[0], sal = row[1], cah = row[2], cal = row[3];
  double p, pe, h, t, l;
  if (sin_r) {
    // sin(a + b) = sin a + cos a b + (cos a (sin b - b) + sin a (cos b - 1))
    two_prod(cah, bh, p, pe);
    two_sum(sah, p, h, t);
    l = t + (pe + (sal + cah * bl + cal * bh + cah * sb3 + sah * cb1));
    fast_two_sum(h, l, sin_r->hi, sin_r->lo);
    if (negative) sin_r->hi = -sin_r->hi, sin_r->lo = -sin_r->lo;
  }
  if (cos_r) {
    // cos(a + b) = cos a - sin a b + (cos a (cos b - 1) - sin a (sin b - b))
    two_prod(sah, bh, p, pe);
    two_sum(cah, -p, h, t);
    l = t + (-pe + (cal - sah * bl - sal * bh + cah * cb1 - sah * sb3));
    fast_two_sum(h, l, cos_r->hi, cos_r->lo);
  }
}

// sin or cos of k pi/2 + r: quadrant 0 sin r, 1 cos r, 2 -sin r, 3 -cos r (cos: one more).
double from_quadrant(const Reduced& red, bool want_cos) {
  const int q = (red.k + (want_cos ? 1 : 0)) & 3;
  DD v;
  if (q & 1)
    sin_cos(red.r, nullptr, &v);
  else
    sin_cos(red.r, &v, nullptr);
  const double s = v.hi + v.lo;
  return q & 2 ? -s : s;
}

}  // namespace

double sin(double x) {
  const double ax = abs_of(x);
  if (ax < 0x1p-26) return x;  // sin x = x - x^3/6: rounds to x (and keeps -0)
  if (ax == infinity() || is_nan(x)) return nan_of(x);
  const double v = from_quadrant(reduce(ax), false);
  return sign_of(x) ? -v : v;
}

double cos(double x) {
  const double ax = abs_of(x);
  if (ax < 0x1p-27) return 1.0;  // cos x = 1 - x^2/2 rounds to 1
  if (ax == infinity() || is_nan(x)) return nan_of(x);
  return from_quadrant(reduce(ax), true);
}

double tan(double x) {
  const double ax = abs_of(x);
  if (ax < 0x1p-27) return x;  // tan x = x + x^3/3 rounds to x
  if (ax == infinity() || is_nan(x)) return nan_of(x);
  const Reduced red = reduce(ax);
  DD s, c;
  sin_cos(red.r, &s, &c);
  // tan(r + k pi/2) = sin r / cos r for even k, -cos r / sin r for odd k.
  const DD q = (red.k & 1) ? div(c, s) : div(s, c);
  double v = q.hi + q.lo;
  if (red.k & 1) v = -v;
  return sign_of(x) ? -v : v;
}

}  // namespace simit::math

// The C names (math_functions.h), here beside the functions so that the object that
// defines a function the interpreter calls also defines the name compiled code links to.
extern "C" {
double simit_math_sin(double x) { return simit::math::sin(x); }
double simit_math_cos(double x) { return simit::math::cos(x); }
double simit_math_tan(double x) { return simit::math::tan(x); }
}
