// Small dense linear algebra on runtime tensors (plain loops in the order docs/arithmetic.md
// states): blocked/unblocked conversion, products, transpose, determinants, inverses and
// dense solves. Every function throws Fault for a run-time condition (singular matrix,
// mismatched shapes).
#pragma once

#include "runtime/tensor.h"

namespace simit::runtime {

// The logical unblocked form of a tensor whose levels all have the same order: component
// (i, j) of a matrix of r x c blocks is entry (i / r, j / c) of block (i % r, j % c).
// Unblocked tensors are returned unchanged.
Tensor unblock(const Tensor& t);
// The inverse of unblock: `logical` laid out with the blocking of `blocked`.
Tensor reblock(const Tensor& logical, const Shape& blocked);

// Products of unblocked operands (Int, Float or Complex components of one kind): (m x k)(k x n)
// -> m x n, (m x n)(n) -> m, (m)(m x n) -> n and the outer product (m)(n) -> m x n. float32:
// each product and addition of a sum rounded to binary32 (runtime/sum_rounding.h).
Tensor matrix_product(const Tensor& a, const Tensor& b, bool float32 = false);
Tensor matrix_vector_product(const Tensor& a, const Tensor& x, bool float32 = false);
Tensor vector_matrix_product(const Tensor& x, const Tensor& a, bool float32 = false);
Tensor outer_product(const Tensor& u, const Tensor& v);
// Sum over all components of u_i * v_i (same size, any shape); a 1-component tensor. A
// blocked u sums each outermost block first, then the block sums left to right
// (docs/arithmetic.md): the order of dense vectors.
Tensor inner_product(const Tensor& u, const Tensor& v, bool float32 = false);
// The same for global vectors (whose outer dimension is a set): each outermost block summed
// first, then the block sums in the blocked order of runtime/blocked_sum.h.
Tensor set_inner_product(const Tensor& u, const Tensor& v);
// The components of each outermost block of a tensor of this shape (1 when unblocked): the
// group an inner product sums before adding it to the total.
size_t inner_product_group(const Shape& s);
// sum over k < n of x[k] y[k]: each run of `group` components summed from +0.0, the run sums
// added in order from +0.0. With group 1 this is the plain left-to-right sum. For dense
// vectors only: a reduction over a set is runtime::blocked_dot's.
double grouped_dot(const double* x, const double* y, size_t n, size_t group, bool float32 = false);

// Swaps the two dimensions of a matrix, and of each of its blocks.
Tensor transpose(const Tensor& m);

// Determinant and inverse of an n x n float matrix, n in {2, 3, 4}.
double determinant(const Tensor& m);
// Throws Fault when the matrix is singular (zero determinant).
Tensor inverse(const Tensor& m);

// Solution x of A x = b for a square unblocked Float or Complex matrix; Fault if singular.
Tensor solve(const Tensor& a, const Tensor& b);
// Forward substitution with the lower triangle of square A (diagonal included).
Tensor lower_triangular_solve(const Tensor& a, const Tensor& b);

// Rounds every float (and complex part) to the nearest binary32 value.
void round_to_float32(Tensor& t);
// True when every float (and complex part) is finite.
bool all_finite(const Tensor& t);

}  // namespace simit::runtime
