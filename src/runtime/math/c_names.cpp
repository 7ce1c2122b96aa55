// The extern "C" names of the project's transcendental functions (math_functions.h), which
// compiled kernels call by symbol.
#include "runtime/math/math_functions.h"

extern "C" {
double simit_math_exp(double x) { return simit::math::exp(x); }
double simit_math_log(double x) { return simit::math::log(x); }
double simit_math_pow(double x, double y) { return simit::math::pow(x, y); }
double simit_math_sin(double x) { return simit::math::sin(x); }
double simit_math_cos(double x) { return simit::math::cos(x); }
double simit_math_tan(double x) { return simit::math::tan(x); }
double simit_math_asin(double x) { return simit::math::asin(x); }
double simit_math_acos(double x) { return simit::math::acos(x); }
double simit_math_atan2(double y, double x) { return simit::math::atan2(y, x); }
double simit_math_cbrt(double x) { return simit::math::cbrt(x); }
}
