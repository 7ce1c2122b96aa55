// How the additions and products inside one operation's sums round (docs/arithmetic.md,
// "--float32"): kept in binary64, or each rounded to binary32 as a binary32 machine computes
// them. Integer sums wrap either way.
#pragma once

#include <complex>
#include <cstdint>

namespace simit::runtime {

// Sums in binary64: each addition and product as computed.
struct Binary64Sums {
  template <class T>
  static T r(T x) {
    return x;
  }
};

// Sums under --float32: each addition and product rounded to binary32 (with binary32
// operands, the binary32 operation's own result: docs/arithmetic.md).
struct Binary32Sums {
  static double r(double x) {
    float f = static_cast<float>(x);
    // The value passes through a register the compiler cannot see into: GCC 12 at -O3 kept a
    // vectorised row sum of SpMV in binary64, dropping this rounding after each addition
    // (found by the random programs against the JIT, which rounds each one).
#if defined(__x86_64__) || defined(__i386__)
    asm("" : "+x"(f));
#elif defined(__aarch64__)
    asm("" : "+w"(f));
#else
    volatile float v = f;
    f = v;
#endif
    return f;
  }
  static std::complex<double> r(std::complex<double> x) { return {r(x.real()), r(x.imag())}; }
  static uint32_t r(uint32_t x) { return x; }
  static int32_t r(int32_t x) { return x; }
};

// f(Binary32Sums{}) where float32, else f(Binary64Sums{}): one dispatch outside a loop.
template <class F>
decltype(auto) with_sums(bool float32, F&& f) {
  if (float32) return f(Binary32Sums{});
  return f(Binary64Sums{});
}

}  // namespace simit::runtime
