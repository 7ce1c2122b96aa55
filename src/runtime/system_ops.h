// Linear algebra on system matrices and global vectors: products, sums, scaling, reductions.
// Global vectors are flat double arrays, one block per element; a blocked vector and its
// unblocked form share this layout, so every vector operation serves both.
#pragma once

#include <cstdint>
#include <functional>
#include <span>
#include <vector>

#include "runtime/system_matrix.h"

namespace simit::runtime {

// y = A x, with x of A.scalar_cols() and y of A.scalar_rows() components. The vectors'
// component type must be the one storing A's (double for Float, int32 for Int, Complex for
// Complex; int arithmetic wraps). float32: each product and addition of a row's sum rounded
// to binary32 (runtime/sum_rounding.h).
void multiply(const SystemMatrix& a, std::span<const double> x, std::span<double> y,
              bool float32 = false);
void multiply(const SystemMatrix& a, std::span<const int32_t> x, std::span<int32_t> y);
void multiply(const SystemMatrix& a, std::span<const Complex> x, std::span<Complex> y,
              bool float32 = false);
// y = Aᵀ x, with x of A.scalar_rows() and y of A.scalar_cols() components.
void multiply_transposed(const SystemMatrix& a, std::span<const double> x, std::span<double> y,
                         bool float32 = false);
void multiply_transposed(const SystemMatrix& a, std::span<const int32_t> x, std::span<int32_t> y);
void multiply_transposed(const SystemMatrix& a, std::span<const Complex> x, std::span<Complex> y,
                         bool float32 = false);

// Matrices of any kind the SystemMatrix holds; operands of one operation share the kind,
// factors applied to int matrices must be integers and only complex matrices take complex
// factors (Fault otherwise). The transpose does not conjugate.

// alpha A + beta B over the union of the patterns (A's pattern itself when they share it).
// With a registry the union is built once per pair of patterns.
SystemMatrix add(const SystemMatrix& a, const SystemMatrix& b, double alpha = 1.0,
                 double beta = 1.0, PatternRegistry* registry = nullptr);
// B = alpha A + beta B in B's own storage, with add()'s bits, when every block of A lies in
// B's pattern (float matrices of one block shape, canonical patterns); returns false and
// leaves B alone otherwise. The JIT computes `A = M - s * K` so in the matrix K's map made.
// `for_each(tasks, task)`, when given, runs task(0 .. tasks-1) on the caller's threads (each
// task computes its own rows: the bits do not depend on how the tasks run).
// With `float32` (the --float32 mode), the bits of the interpreter's `A + beta * B` there:
// beta * B rounded to binary32, then the sum rounded (docs/arithmetic.md).
using ForEachTask = std::function<void(int64_t, const std::function<void(int64_t)>&)>;
bool add_into(const SystemMatrix& a, double alpha, SystemMatrix& b, double beta,
              const ForEachTask& for_each = {}, bool float32 = false);
// --float32: rounds every float component (and complex part) to the nearest binary32 value,
// and whether every one is one already (a NaN counts as one).
void round_to_float32(SystemMatrix& m);
bool is_binary32(const SystemMatrix& m);
inline bool is_binary32(double x) {
  return static_cast<double>(static_cast<float>(x)) == x || x != x;
}
bool is_binary32(std::span<const double> values);
// A .* B: component products over the union of the patterns.
SystemMatrix multiply_elementwise(const SystemMatrix& a, const SystemMatrix& b,
                                  PatternRegistry* registry = nullptr);
SystemMatrix scaled(double s, const SystemMatrix& a);  // same pattern
SystemMatrix scaled(Complex s, const SystemMatrix& a);
void scale(double s, SystemMatrix& a);
// Every component divided by s; int matrices divide by truncation and Fault on s = 0.
SystemMatrix divided(const SystemMatrix& a, double s);
SystemMatrix divided(const SystemMatrix& a, Complex s);
// Aᵀ: transposed pattern (cached with a registry) and transposed blocks.
SystemMatrix transposed(const SystemMatrix& a, PatternRegistry* registry = nullptr);
// The sparse product A B; its pattern is the product pattern, built on each call. float32:
// each product and addition rounded to binary32.
SystemMatrix multiply(const SystemMatrix& a, const SystemMatrix& b, bool float32 = false);

// Blocks that are themselves blocked (`tensor[V,V](tensor[3,3](tensor[2,2](float)))`): a
// matrix stores each block as its logical unblocked form (here 6 x 6, row-major), while a
// dense tensor of the block's shape stores it level by level. For each component of the
// logical form, row-major, the component of the level-by-level form it is.
std::vector<int32_t> nested_positions(const Shape& block);
// Rewrites every block of m from the level-by-level layout of `block` to the logical
// layout (nothing to do for an unblocked block shape).
void unnest_blocks(SystemMatrix& m, const Shape& block);

// Global vectors (all operands the same length).
void axpy(double alpha, std::span<const double> x, std::span<double> y);  // y += alpha x
void scale(double s, std::span<double> x);
void add(std::span<const double> x, std::span<const double> y, std::span<double> out);
void subtract(std::span<const double> x, std::span<const double> y, std::span<double> out);
void multiply_elementwise(std::span<const double> x, std::span<const double> y,
                          std::span<double> out);
void divide_elementwise(std::span<const double> x, std::span<const double> y,
                        std::span<double> out);
// Inner products sum each element's block of `group` components first, then the element
// sums in the blocked order of runtime/blocked_sum.h (docs/arithmetic.md).
double dot(std::span<const double> x, std::span<const double> y, size_t group = 1);
double norm(std::span<const double> x, size_t group = 1);  // Euclidean

}  // namespace simit::runtime
