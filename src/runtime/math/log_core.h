// The arithmetic of log after its argument is reduced (runtime/math/exp_log.cpp), for one
// value (F = double) or the four lanes of a vector (runtime/math/lanes.cpp): the same
// operations in the same order, so every lane gives the one-value bits.
#pragma once

#include "runtime/math/dd.h"
#include "runtime/math/tables.h"

namespace simit::math::detail {

// log x = e ln2 - log c + log1p(r) for x = 2^e z, z in [3/4, 3/2), c ~ 1/z from the table
// (log c = log_c_hi + log_c_lo there) and r = z c - 1, as a double-double hi + lo: relative
// error near 2^-76 when kPrecise (as pow needs), else near 2^-67 (log's own result needs no
// more). `ed` is e as a double.
template <bool kPrecise, class F>
[[gnu::always_inline]] inline void log_core(F z, F c, F ed, F log_c_hi, F log_c_lo, F& hi, F& lo) {
  // r = z c - 1 exactly; |r| < 2^-7.
  F ph, pl, rh, rl;
  two_prod(z, c, ph, pl);
  two_sum(ph - 1.0, pl, rh, rl);  // ph - 1 is exact (ph is within 2^-6 of 1)
  // log1p(r) = r - r^2/2 + r^3 (1/3 + r P(r)); the terms down to r^3/3 in double-doubles.
  const double* p = tables::kLogPoly;
  const F tail =
      p[0] +
      rh * (p[1] + rh * (p[2] + rh * (p[3] + rh * (p[4] + rh * (p[5] + rh * (p[6] + rh * p[7]))))));
  F r2_hi, r2_lo;
  two_prod(rh, rh, r2_hi, r2_lo);
  r2_lo += 2.0 * rh * rl;
  F t3_hi = r2_hi * rh * (tables::kThirdHi + rh * tail);  // at most 2^-14.6 of log1p(r)
  F t3_lo{};
  if constexpr (kPrecise) {
    DD u;
    fast_two_sum(tables::kThirdHi, rh * tail, u.hi, u.lo);
    u.lo += tables::kThirdLo;
    DD r3;
    two_prod(r2_hi, rh, r3.hi, r3.lo);
    r3.lo += r2_hi * rl + r2_lo * rh;
    const DD t3 = mul(r3, u);
    t3_hi = t3.hi;
    t3_lo = t3.lo;
  }
  // e ln2 - log c + r - r^2/2 + t3, the large terms by exact sums.
  F h, l, t;
  two_sum(ed * tables::kLn2Hi, log_c_hi, h, l);  // ed * kLn2Hi is exact
  l += ed * tables::kLn2Lo + log_c_lo;
  two_sum(h, rh, h, t);
  l += t;
  two_sum(h, -0.5 * r2_hi, h, t);
  l += t;
  two_sum(h, t3_hi, h, t);
  l += t;
  l += (rl - 0.5 * r2_lo) + t3_lo;
  fast_two_sum(h, l, hi, lo);
}

}  // namespace simit::math::detail
