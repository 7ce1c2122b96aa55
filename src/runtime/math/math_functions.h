// The project's own transcendental functions (docs/math.md): binary64 in, binary64 out, the
// same bits on every target, since they use only + - * / sqrt, comparisons and integer
// operations on the bits. Error below 1 ulp everywhere, and almost always correctly rounded.
// Special values as C99 Annex F says.
#pragma once

namespace simit::math {

double exp(double x);
double log(double x);
double pow(double x, double y);
double sin(double x);
double cos(double x);
double tan(double x);
double asin(double x);
double acos(double x);
double atan2(double y, double x);
double cbrt(double x);
// out[l] = atan2(y[l], x[l]) for l < 4, with atan2's bits, in SIMD lanes where it can.
void atan2_x4(const double* y, const double* x, double* out);
// out[l] = log(x[l]) for l < 4, with log's bits.
void log_x4(const double* x, double* out);

}  // namespace simit::math

// The same functions by plain names, for compiled code that calls them by symbol.
extern "C" {
double simit_math_exp(double x);
double simit_math_log(double x);
double simit_math_pow(double x, double y);
double simit_math_sin(double x);
double simit_math_cos(double x);
double simit_math_tan(double x);
double simit_math_asin(double x);
double simit_math_acos(double x);
double simit_math_atan2(double y, double x);
double simit_math_cbrt(double x);
void simit_math_atan2_x4(const double* y, const double* x, double* out);
void simit_math_log_x4(const double* x, double* out);
void simit_math_atan2_x8(const double* y, const double* x, double* out);
void simit_math_log_x8(const double* x, double* out);
}
