// Sparse solvers on system matrices (LANGUAGE.md §9.5): Cholesky through CHOLMOD, LU through
// Eigen's SparseLU, forward substitution, and the general solve behind `A \ b`. Factors are
// reusable for any number of right-hand sides; a failed factorisation throws Fault.
#pragma once

#include <memory>
#include <span>
#include <vector>

#include "runtime/system_matrix.h"

namespace simit::runtime {

// L Lᵀ = A for a symmetric positive definite A (only its upper triangle is read).
class CholeskyFactor {
 public:
  explicit CholeskyFactor(const SystemMatrix& a);
  CholeskyFactor(CholeskyFactor&&) noexcept;
  CholeskyFactor& operator=(CholeskyFactor&&) noexcept;
  ~CholeskyFactor();

  // Factors a new matrix; one with the previous pattern and block size reuses the ordering
  // and symbolic analysis.
  void refactor(const SystemMatrix& a);
  int64_t size() const;  // scalar rows
  // x = A⁻¹ b (x may alias b). Not thread-safe: the factor keeps solve workspace.
  void solve(std::span<const double> b, std::span<double> x) const;
  std::vector<double> solve(std::span<const double> b) const;
  // X = A⁻¹ B for a sparse right-hand side; X is unblocked, its pattern the nonzeros of X.
  SystemMatrix solve(const SystemMatrix& b) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// P A Q = L U for a square non-singular A.
class LuFactor {
 public:
  explicit LuFactor(const SystemMatrix& a);
  LuFactor(LuFactor&&) noexcept;
  LuFactor& operator=(LuFactor&&) noexcept;
  ~LuFactor();

  void refactor(const SystemMatrix& a);  // reuses the analysis for the same pattern
  int64_t size() const;
  void solve(std::span<const double> b, std::span<double> x) const;
  std::vector<double> solve(std::span<const double> b) const;
  SystemMatrix solve(const SystemMatrix& b) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Forward substitution with the lower triangle of square A, diagonal included, strict upper
// part ignored (`triangularSolve`). A zero on the diagonal throws Fault.
void lower_triangular_solve(const SystemMatrix& a, std::span<const double> b, std::span<double> x);

// `A \ b`: Cholesky when A is exactly symmetric and positive definite, LU otherwise.
std::vector<double> solve(const SystemMatrix& a, std::span<const double> b);

// True when A equals its transpose exactly (pattern positions compared by value).
bool is_symmetric(const SystemMatrix& a);

}  // namespace simit::runtime
