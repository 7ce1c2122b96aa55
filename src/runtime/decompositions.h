// Small dense decompositions behind the intrinsics svd, eig, polar, project_spd and
// project_spd_abs (docs/intrinsics.md): Jacobi methods as plain loops, so that every target
// gives the same bits (docs/arithmetic.md). Inputs are unblocked n x n float matrices, except
// project_spd's, which may be blocked with square blocks.
#pragma once

#include "runtime/tensor.h"

namespace simit::runtime {

// A = U diag(s) V' with U and V proper rotations (det +1) and s = (s_0 >= ... >= s_{n-1}):
// all non-negative except s_{n-1}, which is negative when det A < 0. n is 2 or 3.
struct RotationSvd {
  Tensor u, s, v;
};
RotationSvd rotation_svd(const Tensor& a);

// A Q = Q diag(w) for symmetric A: w ascending, Q orthonormal with each column's
// largest-magnitude component positive. Throws Fault when A is not symmetric within
// `symmetry_tolerance` (relative to its largest component); the symmetric part
// (A + A') / 2 is what is decomposed.
struct SymmetricEig {
  Tensor w, q;
};
SymmetricEig symmetric_eig(const Tensor& a, double symmetry_tolerance);

// F = R S with R a proper rotation and S symmetric (R = U V', S = V diag(s) V' from
// rotation_svd): S has a negative eigenvalue exactly when det F < 0. n is 2 or 3.
struct PolarDecomposition {
  Tensor r, s;
};
PolarDecomposition polar_decomposition(const Tensor& f);

// The nearest positive semi-definite matrix (Clamp: negative eigenvalues set to 0), or the
// matrix with every eigenvalue replaced by its absolute value (Absolute). A matrix that is
// already positive semi-definite (no eigenvalue below -4 n epsilon max |w|) comes back as its
// symmetric part (the same bits when it is exactly symmetric). Blocked matrices are
// decomposed in their logical form.
enum class SpdProjection { Clamp, Absolute };
Tensor project_spd(const Tensor& a, SpdProjection mode, double symmetry_tolerance);

}  // namespace simit::runtime
