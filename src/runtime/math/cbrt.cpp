// cbrt (docs/math.md): x = 2^(3q) u with u in [1, 8); a polynomial guess of cbrt u, two Newton
// steps in double, and a last one whose residual u - y^3 is computed exactly, so the result is
// y + (u - y^3)/(3 y^2) rounded once: correctly rounded but for a relative 2^-100.
#include "runtime/math/dd.h"
#include "runtime/math/math_functions.h"
#include "runtime/math/tables.h"

namespace simit::math {

double cbrt(double x) {
  using namespace detail;
  namespace tb = tables;
  if (x == 0.0 || abs_of(x) == infinity()) return x;  // keeps the sign of a zero
  if (is_nan(x)) return x + x;
  const bool negative = sign_of(x);
  double ax = abs_of(x);
  int e = 0;
  if (bits_of(ax) < (uint64_t{1} << 52)) {  // subnormal: scale into the normal range
    ax *= pow2(54);
    e = -54;
  }
  const uint64_t ix = bits_of(ax);
  e += static_cast<int>(ix >> 52) - 1023;
  // e = 3q + rho with 0 <= rho < 3 (q rounded toward minus infinity).
  const int q = e >= 0 ? e / 3 : -((2 - e) / 3);
  const int rho = e - 3 * q;
  const double m = from_bits((ix & ((uint64_t{1} << 52) - 1)) | (uint64_t{1023} << 52));
  const double u = m * pow2(rho);
  const double* g = tb::kCbrtGuess;
  double y = (((g[0] * m + g[1]) * m + g[2]) * m + g[3]) * tb::kCbrtTwo[rho];  // ~2^-13
  for (int step = 0; step < 2; ++step) y -= (y * y * y - u) / (3.0 * y * y);   // ~2^-26, 2^-52
  double p, pe, c, ce;
  two_prod(y, y, p, pe);
  two_prod(p, y, c, ce);
  ce += pe * y;                   // y^3 = c + ce to about 2^-104
  const double r = (u - c) - ce;  // u - c is exact: c is within 2^-50 of u
  y += r / (3.0 * y * y);
  return with_sign(y * pow2(q), negative);
}

}  // namespace simit::math

// The C names (math_functions.h), here beside the functions so that the object that
// defines a function the interpreter calls also defines the name compiled code links to.
extern "C" {
double simit_math_cbrt(double x) { return simit::math::cbrt(x); }
}
