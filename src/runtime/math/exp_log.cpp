// exp, log and pow (docs/math.md). log keeps about 76 bits of log x (a double-double), so that
// pow's y log x, up to 745 in size, still has an absolute error near 2^-67, and exp takes its
// argument as a double-double: pow is then almost always correctly rounded, as exp and log are.
#include "runtime/math/dd.h"
#include "runtime/math/log_core.h"
#include "runtime/math/math_functions.h"
#include "runtime/math/tables.h"

#include <cmath>  // std::sqrt only: correctly rounded by IEEE 754, an instruction everywhere

namespace simit::math {

namespace {

using namespace detail;
namespace tb = tables;

// Beyond these exp's result is inf or 0 whatever the rounding (ln DBL_MAX = 709.78...,
// ln 2^-1075 = -745.13...); between them and the true thresholds, scale_result decides.
constexpr double kExpOverflow = 709.8;
constexpr double kExpUnderflow = -745.2;

// Rounds (hi + lo) * 2^k once, for 0.5 <= hi < 4 and |lo| <= ulp(hi): overflow gives inf,
// a subnormal result is rounded on the subnormal grid directly (not rounded to 53 bits first).
double scale_result(double hi, double lo, int k) {
  if (k >= -1021) return scale(hi + lo, k);  // at least 2^-1022: normal (or overflow)
  const int k1 = k + 1022;                   // the result is (hs + ls) * 2^-1022
  if (k1 < -60) return 0.0;                  // below 2^-1080: rounds to zero
  const double hs = hi * pow2(k1), ls = lo * pow2(k1);
  const double y = hs + ls;
  if (y >= 1.0) return y * pow2(-1022);
  // In [1, 2) a double's ulp is 2^-52, which is 2^-1074 once scaled by 2^-1022: adding 1
  // rounds hs + ls on the subnormal grid in one step.
  double s, e;
  two_sum(1.0, hs, s, e);
  const double r = s + (e + ls);
  return (r - 1.0) * pow2(-1022);
}

// exp(xh + xl) = (hi + lo) * 2^k with 0.99 < hi < 2.02, relative error near 2^-70,
// for kExpUnderflow <= xh <= kExpOverflow and |xl| <= ulp(xh).
struct Scaled {
  double hi, lo;
  int k;
};

Scaled exp_core(double xh, double xl) {
  // x = n ln2/128 + r with |r| <= ln2/256 (n by rounding: adding 1.5 * 2^52 rounds to integer).
  constexpr double kShift = 0x1.8p52;
  const double nd = (xh * tb::kExpInvLn2N + kShift) - kShift;
  const int n = static_cast<int>(nd);
  const double r0 = xh - nd * tb::kExpLn2N1;  // exact: nd * kExpLn2N1 has at most 53 bits
  double rh, rl;
  two_sum(r0, xl - nd * tb::kExpLn2N2, rh, rl);
  // exp(r) - 1 - r, of size r^2/2 <= 2^-18: double precision is enough for it.
  const double* c = tb::kExpPoly;
  const double q = rh * rh * (c[0] + rh * (c[1] + rh * (c[2] + rh * (c[3] + rh * c[4])))) + rh * rl;
  double ph, pl;
  fast_two_sum(rh, rl + q, ph, pl);  // exp(r) = 1 + ph + pl
  // 2^(j/128) (1 + p), with the products that matter kept exact.
  const int j = n & 127;
  const double th = tb::kExp2[2 * j], tl = tb::kExp2[2 * j + 1];
  double ah, al, sh, sl;
  two_prod(th, ph, ah, al);
  fast_two_sum(th, ah, sh, sl);
  const double lo = sl + (al + th * pl + tl + tl * ph);
  return {sh, lo, n >> 7};  // n >> 7 rounds toward minus infinity, as n & 127 assumes
}

// log x as a double-double for finite x > 0, relative error near 2^-76 when `precise` (as
// pow needs), else near 2^-67 (log's own result needs no more).
DD log_dd(double x, bool precise) {
  uint64_t ix = bits_of(x);
  int e = 0;
  if (ix < (uint64_t{1} << 52)) {  // subnormal: scale into the normal range
    x *= pow2(52);
    ix = bits_of(x);
    e = -52;
  }
  e += static_cast<int>(ix >> 52) - 1023;
  const uint64_t mant = ix & ((uint64_t{1} << 52) - 1);
  // x = 2^e z with z in [3/4, 3/2): a significand of 1.5 or more is halved.
  const int j = static_cast<int>(mant >> 45);  // the top 7 bits: z's interval
  uint64_t zexp = 1023;
  if (j >= 64) {
    zexp = 1022;
    e += 1;
  }
  const double z = from_bits(mant | (zexp << 52));
  DD out;
  const double ed = e;
  if (precise)
    log_core<true>(z, tb::kLog[3 * j], ed, tb::kLog[3 * j + 1], tb::kLog[3 * j + 2], out.hi,
                   out.lo);
  else
    log_core<false>(z, tb::kLog[3 * j], ed, tb::kLog[3 * j + 1], tb::kLog[3 * j + 2], out.hi,
                    out.lo);
  return out;
}

// y's kind for pow: not an integer, an odd integer, or an even one.
enum class IntKind { NotInteger, Odd, Even };

IntKind integer_kind(double y) {
  const uint64_t iy = bits_of(y) & kAbsMask;
  const int ey = static_cast<int>(iy >> 52) - 1023;
  if (ey < 0) return iy == 0 ? IntKind::Even : IntKind::NotInteger;
  if (ey > 52) return IntKind::Even;  // 2^53 and beyond are even integers (and inf, NaN)
  const uint64_t sig = (iy & ((uint64_t{1} << 52) - 1)) | (uint64_t{1} << 52);
  const int frac_bits = 52 - ey;
  if (frac_bits > 0 && (sig & ((uint64_t{1} << frac_bits) - 1)) != 0) return IntKind::NotInteger;
  return ((sig >> frac_bits) & 1) ? IntKind::Odd : IntKind::Even;
}

}  // namespace

double exp(double x) {
  if (is_nan(x)) return x + x;
  if (x > kExpOverflow) return infinity();
  if (x < kExpUnderflow) return 0.0;
  if (abs_of(x) < 0x1p-54) return 1.0 + x;  // exp x = 1 + x + x^2/2...: rounds as 1 + x
  const Scaled s = exp_core(x, 0.0);
  return scale_result(s.hi, s.lo, s.k);
}

double log(double x) {
  if (is_nan(x)) return x + x;
  if (x == 0.0) return -infinity();  // either zero
  if (sign_of(x)) return nan_of(x);
  if (x == infinity()) return x;
  const DD l = log_dd(x, false);
  return l.hi + l.lo;
}

double pow(double x, double y) {
  // The special cases of C99 F.9.4.4, in its order of precedence.
  if (y == 0.0) return 1.0;  // even for a NaN x
  if (x == 1.0) return 1.0;  // even for a NaN y
  if (is_nan(x) || is_nan(y)) return x + y;
  const double ax = abs_of(x);
  if (abs_of(y) == infinity()) {
    if (ax == 1.0) return 1.0;
    return (ax > 1.0) == (y > 0.0) ? infinity() : 0.0;
  }
  const IntKind kind = integer_kind(y);
  const bool odd = kind == IntKind::Odd;
  if (x == 0.0) {
    if (y < 0.0) return odd ? with_sign(infinity(), sign_of(x)) : infinity();
    return odd ? x : 0.0;
  }
  if (ax == infinity()) {
    const bool negative = sign_of(x) && odd;
    return with_sign(y < 0.0 ? 0.0 : infinity(), negative);
  }
  bool negative = false;
  if (x < 0.0) {
    if (kind == IntKind::NotInteger) return nan_of(x);
    negative = odd;
  }
  // Two common exponents whose correctly rounded results are one operation (the general path
  // can miss by a hair where x^2 is exactly halfway between two doubles).
  if (y == 2.0) return with_sign(ax * ax, negative);
  if (y == 0.5) return std::sqrt(ax);
  // Now ax is finite, positive and not 1, and y finite and not 0. |log ax| >= 2^-53, so for
  // |y| >= 2^64 the result is beyond overflow or underflow.
  const bool grows = (ax > 1.0) == (y > 0.0);
  if (abs_of(y) >= 0x1p64) return with_sign(grows ? infinity() : 0.0, negative);
  const DD l = log_dd(ax, true);
  double zh, zl;
  two_prod(y, l.hi, zh, zl);
  zl += y * l.lo;
  fast_two_sum(zh, zl, zh, zl);
  if (zh > kExpOverflow) return with_sign(infinity(), negative);
  if (zh < kExpUnderflow) return with_sign(0.0, negative);
  const Scaled s = exp_core(zh, zl);
  return with_sign(scale_result(s.hi, s.lo, s.k), negative);
}

}  // namespace simit::math

// The C names (math_functions.h), here beside the functions so that the object that
// defines a function the interpreter calls also defines the name compiled code links to.
extern "C" {
double simit_math_exp(double x) { return simit::math::exp(x); }
double simit_math_log(double x) { return simit::math::log(x); }
double simit_math_pow(double x, double y) { return simit::math::pow(x, y); }
}
