// atan2 and log of four arguments at once (or eight, as two groups of four), for compiled map
// kernels that compute four or eight elements in SIMD lanes: the arithmetic of
// runtime/math/atan_fast.h and log_core.h lane by lane, and the one-value function for each lane
// outside it (special values, subnormals, a result atan2's fast path cannot round). Every lane gets
// the one-value function's bits.
#include <cstdint>

#include "runtime/math/atan_fast.h"
#include "runtime/math/log_core.h"
#include "runtime/math/math_functions.h"

namespace simit::math {

namespace {

using detail::LaneBits4;
using detail::Lanes4;
using Mask4 = int64_t __attribute__((vector_size(32)));  // a lane's condition: 0 or -1
namespace tb = tables;

LaneBits4 bits_of(Lanes4 x) { return std::bit_cast<LaneBits4>(x); }
Lanes4 from_bits(LaneBits4 b) { return std::bit_cast<Lanes4>(b); }
Lanes4 pick(Mask4 c, Lanes4 a, Lanes4 b) {
  const LaneBits4 m = std::bit_cast<LaneBits4>(c);
  return from_bits((bits_of(a) & m) | (bits_of(b) & ~m));
}
Lanes4 splat(double v) { return Lanes4{v, v, v, v}; }
LaneBits4 pick_bits(Mask4 c, LaneBits4 a, LaneBits4 b) {
  const LaneBits4 m = std::bit_cast<LaneBits4>(c);
  return (a & m) | (b & ~m);
}

}  // namespace

void atan2_x4(const double* y, const double* x, double* out) {
  Lanes4 vy, vx;
  for (int l = 0; l < 4; ++l) {
    vy[l] = y[l];
    vx[l] = x[l];
  }
  const LaneBits4 by = bits_of(vy), bx = bits_of(vx);
  const LaneBits4 abs_mask = {detail::kAbsMask, detail::kAbsMask, detail::kAbsMask,
                              detail::kAbsMask};
  // The fast path's domain, as atan2 tests it: both finite, between 2^-900 and 2^901 in
  // magnitude, within a factor 2^60 of each other (unsigned differences of the exponents).
  const LaneBits4 ey = (by & abs_mask) >> 52, ex = (bx & abs_mask) >> 52;
  const Mask4 fast = ((ey - 123) <= 1800) & ((ex - 123) <= 1800) & ((ey - ex + 60) <= 120);
  const Lanes4 ay = from_bits(by & abs_mask), ax = from_bits(bx & abs_mask);
  const Mask4 steep = ay > ax, left = (bx >> 63) != 0;
  // Lanes outside the domain compute atan(1) (their result is not used), so that every
  // lane's table index stays in range.
  const Lanes4 one = splat(1.0);
  const Lanes4 n = pick(fast, pick(ay < ax, ay, ax), one);
  const Lanes4 d = pick(fast, pick(ay < ax, ax, ay), one);
  // The octant's K and s, as inverse_trig.cpp's kOctants lists them: K is pi/2 when steep,
  // else pi when left, else 0; s is 1 when steep and left are alike, else -1.
  const Lanes4 k_hi = pick(steep, splat(tb::kPio2Hi), pick(left, splat(tb::kPiHi), splat(0.0)));
  const Lanes4 k_lo = pick(steep, splat(tb::kPio2Lo), pick(left, splat(tb::kPiLo), splat(0.0)));
  const Lanes4 s = pick(steep == left, one, splat(-1.0));
  const Lanes4 zero = splat(0.0);
  Lanes4 other;
  const Lanes4 result = detail::atan_fast<false>(n / d, n, d, zero, zero, k_hi, k_lo, s, other);
  const Mask4 done = fast & (result == other);
  const LaneBits4 sign = by & ~abs_mask;
  const Lanes4 signed_result = from_bits((bits_of(result) & abs_mask) | sign);
  for (int l = 0; l < 4; ++l) out[l] = done[l] ? signed_result[l] : math::atan2(y[l], x[l]);
}

void log_x4(const double* x, double* out) {
  Lanes4 vx;
  for (int l = 0; l < 4; ++l) vx[l] = x[l];
  const LaneBits4 bx = bits_of(vx);
  // Positive normal finite arguments (biased exponent 1 to 2046, sign clear) take the lanes;
  // the others (zeros, negatives, subnormals, infinities, NaNs) log itself.
  const LaneBits4 biased = bx >> 52;
  const Mask4 normal = (biased - 1) < 2046;
  // x = 2^e z with z in [3/4, 3/2) (a significand of 1.5 or more is halved), e as a double,
  // and the table's entries for z's interval j (the top 7 bits of the significand). A lane
  // not taken computes log 1.
  const LaneBits4 mant = bx & ((uint64_t{1} << 52) - 1);
  const LaneBits4 j = pick_bits(normal, mant >> 45, LaneBits4{});
  const Mask4 upper = j >= 64;
  const LaneBits4 zexp = pick_bits(upper, LaneBits4{} + 1022, LaneBits4{} + 1023);
  const Lanes4 z =
      pick(normal, from_bits(pick_bits(normal, mant, LaneBits4{}) | (zexp << 52)), splat(1.0));
  Lanes4 ed, c, log_c_hi, log_c_lo;
  for (int l = 0; l < 4; ++l) {
    const int e = normal[l] ? static_cast<int>(biased[l]) - 1023 + (upper[l] ? 1 : 0) : 0;
    ed[l] = e;
    c[l] = tb::kLog[3 * j[l]];
    log_c_hi[l] = tb::kLog[3 * j[l] + 1];
    log_c_lo[l] = tb::kLog[3 * j[l] + 2];
  }
  Lanes4 hi, lo;
  detail::log_core<false>(z, c, ed, log_c_hi, log_c_lo, hi, lo);
  const Lanes4 result = hi + lo;
  for (int l = 0; l < 4; ++l) out[l] = normal[l] ? result[l] : math::log(x[l]);
}

}  // namespace simit::math

extern "C" {
void simit_math_atan2_x4(const double* y, const double* x, double* out) {
  simit::math::atan2_x4(y, x, out);
}
void simit_math_log_x4(const double* x, double* out) { simit::math::log_x4(x, out); }
// Eight lanes (a --float32 kernel's: jit/tunables.h, kLanes32) as two groups of four in one
// call, which saves the kernel a call and the spills of its lanes around it.
void simit_math_atan2_x8(const double* y, const double* x, double* out) {
  simit::math::atan2_x4(y, x, out);
  simit::math::atan2_x4(y + 4, x + 4, out + 4);
}
void simit_math_log_x8(const double* x, double* out) {
  simit::math::log_x4(x, out);
  simit::math::log_x4(x + 4, out + 4);
}
}
