// Conversions of system matrices to Eigen's scalar forms, for solvers, tests and debugging.
#pragma once

#include <Eigen/Dense>
#include <Eigen/SparseCore>

#include "runtime/system_matrix.h"

namespace simit::runtime {

using EigenSparse = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;

// The logical unblocked matrix (of a float matrix) in compressed column form: rows ascending within
// each column, every pattern position kept (explicit zeros included), repeated stencil entries
// summed.
EigenSparse to_eigen(const SystemMatrix& a);
// The logical unblocked matrix as a dense matrix (small matrices only).
Eigen::MatrixXd to_dense(const SystemMatrix& a);

}  // namespace simit::runtime
