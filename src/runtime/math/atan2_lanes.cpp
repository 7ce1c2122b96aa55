// atan2 of four pairs at once, for compiled map kernels that compute four elements in SIMD
// lanes: the fast path of runtime/math/atan_fast.h lane by lane, and atan2 itself for each
// lane it does not cover or cannot round. Every lane gets the bits of simit::math::atan2.
#include <cstdint>

#include "runtime/math/atan_fast.h"
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
  // The octant's K and s (inverse_trig.cpp's kOctants): K is pi/2 when steep, else pi when
  // left, else 0; s is -1 when steep and left or neither... as the table lists them.
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

}  // namespace simit::math

extern "C" void simit_math_atan2_x4(const double* y, const double* x, double* out) {
  simit::math::atan2_x4(y, x, out);
}
