// Building blocks of the project's transcendental functions: exact sums and products of two
// doubles (double-double arithmetic without FMA), bit access, and scaling by powers of two.
// Everything is + - * / and integer operations on the bits, so a GPU computes the same bits.
#pragma once

#include <bit>
#include <cstdint>

namespace simit::math::detail {

inline uint64_t bits_of(double x) { return std::bit_cast<uint64_t>(x); }
inline double from_bits(uint64_t b) { return std::bit_cast<double>(b); }

inline constexpr uint64_t kSignBit = 0x8000000000000000ull;
inline constexpr uint64_t kAbsMask = 0x7fffffffffffffffull;
inline constexpr uint64_t kInfBits = 0x7ff0000000000000ull;

inline double abs_of(double x) { return from_bits(bits_of(x) & kAbsMask); }
inline bool is_nan(double x) { return (bits_of(x) & kAbsMask) > kInfBits; }
inline bool sign_of(double x) { return (bits_of(x) >> 63) != 0; }
inline double with_sign(double x, bool negative) {
  return from_bits((bits_of(x) & kAbsMask) | (negative ? kSignBit : 0));
}
inline double infinity() { return from_bits(kInfBits); }
// A quiet NaN made by arithmetic, as an invalid operation makes it.
inline double nan_of(double x) { return (x - x) / (x - x); }

// 2^k for a normal power, -1022 <= k <= 1023.
inline double pow2(int k) { return from_bits(static_cast<uint64_t>(k + 1023) << 52); }

// x * 2^k, exact when the result is normal (each step multiplies by a normal power of two).
inline double scale(double x, int k) {
  while (k > 1000) {
    x *= pow2(1000);
    k -= 1000;
  }
  while (k < -1000) {
    x *= pow2(-1000);
    k += 1000;
  }
  return x * pow2(k);
}

// s + e == a + b exactly (Knuth's two-sum); F is double, or a vector of doubles lane by lane.
template <class F>
inline void two_sum(F a, F b, F& s, F& e) {
  s = a + b;
  const F bb = s - a;
  e = (a - (s - bb)) + (b - bb);
}

// s + e == a + b exactly, when |a| >= |b| or a == 0 (Dekker's fast two-sum).
template <class F>
inline void fast_two_sum(F a, F b, F& s, F& e) {
  s = a + b;
  e = b - (s - a);
}

// a == hi + lo with each half of 26 bits or fewer (Veltkamp), for |a| < 2^995.
template <class F>
inline void split(F a, F& hi, F& lo) {
  const F t = 134217729.0 * a;  // 2^27 + 1
  hi = t - (t - a);
  lo = a - hi;
}

// p + e == a * b exactly (Dekker's product; no FMA), when nothing overflows or underflows.
template <class F>
inline void two_prod(F a, F b, F& p, F& e) {
  p = a * b;
  F ah, al, bh, bl;
  split(a, ah, al);
  split(b, bh, bl);
  e = ((ah * bh - p) + ah * bl + al * bh) + al * bl;
}

// A double-double: an unevaluated sum hi + lo with |lo| <= ulp(hi) (about 106 bits).
struct DD {
  double hi, lo;
};

// (a.hi + a.lo) * (b.hi + b.lo), with relative error near 2^-104.
inline DD mul(DD a, DD b) {
  double p, e;
  two_prod(a.hi, b.hi, p, e);
  e += a.hi * b.lo + a.lo * b.hi;
  DD r;
  fast_two_sum(p, e, r.hi, r.lo);
  return r;
}

// (a.hi + a.lo) * b.
inline DD mul(DD a, double b) {
  double p, e;
  two_prod(a.hi, b, p, e);
  e += a.lo * b;
  DD r;
  fast_two_sum(p, e, r.hi, r.lo);
  return r;
}

// (a.hi + a.lo) + (b.hi + b.lo).
inline DD add(DD a, DD b) {
  double s, e;
  two_sum(a.hi, b.hi, s, e);
  e += a.lo + b.lo;
  DD r;
  fast_two_sum(s, e, r.hi, r.lo);
  return r;
}

// (a.hi + a.lo) / (b.hi + b.lo), with relative error near 2^-104 (b != 0).
inline DD div(DD a, DD b) {
  const double q = a.hi / b.hi;
  double p, e;
  two_prod(q, b.hi, p, e);
  // a - q*b, in which a.hi - p cancels exactly.
  const double rest = (((a.hi - p) - e) + a.lo) - q * b.lo;
  DD r;
  fast_two_sum(q, rest / b.hi, r.hi, r.lo);
  return r;
}

}  // namespace simit::math::detail
