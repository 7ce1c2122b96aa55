// The fast path of atan2, asin and acos (runtime/math/inverse_trig.cpp): atan of a quotient
// n/d <= 1 in plain doubles with an error bound, for one value (F = double) or for the four
// lanes of a vector (F = Lanes4, runtime/math/lanes.cpp). Both run the same operations
// in the same order, so every lane gives the bits of the one-value path.
#pragma once

#include "runtime/math/dd.h"
#include "runtime/math/tables.h"

namespace simit::math::detail {

// x with the low kBits bits of its significand cleared: for a normal x, x - truncated(x)
// is exact and has at most kBits significant bits, and |truncated(x)| <= |x|.
template <int kBits>
inline double truncated(double x) {
  return from_bits(bits_of(x) & ~((uint64_t{1} << kBits) - 1));
}

// atan(j/64) as a double-double, j the low 7 bits of `shifted` (0 <= j <= 64).
inline void atan_table(double shifted, double& hi, double& lo) {
  const int j = static_cast<int>(bits_of(shifted) & 127);
  hi = tables::kAtan[2 * j];
  lo = tables::kAtan[2 * j + 1];
}

// Four lanes (GCC's and Clang's vector extension: each operation lane by lane, IEEE).
using Lanes4 = double __attribute__((vector_size(32)));
using LaneBits4 = uint64_t __attribute__((vector_size(32)));

template <int kBits>
inline Lanes4 truncated(Lanes4 x) {
  return std::bit_cast<Lanes4>(std::bit_cast<LaneBits4>(x) & ~((uint64_t{1} << kBits) - 1));
}

inline void atan_table(Lanes4 shifted, Lanes4& hi, Lanes4& lo) {
  for (int l = 0; l < 4; ++l) {
    double h, o;
    atan_table(shifted[l], h, o);
    hi[l] = h;
    lo[l] = o;
  }
}

// The fast path's error bound relative to its result. Its error stays below 2^-63.7 of the
// result: mostly the polynomial's, at most 9.2 ulp of |v|^3 <= 2^-14 |v| (7.5 ulp from v
// rounded, the rest from the rounding of the polynomial), with |v| <= 1.0001 atan(n/d); v
// itself comes out within 2^-75 and the table within 2^-106, and each of the four roundings
// of the low parts costs at most 2^-73.
inline constexpr double kFastError = 0x1p-62;

// K + s atan((n + n_lo)/(d + d_lo)), where K = k_hi + k_lo is 0, pi/2 or pi and s is 1 or
// -1 (the octant: whether n/d is the reciprocal of the ratio asked for, pi/2 - atan, and
// whether the angle is pi minus that). Returns the result rounded from one end of its error
// interval and sets `other` to it rounded from the other end: where they agree, that is the
// correctly rounded value; where not, the caller takes the accurate path. Needs
// 0 <= n <= d with n/d >= 2^-62, 2^-900 <= d < 2^901, |n_lo| <= 2.5 2^-53 n and
// |d_lo| <= 2.5 2^-53 d (zero unless kWithLo), and q, n/d to within 8 ulp.
template <bool kWithLo, class F>
[[gnu::always_inline]] inline F atan_fast(F q, F n, F d, F n_lo, F d_lo, F k_hi, F k_lo, F s,
                                          F& other) {
  // j = round(64 q (1 - 2^-40)) (the low bits of the shifted sum) and c = j/64: then
  // |n/d - c| <= 1/128 + 2^-40, and j >= 1 only where n/d > 1/128, so c d < 2n.
  constexpr double kShift = 0x1.8p52;
  const F shifted = q * (64.0 - 0x1p-34) + kShift;
  F atan_c_hi, atan_c_lo;
  atan_table(shifted, atan_c_hi, atan_c_lo);
  const F c = (shifted - kShift) * 0x1p-6;
  // v = (n - c d)/(d + c n), |v| <= 2^-7 (1 + 2^-33). With the last 7 bits of d and n cleared
  // (dh, nh), c dh and c nh are exact (c has 7 bits), and so are c (d - dh) and c (n - nh),
  // products of numbers of 7 bits; n - c dh cancels exactly (0 <= c dh < 2n). So num and
  // den are unevaluated sums of exact parts and parts below 2^-44 of them.
  const F dh = truncated<7>(d), nh = truncated<7>(n);
  F num_small = -(c * (d - dh)), den_small = c * (n - nh);
  if constexpr (kWithLo) {
    num_small += n_lo - c * d_lo;
    den_small += d_lo + c * n_lo;
  }
  F num_hi, num_lo;
  two_sum(n - c * dh, num_small, num_hi, num_lo);
  F den, den_lo;
  fast_two_sum(d, c * nh, den, den_lo);  // d >= c nh
  den_lo += den_small;
  // v = vh + vl: vd is v within 7.5 ulp (den rounded apart, without waiting for the exact
  // sum), vh is vd to 27 bits and denh is den to 26, so vh denh is exact and num - vh den,
  // at most 2^-25 num, comes out within a few of its ulps; over den it is vl.
  const F r = 1.0 / (d + c * n);
  const F vd = num_hi * r;
  const F vh = truncated<26>(vd);
  const F denh = truncated<27>(den);
  const F rest = (num_hi - vh * denh) + (num_lo - vh * ((den - denh) + den_lo));
  // atan v - v = v^3 (-1/3 + v^2/5 - v^4/7 + v^6/9), below 2^-22.6 |v|; the next term is
  // below 2^-73 |v|. Estrin's scheme, for a shorter chain of dependent operations.
  const double* a = tables::kAtanPoly;
  const F v2 = vd * vd, v4 = v2 * v2;
  const F poly = (a[0] + v2 * a[1]) + v4 * (a[2] + v2 * a[3]);
  const F tail = ((s * vd) * v2) * poly;  // s (atan v - v)
  // K + s (atan c + vh + vl) + tail. K + s atan c = k0 + e0 exactly (K is 0 or above
  // pi/2 >= 2 atan c), before v is known; k0 + s vh = hi + e1 exactly too (k0 is 0 or above
  // 2^-6 > |vh|). The low parts, below 2^-20 hi, are summed in the order they come.
  F k0, e0, hi, e1;
  fast_two_sum(k_hi, s * atan_c_hi, k0, e0);
  fast_two_sum(k0, s * vh, hi, e1);
  const F lo_first = (k_lo + e0) + s * atan_c_lo;
  const F err = hi * kFastError;
  const F lo_last = (e1 + tail) + rest * (s * r);  // e1 + s vl + tail
  // The true value lies within err of hi + lo_first + lo_last: if both ends round alike, so
  // does it (the roundings of each end move it by under 2^-71 hi).
  other = hi + ((lo_first - err) + lo_last);
  return hi + ((lo_first + err) + lo_last);
}

}  // namespace simit::math::detail
