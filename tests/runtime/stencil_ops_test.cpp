// Matrix operations on stencil patterns whose offsets wrap to one point (LANGUAGE.md §8.7): the
// blocks for offsets (0, 1) and (0, -1) on an axis of extent 2 lie in one column and every
// operation must read their sum. Expected matrices are built from the grid's geometry by hand.
#include <gtest/gtest.h>

#include <vector>

#include "runtime/sparse_convert.h"
#include "runtime/system_ops.h"

namespace simit::runtime {
namespace {

// A 3 x 2 periodic grid: point c0 + 3 c1. Offset (0, +-1) flips c1; offset (1, 0) moves c0.
int flip_axis1(int p) { return (p + 3) % 6; }
int next_axis0(int p) { return (p % 3 + 1) % 3 + 3 * (p / 3); }

class WrappedStencils : public ::testing::Test {
 protected:
  WrappedStencils() : grid("links", points, {3, 2}) {}

  // A: 1 on the diagonal, 2 at offset (0, 1), 5 at offset (0, -1) (one column: 7).
  SystemMatrix matrix_a(ComponentKind kind = ComponentKind::Float) {
    PatternPtr p = registry.stencil(grid, {{0, 0}, {0, 1}, {0, -1}});
    SystemMatrix m(p, 1, 1, kind);
    for (int pt = 0; pt < 6; ++pt) put(m, p->row_ptr()[pt], {1, 2, 5});
    return m;
  }
  // B: 0.5 (int: 3) on the diagonal and 3 at offset (1, 0).
  SystemMatrix matrix_b(ComponentKind kind = ComponentKind::Float) {
    PatternPtr p = registry.stencil(grid, {{0, 0}, {1, 0}});
    SystemMatrix m(p, 1, 1, kind);
    for (int pt = 0; pt < 6; ++pt)
      put(m, p->row_ptr()[pt], {kind == ComponentKind::Int ? 3 : 0.5, 3});
    return m;
  }
  static void put(SystemMatrix& m, int32_t first, std::vector<double> values) {
    for (size_t j = 0; j < values.size(); ++j) {
      if (m.is_float())
        m.values()[first + j] = values[j];
      else
        m.ints()[first + j] = static_cast<int32_t>(values[j]);
    }
  }
  // a A + b B as a dense matrix, from the geometry.
  static Eigen::MatrixXd dense(double a, double b, double b_diag = 0.5) {
    Eigen::MatrixXd d = Eigen::MatrixXd::Zero(6, 6);
    for (int p = 0; p < 6; ++p) {
      d(p, p) += a * 1.0 + b * b_diag;
      d(p, flip_axis1(p)) += a * 7.0;
      d(p, next_axis0(p)) += b * 3.0;
    }
    return d;
  }
  static Eigen::MatrixXd int_dense(const SystemMatrix& m) {
    Eigen::MatrixXd d(6, 6);
    for (int i = 0; i < 6; ++i)
      for (int j = 0; j < 6; ++j) d(i, j) = m.component_as<int32_t>(i, j);
    return d;
  }

  Set points{"points"};
  Set grid;
  PatternRegistry registry;
};

TEST_F(WrappedStencils, OneMatrixReadsTheSumOfItsWrappedOffsets) {
  EXPECT_FALSE(matrix_a().pattern().canonical());
  EXPECT_EQ(to_dense(matrix_a()), dense(1.0, 0.0));
  EXPECT_EQ(to_dense(matrix_b()), dense(0.0, 1.0));
}

TEST_F(WrappedStencils, SumsOfDifferentPatternsKeepEveryOffset) {
  const SystemMatrix a = matrix_a(), b = matrix_b();
  EXPECT_EQ(to_dense(add(a, b)), dense(1.0, 1.0));
  EXPECT_EQ(to_dense(add(b, a)), dense(1.0, 1.0));
  EXPECT_EQ(to_dense(add(a, b, 1.0, 1.0, &registry)), dense(1.0, 1.0));
  EXPECT_EQ(to_dense(add(a, b, 1.0, -1.0, &registry)), dense(1.0, -1.0));
  EXPECT_EQ(to_dense(add(b, a, 2.0, -3.0, &registry)), dense(-3.0, 2.0));
  EXPECT_TRUE(add(a, b, 1.0, 1.0, &registry).pattern().canonical());
  // (A + B) x = A x + B x; row 0 reads x0, x3 (7 x 4) and x1 (3 x 2): 1.5 + 28 + 6.
  const std::vector<double> x = {1, 2, 3, 4, 5, 6};
  std::vector<double> y(6);
  multiply(add(a, b, 1.0, 1.0, &registry), x, y);
  EXPECT_EQ(y[0], 35.5);
  for (int p = 0; p < 6; ++p)
    EXPECT_EQ(y[p], 1.5 * x[p] + 7.0 * x[flip_axis1(p)] + 3.0 * x[next_axis0(p)]) << p;
}

TEST_F(WrappedStencils, SumsOnOnePatternAndOfIntMatrices) {
  const SystemMatrix a = matrix_a();
  EXPECT_EQ(to_dense(add(a, a, 1.0, 2.0, &registry)), dense(3.0, 0.0));
  const SystemMatrix ai = matrix_a(ComponentKind::Int), bi = matrix_b(ComponentKind::Int);
  EXPECT_EQ(int_dense(add(ai, bi, 1.0, 1.0, &registry)), dense(1.0, 1.0, 3.0));
  EXPECT_EQ(int_dense(add(ai, bi, 1.0, -1.0, &registry)), dense(1.0, -1.0, 3.0));
}

TEST_F(WrappedStencils, ElementwiseProductsMultiplyTheSums) {
  const SystemMatrix a = matrix_a(), b = matrix_b();
  // A .* A: 1 on the diagonal, 7 * 7 = 49 at the flipped point (not 2 * 2 + 5 * 5 = 29).
  Eigen::MatrixXd aa = Eigen::MatrixXd::Zero(6, 6);
  for (int p = 0; p < 6; ++p) {
    aa(p, p) = 1.0;
    aa(p, flip_axis1(p)) = 49.0;
  }
  EXPECT_EQ(to_dense(multiply_elementwise(a, a, &registry)), aa);
  EXPECT_EQ(to_dense(multiply_elementwise(a, a)), aa);
  // A .* B: only the diagonals meet.
  EXPECT_EQ(to_dense(multiply_elementwise(a, b, &registry)),
            Eigen::MatrixXd(0.5 * Eigen::MatrixXd::Identity(6, 6)));
  const SystemMatrix ai = matrix_a(ComponentKind::Int);
  EXPECT_EQ(int_dense(multiply_elementwise(ai, ai, &registry)), aa);
}

TEST_F(WrappedStencils, IntDivisionTruncatesTheSum) {
  // 1 at offset (0, 1) and 1 at (0, -1): (1 + 1) / 2 = 1, where 1 / 2 + 1 / 2 would be 0.
  PatternPtr p = registry.stencil(grid, {{0, 1}, {0, -1}});
  SystemMatrix m(p, 1, 1, ComponentKind::Int);
  for (size_t i = 0; i < m.value_count(); ++i) m.ints()[i] = 1;
  const SystemMatrix half = divided(m, 2.0);
  for (int pt = 0; pt < 6; ++pt)
    for (int q = 0; q < 6; ++q)
      EXPECT_EQ(half.component_as<int32_t>(pt, q), q == flip_axis1(pt) ? 1 : 0) << pt << "," << q;
  // -3 / 2 truncates to -1 (not -1 + -1 from -1 / 2 + -2 / 2 = 0 + -1).
  for (int pt = 0; pt < 6; ++pt) {
    m.ints()[p->row_ptr()[pt]] = -1;
    m.ints()[p->row_ptr()[pt] + 1] = -2;
  }
  EXPECT_EQ(divided(m, 2.0).component_as<int32_t>(0, 3), -1);
  EXPECT_EQ(divided(m, -1.0).component_as<int32_t>(0, 3), 3);
}

TEST_F(WrappedStencils, TransposesAndProductsKeepEveryOffset) {
  const SystemMatrix a = matrix_a(), b = matrix_b();
  const Eigen::MatrixXd da = dense(1.0, 0.0), db = dense(0.0, 1.0);
  EXPECT_EQ(to_dense(transposed(a, &registry)), Eigen::MatrixXd(da.transpose()));
  const std::vector<double> x = {1, 2, 3, 4, 5, 6};
  std::vector<double> y(6);
  multiply_transposed(a, x, y);
  for (int p = 0; p < 6; ++p) EXPECT_EQ(y[p], x[p] + 7.0 * x[flip_axis1(p)]) << p;
  EXPECT_EQ(to_dense(multiply(a, b)), Eigen::MatrixXd(da * db));
  EXPECT_EQ(to_dense(multiply(a, a)), Eigen::MatrixXd(da * da));
  EXPECT_EQ(to_dense(scaled(-2.0, a)), Eigen::MatrixXd(-2.0 * da));
  EXPECT_EQ(to_dense(divided(a, 4.0)), Eigen::MatrixXd(da / 4.0));
}

}  // namespace
}  // namespace simit::runtime
