// The decompositions behind svd, eig, polar and project_spd on degenerate and random
// inputs: orthogonality, proper rotations, reconstruction to 1e-12, ordering, and values
// against Eigen's own solvers (an independent implementation).
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "runtime/decompositions.h"
#include "runtime/dense_linalg.h"
#include "runtime/fault.h"

namespace simit::runtime {
namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;

Tensor tensor_of(const MatrixXd& m) {
  Tensor t(ComponentKind::Float, Shape{static_cast<int>(m.rows()), static_cast<int>(m.cols())});
  for (int i = 0; i < m.rows(); ++i)
    for (int j = 0; j < m.cols(); ++j) t.mutable_floats()[i * m.cols() + j] = m(i, j);
  return t;
}

MatrixXd matrix_of(const Tensor& t) {
  const int r = t.shape().dim(0), c = t.shape().dim(1);
  MatrixXd m(r, c);
  for (int i = 0; i < r; ++i)
    for (int j = 0; j < c; ++j) m(i, j) = t.floats()[i * c + j];
  return m;
}

VectorXd vector_of(const Tensor& t) {
  VectorXd v(t.size());
  for (size_t i = 0; i < t.size(); ++i) v(static_cast<int>(i)) = t.floats()[i];
  return v;
}

double max_abs(const MatrixXd& m) { return m.cwiseAbs().maxCoeff(); }

// Orthonormal columns to 1e-14: Q'Q = I.
void expect_orthonormal(const MatrixXd& q, const char* what) {
  const int n = static_cast<int>(q.rows());
  EXPECT_LE(max_abs(q.transpose() * q - MatrixXd::Identity(n, n)), 1e-14) << what << "\n" << q;
}

void expect_rotation(const MatrixXd& q, const char* what) {
  expect_orthonormal(q, what);
  EXPECT_NEAR(q.determinant(), 1.0, 1e-14) << what;
}

// Everything the rotation SVD promises, for one matrix.
void check_svd(const MatrixXd& a) {
  SCOPED_TRACE(::testing::Message() << "A =\n" << a);
  const int n = static_cast<int>(a.rows());
  RotationSvd d = rotation_svd(tensor_of(a));
  const MatrixXd u = matrix_of(d.u), v = matrix_of(d.v);
  const VectorXd s = vector_of(d.s);
  ASSERT_EQ(s.size(), n);
  expect_rotation(u, "U");
  expect_rotation(v, "V");
  const double scale = std::max(max_abs(a), std::numeric_limits<double>::min());
  EXPECT_LE(max_abs(u * s.asDiagonal() * v.transpose() - a), 1e-12 * scale);
  for (int k = 0; k + 1 < n; ++k) {
    EXPECT_GE(s(k), 0.0);
    EXPECT_GE(s(k), std::fabs(s(k + 1)));
  }
  // The sign of the last singular value is that of the determinant.
  const double det = a.determinant();
  if (std::fabs(det) > 1e-10 * std::pow(scale, n)) {
    EXPECT_EQ(s(n - 1) < 0, det < 0);
  }
  // Magnitudes against Eigen's JacobiSVD.
  VectorXd ref = Eigen::JacobiSVD<MatrixXd>(a).singularValues();
  EXPECT_LE((s.cwiseAbs() - ref).cwiseAbs().maxCoeff(), 1e-13 * scale) << s << "\nvs\n" << ref;
}

MatrixXd mat(int n, std::initializer_list<double> rows) {
  MatrixXd m(n, n);
  auto it = rows.begin();
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) m(i, j) = *it++;
  return m;
}

MatrixXd rotation3(double ax, double ay, double az) {
  return (Eigen::AngleAxisd(az, Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(ay, Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(ax, Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

MatrixXd random_matrix(std::mt19937& g, int n, double lo = -1.0, double hi = 1.0) {
  std::uniform_real_distribution<double> u(lo, hi);
  MatrixXd m(n, n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) m(i, j) = u(g);
  return m;
}

TEST(RotationSvd, DegenerateThreeByThree) {
  const MatrixXd r = rotation3(0.3, -1.1, 2.0), q = rotation3(-0.7, 0.4, 0.9);
  const std::vector<MatrixXd> cases = {
      MatrixXd::Identity(3, 3),
      MatrixXd::Zero(3, 3),
      mat(3, {3, 0, 0, 0, -2, 0, 0, 0, 5}),          // diagonal, unsorted, one negative
      mat(3, {1, 0, 0, 0, 1, 0, 0, 0, -1}),          // a reflection
      -MatrixXd::Identity(3, 3),                     // det -1, all repeated
      mat(3, {1, 2, 3, 2, 4, 6, 3, 6, 9}),           // rank 1
      mat(3, {1, 2, 3, 4, 5, 6, 7, 8, 9}),           // rank 2
      mat(3, {0, 0, 0, 0, 0, 0, 0, 0, 1e-300}),      // rank 1, tiny
      r,                                             // all singular values 1
      r * mat(3, {2, 0, 0, 0, 2, 0, 0, 0, 1}) * q,   // repeated largest
      r * mat(3, {3, 0, 0, 0, 1, 0, 0, 0, 1}) * q,   // repeated smallest
      r * mat(3, {1, 0, 0, 0, 1, 0, 0, 0, -1}) * q,  // a rotated reflection
      r * mat(3, {1, 0, 0, 0, 1e-9, 0, 0, 0, 0}) * q,
      r * mat(3, {1, 0, 0, 0, 1 + 1e-12, 0, 0, 0, 1e-14}) * q,
      1e200 * r * mat(3, {3, 0, 0, 0, 2, 0, 0, 0, -1}) * q,  // squares would overflow
      1e-200 * r * mat(3, {3, 0, 0, 0, 2, 0, 0, 0, -1}) * q,
  };
  for (const MatrixXd& a : cases) check_svd(a);
}

TEST(RotationSvd, DegenerateTwoByTwo) {
  const Eigen::Rotation2Dd r(0.8), q(-2.1);
  const MatrixXd rm = r.toRotationMatrix(), qm = q.toRotationMatrix();
  const std::vector<MatrixXd> cases = {
      MatrixXd::Identity(2, 2),
      MatrixXd::Zero(2, 2),
      mat(2, {1, 0, 0, -1}),
      mat(2, {-3, 0, 0, -3}),
      mat(2, {1, 2, 2, 4}),
      mat(2, {0, 1, 0, 0}),
      rm,
      rm * mat(2, {2, 0, 0, -1e-13}) * qm,
      mat(2, {0, 1, 1, 0}),  // a reflection across the diagonal
  };
  for (const MatrixXd& a : cases) check_svd(a);
}

TEST(RotationSvd, RandomMatricesBothSigns) {
  std::mt19937 g(12345);
  int negative = 0;
  for (int trial = 0; trial < 500; ++trial) {
    const int n = 2 + trial % 2;
    const MatrixXd a = random_matrix(g, n);
    negative += a.determinant() < 0;
    check_svd(a);
  }
  EXPECT_GT(negative, 100);  // reflections are well represented
}

TEST(RotationSvd, KnownValuesOfADiagonalReflection) {
  RotationSvd d = rotation_svd(tensor_of(mat(3, {3, 0, 0, 0, -2, 0, 0, 0, 5})));
  const VectorXd s = vector_of(d.s);
  EXPECT_DOUBLE_EQ(s(0), 5.0);
  EXPECT_DOUBLE_EQ(s(1), 3.0);
  EXPECT_DOUBLE_EQ(s(2), -2.0);
}

TEST(RotationSvd, NonFiniteInputGivesNaN) {
  MatrixXd a = MatrixXd::Identity(3, 3);
  a(1, 2) = std::numeric_limits<double>::quiet_NaN();
  RotationSvd d = rotation_svd(tensor_of(a));
  for (const Tensor* t : {&d.u, &d.s, &d.v})
    for (size_t i = 0; i < t->size(); ++i) EXPECT_TRUE(std::isnan(t->floats()[i]));
}

TEST(RotationSvd, RejectsOtherShapes) {
  try {
    rotation_svd(tensor_of(MatrixXd::Identity(4, 4)));
    FAIL() << "no fault";
  } catch (const Fault& f) {
    EXPECT_STREQ(f.what(), "svd needs a 2x2 or 3x3 matrix, not 4x4");
  }
  EXPECT_THROW(rotation_svd(Tensor(ComponentKind::Float, Shape{2, 3})), Fault);
}

// Everything eig promises, for one symmetric matrix.
void check_eig(const MatrixXd& a) {
  SCOPED_TRACE(::testing::Message() << "A =\n" << a);
  const int n = static_cast<int>(a.rows());
  SymmetricEig d = symmetric_eig(tensor_of(a), 1e-8);
  const MatrixXd q = matrix_of(d.q);
  const VectorXd w = vector_of(d.w);
  expect_orthonormal(q, "Q");
  const double scale = std::max(max_abs(a), std::numeric_limits<double>::min());
  EXPECT_LE(max_abs(a * q - q * w.asDiagonal()), 1e-12 * scale);
  EXPECT_LE(max_abs(q * w.asDiagonal() * q.transpose() - a), 1e-12 * scale);
  for (int k = 0; k + 1 < n; ++k) EXPECT_LE(w(k), w(k + 1));
  // Each column's largest-magnitude component is positive.
  for (int k = 0; k < n; ++k) {
    int big = 0;
    for (int i = 1; i < n; ++i)
      if (std::fabs(q(i, k)) > std::fabs(q(big, k))) big = i;
    EXPECT_GT(q(big, k), 0.0) << "column " << k;
  }
  VectorXd ref = Eigen::SelfAdjointEigenSolver<MatrixXd>(a).eigenvalues();
  EXPECT_LE((w - ref).cwiseAbs().maxCoeff(), 1e-13 * scale) << w << "\nvs\n" << ref;
}

TEST(SymmetricEig, DegenerateMatrices) {
  const MatrixXd r = rotation3(0.3, -1.1, 2.0);
  const std::vector<MatrixXd> cases = {
      MatrixXd::Identity(3, 3),
      MatrixXd::Zero(3, 3),
      MatrixXd::Identity(1, 1) * -4.0,
      mat(3, {3, 0, 0, 0, -2, 0, 0, 0, 5}),
      mat(2, {0, 1, 1, 0}),
      mat(2, {1, 1e-20, 1e-20, 1}),
      mat(3, {1, 2, 3, 2, 4, 6, 3, 6, 9}),  // rank 1
      r * mat(3, {2, 0, 0, 0, 2, 0, 0, 0, -1}) * r.transpose(),
      r * mat(3, {1, 0, 0, 0, 1 + 1e-13, 0, 0, 0, 1 - 1e-13}) * r.transpose(),
      1e250 * r * mat(3, {3, 0, 0, 0, 2, 0, 0, 0, -1}) * r.transpose(),
      1e-250 * r * mat(3, {3, 0, 0, 0, 2, 0, 0, 0, -1}) * r.transpose(),
  };
  for (const MatrixXd& a : cases) check_eig(a);
}

TEST(SymmetricEig, RandomSymmetricMatricesUpToTwelve) {
  std::mt19937 g(777);
  for (int n : {1, 2, 3, 4, 6, 9, 12})
    for (int trial = 0; trial < 40; ++trial) {
      const MatrixXd b = random_matrix(g, n);
      check_eig(b + b.transpose());
    }
}

TEST(SymmetricEig, SortsDiagonalInputAscending) {
  SymmetricEig d = symmetric_eig(tensor_of(mat(3, {3, 0, 0, 0, -2, 0, 0, 0, 5})), 1e-8);
  const VectorXd w = vector_of(d.w);
  EXPECT_EQ(w(0), -2.0);
  EXPECT_EQ(w(1), 3.0);
  EXPECT_EQ(w(2), 5.0);
  EXPECT_EQ(matrix_of(d.q), mat(3, {0, 1, 0, 1, 0, 0, 0, 0, 1}));
}

TEST(SymmetricEig, NonSymmetricInputIsAFaultNamingTheComponents) {
  try {
    symmetric_eig(tensor_of(mat(3, {1, 0, 0, 0, 1, 2, 0, 3, 1})), 1e-8);
    FAIL() << "no fault";
  } catch (const Fault& f) {
    EXPECT_STREQ(f.what(),
                 "eig needs a symmetric matrix: component (1, 2) is 2 but component (2, 1) is 3");
  }
  // Rounding-sized asymmetry is accepted, and the symmetric part decomposed.
  MatrixXd a = mat(2, {2, 1, 1 + 1e-15, 2});
  SymmetricEig d = symmetric_eig(tensor_of(a), 1e-8);
  EXPECT_NEAR(vector_of(d.w)(0), 1.0, 1e-14);
}

TEST(Polar, RotationTimesSymmetric) {
  std::mt19937 g(99);
  std::vector<MatrixXd> cases = {
      MatrixXd::Identity(3, 3), mat(3, {1, 0, 0, 0, 1, 0, 0, 0, -1}), rotation3(0.1, 0.2, 0.3),
      mat(2, {0, -1, 1, 0}),    mat(3, {1, 2, 3, 4, 5, 6, 7, 8, 9}),  MatrixXd::Zero(2, 2)};
  for (int k = 0; k < 100; ++k) cases.push_back(random_matrix(g, 2 + k % 2));
  for (const MatrixXd& f : cases) {
    SCOPED_TRACE(::testing::Message() << "F =\n" << f);
    PolarDecomposition d = polar_decomposition(tensor_of(f));
    const MatrixXd r = matrix_of(d.r), s = matrix_of(d.s);
    expect_rotation(r, "R");
    EXPECT_EQ(s, s.transpose());  // to the bit
    EXPECT_LE(max_abs(r * s - f), 1e-12 * std::max(max_abs(f), 1e-300));
    // S has a negative eigenvalue exactly when det F < 0.
    const double det = f.determinant();
    const double smallest = Eigen::SelfAdjointEigenSolver<MatrixXd>(s).eigenvalues()(0);
    if (std::fabs(det) > 1e-9) {
      EXPECT_EQ(smallest < 0, det < 0);
    }
  }
}

TEST(Polar, ARotationIsItsOwnFactor) {
  const MatrixXd q = rotation3(0.5, -0.25, 1.5);
  PolarDecomposition d = polar_decomposition(tensor_of(q));
  EXPECT_LE(max_abs(matrix_of(d.r) - q), 1e-15);
  EXPECT_LE(max_abs(matrix_of(d.s) - MatrixXd::Identity(3, 3)), 1e-15);
}

MatrixXd projected(const MatrixXd& a, SpdProjection mode) {
  return matrix_of(project_spd(tensor_of(a), mode, 1e-8));
}

TEST(ProjectSpd, ClampsOrFlipsNegativeEigenvalues) {
  std::mt19937 g(4242);
  for (int n : {1, 2, 3, 6, 12})
    for (int trial = 0; trial < 30; ++trial) {
      const MatrixXd b = random_matrix(g, n);
      const MatrixXd a = b + b.transpose();
      Eigen::SelfAdjointEigenSolver<MatrixXd> es(a);
      const VectorXd w = es.eigenvalues();
      const MatrixXd clamp_ref =
          es.eigenvectors() * w.cwiseMax(0.0).asDiagonal() * es.eigenvectors().transpose();
      const MatrixXd abs_ref =
          es.eigenvectors() * w.cwiseAbs().asDiagonal() * es.eigenvectors().transpose();
      const MatrixXd c = projected(a, SpdProjection::Clamp);
      const MatrixXd f = projected(a, SpdProjection::Absolute);
      const double scale = max_abs(a);
      EXPECT_LE(max_abs(c - clamp_ref), 1e-12 * scale);
      EXPECT_LE(max_abs(f - abs_ref), 1e-12 * scale);
      EXPECT_EQ(c, c.transpose());
      EXPECT_EQ(f, f.transpose());
      EXPECT_GE(Eigen::SelfAdjointEigenSolver<MatrixXd>(c).eigenvalues()(0), -1e-12 * scale);
    }
}

TEST(ProjectSpd, PositiveSemiDefiniteInputComesBackUnchanged) {
  std::mt19937 g(5);
  for (int n : {2, 3, 12}) {
    const MatrixXd b = random_matrix(g, n);
    const MatrixXd m = b * b.transpose() + 0.1 * MatrixXd::Identity(n, n);
    const MatrixXd spd = 0.5 * (m + m.transpose());  // exactly symmetric
    EXPECT_EQ(projected(spd, SpdProjection::Clamp), spd);
    EXPECT_EQ(projected(spd, SpdProjection::Absolute), spd);
  }
  const MatrixXd semi = mat(2, {1, 1, 1, 1});  // eigenvalues 0 and 2
  EXPECT_EQ(projected(semi, SpdProjection::Clamp), semi);
  EXPECT_EQ(projected(MatrixXd::Zero(3, 3), SpdProjection::Clamp), MatrixXd::Zero(3, 3));
}

TEST(ProjectSpd, KnownTwoByTwo) {
  // [1 2; 2 1] has eigenvalues -1 and 3 with eigenvectors (1, -1) and (1, 1) / sqrt 2.
  const MatrixXd a = mat(2, {1, 2, 2, 1});
  EXPECT_LE(max_abs(projected(a, SpdProjection::Clamp) - mat(2, {1.5, 1.5, 1.5, 1.5})), 1e-15);
  EXPECT_LE(max_abs(projected(a, SpdProjection::Absolute) - mat(2, {2, 1, 1, 2})), 1e-15);
}

TEST(ProjectSpd, BlockedMatricesAreProjectedInLogicalForm) {
  std::mt19937 g(8);
  const MatrixXd b = random_matrix(g, 6);
  const MatrixXd a = b + b.transpose();
  const Shape blocked = Shape::blocked({2, 2}, Shape{3, 3});
  const Tensor t = reblock(tensor_of(a), blocked);
  const Tensor p = project_spd(t, SpdProjection::Clamp, 1e-8);
  EXPECT_EQ(p.shape(), blocked);
  EXPECT_EQ(matrix_of(unblock(p)), projected(a, SpdProjection::Clamp));
}

TEST(ProjectSpd, NonSymmetricInputIsAFault) {
  try {
    project_spd(tensor_of(mat(2, {1, 2, 0, 1})), SpdProjection::Absolute, 1e-8);
    FAIL() << "no fault";
  } catch (const Fault& f) {
    EXPECT_STREQ(f.what(),
                 "project_spd_abs needs a symmetric matrix: component (0, 1) is 2 but "
                 "component (1, 0) is 0");
  }
}

}  // namespace
}  // namespace simit::runtime
