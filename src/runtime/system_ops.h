// Linear algebra on system matrices and global vectors: products, sums, scaling, reductions.
// Global vectors are flat double arrays, one block per element; a blocked vector and its
// unblocked form share this layout, so every vector operation serves both.
#pragma once

#include <span>

#include "runtime/system_matrix.h"

namespace simit::runtime {

// y = A x, with x of A.scalar_cols() and y of A.scalar_rows() components.
void multiply(const SystemMatrix& a, std::span<const double> x, std::span<double> y);
// y = Aᵀ x, with x of A.scalar_rows() and y of A.scalar_cols() components.
void multiply_transposed(const SystemMatrix& a, std::span<const double> x, std::span<double> y);

// alpha A + beta B over the union of the patterns (A's pattern itself when they share it).
// With a registry the union is built once per pair of patterns.
SystemMatrix add(const SystemMatrix& a, const SystemMatrix& b, double alpha = 1.0,
                 double beta = 1.0, PatternRegistry* registry = nullptr);
SystemMatrix scaled(double s, const SystemMatrix& a);  // same pattern
void scale(double s, SystemMatrix& a);
// Aᵀ: transposed pattern (cached with a registry) and transposed blocks.
SystemMatrix transposed(const SystemMatrix& a, PatternRegistry* registry = nullptr);
// The sparse product A B; its pattern is the product pattern, built on each call.
SystemMatrix multiply(const SystemMatrix& a, const SystemMatrix& b);

// Global vectors (all operands the same length).
void axpy(double alpha, std::span<const double> x, std::span<double> y);  // y += alpha x
void scale(double s, std::span<double> x);
void add(std::span<const double> x, std::span<const double> y, std::span<double> out);
void subtract(std::span<const double> x, std::span<const double> y, std::span<double> out);
void multiply_elementwise(std::span<const double> x, std::span<const double> y,
                          std::span<double> out);
void divide_elementwise(std::span<const double> x, std::span<const double> y,
                        std::span<double> out);
double dot(std::span<const double> x, std::span<const double> y);
double norm(std::span<const double> x);  // Euclidean

}  // namespace simit::runtime
