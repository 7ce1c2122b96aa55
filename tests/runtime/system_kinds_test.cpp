// Int, bool and complex system matrices and matrices whose blocks are blocked, against dense
// references and hand-worked values.
#include <gtest/gtest.h>

#include <cstdint>
#include <limits>

#include "runtime/solvers.h"
#include "runtime/sparse_convert.h"
#include "runtime/system_ops.h"
#include "runtime_fixtures.h"

namespace simit::runtime {
namespace {

using namespace simit::runtime::testing;

// A small integer for value slot i, so that float products of the values are exact.
int32_t small_int(size_t i, int salt) { return static_cast<int32_t>((i * 7 + salt) % 11) - 5; }

class IntMatrices : public ::testing::Test {
 protected:
  IntMatrices() : tets("tets", {&verts, &verts, &verts, &verts}) {
    build_cube_tets(2, verts, tets);
  }
  // An int matrix with blocks br x bc through the tets; `as_float` gets the same values as
  // doubles, whose operations (tested elsewhere) are the reference.
  SystemMatrix int_matrix(int br, int bc, int salt, SystemMatrix& as_float) {
    PatternPtr p = registry.assembled(tets, verts, verts);
    SystemMatrix m(p, br, bc, ComponentKind::Int);
    as_float = SystemMatrix(p, br, bc);
    for (size_t i = 0; i < m.value_count(); ++i) {
      m.ints()[i] = small_int(i, salt);
      as_float.values()[i] = small_int(i, salt);
    }
    return m;
  }
  static Eigen::MatrixXd dense_of_ints(const SystemMatrix& m) {
    Eigen::MatrixXd d(m.scalar_rows(), m.scalar_cols());
    for (int64_t i = 0; i < d.rows(); ++i)
      for (int64_t j = 0; j < d.cols(); ++j) d(i, j) = m.component_as<int32_t>(i, j);
    return d;
  }

  Set verts{"verts"};
  Set tets;
  PatternRegistry registry;
};

TEST_F(IntMatrices, MatrixVectorProductsMatchTheFloatReference) {
  SystemMatrix f;
  SystemMatrix a = int_matrix(3, 3, 1, f);
  ASSERT_EQ(a.kind(), ComponentKind::Int);
  EXPECT_EQ(dense_of_ints(a), to_dense(f));
  std::vector<int32_t> x(static_cast<size_t>(a.scalar_cols())), y(x.size()), z(x.size());
  for (size_t i = 0; i < x.size(); ++i) x[i] = small_int(i, 3);
  multiply(a, x, y);
  multiply_transposed(a, x, z);
  Eigen::VectorXd xd(static_cast<Eigen::Index>(x.size()));
  for (size_t i = 0; i < x.size(); ++i) xd[static_cast<Eigen::Index>(i)] = x[i];
  const Eigen::VectorXd yd = to_dense(f) * xd, zd = to_dense(f).transpose() * xd;
  for (size_t i = 0; i < x.size(); ++i) {
    EXPECT_EQ(y[i], yd[static_cast<Eigen::Index>(i)]) << i;
    EXPECT_EQ(z[i], zd[static_cast<Eigen::Index>(i)]) << i;
  }
}

TEST_F(IntMatrices, ArithmeticMatchesTheFloatReference) {
  SystemMatrix f, g;
  SystemMatrix a = int_matrix(2, 2, 1, f), b = int_matrix(2, 2, 4, g);
  EXPECT_EQ(dense_of_ints(add(a, b, 1.0, -1.0)), to_dense(f) - to_dense(g));
  EXPECT_EQ(dense_of_ints(scaled(-3.0, a)), -3.0 * to_dense(f));
  EXPECT_EQ(dense_of_ints(transposed(a, &registry)), Eigen::MatrixXd(to_dense(f).transpose()));
  EXPECT_EQ(dense_of_ints(multiply(a, b)), to_dense(f) * to_dense(g));
  EXPECT_EQ(dense_of_ints(multiply_elementwise(a, b)),
            Eigen::MatrixXd(to_dense(f).cwiseProduct(to_dense(g))));
}

TEST_F(IntMatrices, DivisionTruncatesAndRejectsZero) {
  SystemMatrix f;
  SystemMatrix a = int_matrix(1, 1, 2, f);
  const SystemMatrix q = divided(a, 2.0);
  for (size_t i = 0; i < a.value_count(); ++i) EXPECT_EQ(q.ints()[i], a.ints()[i] / 2) << i;
  EXPECT_THROW(divided(a, 0.0), Fault);
  EXPECT_THROW(scaled(0.5, a), Fault);  // an int matrix has no fractional factors
}

TEST_F(IntMatrices, KindsMustMatch) {
  SystemMatrix f;
  SystemMatrix a = int_matrix(1, 1, 2, f);
  EXPECT_THROW(add(a, f), Fault);
  EXPECT_THROW(multiply(a, f), Fault);
  std::vector<double> x(static_cast<size_t>(a.scalar_cols())), y(x.size());
  EXPECT_THROW(multiply(a, x, y), Fault);
  EXPECT_THROW(to_eigen(a), Fault);
  EXPECT_THROW(LuFactor{a}, Fault);
  EXPECT_THROW(CholeskyFactor{a}, Fault);
  EXPECT_THROW(lower_triangular_solve(a, x, y), Fault);
  EXPECT_THROW(solve(a, x), Fault);
}

TEST(IntMatrixArithmetic, WrapsOnOverflow) {
  auto p = MatrixPattern::from_csr(1, 1, {0, 1}, {0});
  SystemMatrix a(p, 1, 1, ComponentKind::Int);
  a.ints()[0] = std::numeric_limits<int32_t>::max();
  const std::vector<int32_t> x = {2};
  std::vector<int32_t> y(1);
  multiply(a, x, y);
  EXPECT_EQ(y[0], -2);  // 2^32 - 2 wrapped
  EXPECT_EQ(add(a, a).ints()[0], -2);
  EXPECT_EQ(divided(scaled(-1.0, a), -1.0).ints()[0], std::numeric_limits<int32_t>::max());
}

TEST(MatrixKinds, BoolIsStoredAsIntAndStringIsRejected) {
  auto p = MatrixPattern::from_csr(2, 2, {0, 1, 1}, {1});
  SystemMatrix b(p, 1, 1, ComponentKind::Bool);
  b.ints()[0] = 1;
  EXPECT_EQ(b.component_as<int32_t>(0, 1), 1);
  EXPECT_EQ(b.component_as<int32_t>(1, 0), 0);
  EXPECT_EQ(transposed(b).component_as<int32_t>(1, 0), 1);
  EXPECT_EQ(b.values(), nullptr);
  EXPECT_THROW(SystemMatrix(p, 1, 1, ComponentKind::String), Fault);
}

TEST(MatrixKinds, ComplexMatricesAgainstHandWorkedProducts) {
  // A = [1+i, 2i; 0, 3] (no entry at (1, 0)); x = (1, i).
  using C = Complex;
  auto p = MatrixPattern::from_csr(2, 2, {0, 2, 3}, {0, 1, 1});
  SystemMatrix a(p, 1, 1, ComponentKind::Complex);
  a.complexes()[0] = C(1, 1);
  a.complexes()[1] = C(0, 2);
  a.complexes()[2] = C(3, 0);
  const std::vector<C> x = {C(1, 0), C(0, 1)};
  std::vector<C> y(2), z(2);
  multiply(a, x, y);
  EXPECT_EQ(y, (std::vector<C>{C(-1, 1), C(0, 3)}));
  multiply_transposed(a, x, z);  // Aᵀ x, not conjugated
  EXPECT_EQ(z, (std::vector<C>{C(1, 1), C(0, 5)}));
  const SystemMatrix aa = multiply(a, a);  // [2i, -2+8i; 0, 9]
  EXPECT_EQ(aa.component_as<C>(0, 0), C(0, 2));
  EXPECT_EQ(aa.component_as<C>(0, 1), C(-2, 8));
  EXPECT_EQ(aa.component_as<C>(1, 1), C(9, 0));
  EXPECT_EQ(scaled(C(0, 1), a).component_as<C>(0, 0), C(-1, 1));
  EXPECT_EQ(divided(a, C(0, 1)).component_as<C>(0, 1), C(2, 0));
  EXPECT_EQ(add(a, a, 1.0, -2.0).component_as<C>(1, 1), C(-3, 0));
  EXPECT_EQ(multiply_elementwise(a, a).component_as<C>(0, 0), C(0, 2));
  EXPECT_EQ(transposed(a).component_as<C>(1, 0), C(0, 2));
  EXPECT_THROW(a.component(0, 0), Fault);
  EXPECT_THROW(to_eigen(a), Fault);
  EXPECT_THROW(LuFactor{a}, Fault);
  SystemMatrix f(p);
  EXPECT_THROW(scaled(C(0, 1), f), Fault);  // only complex matrices take complex factors
}

// ---------------------------------------------------------------------------
// Blocks of blocks

TEST(NestedBlocks, LogicalDimensions) {
  EXPECT_EQ(block_dims(Shape()).rows, 1);
  const BlockDims d = block_dims(Shape::blocked({3, 3}, Shape{2, 2}));
  EXPECT_EQ(d.rows, 6);
  EXPECT_EQ(d.cols, 6);
  const BlockDims r = block_dims(Shape::blocked({2, 2}, Shape{3, 1}));
  EXPECT_EQ(r.rows, 6);
  EXPECT_EQ(r.cols, 2);
  EXPECT_THROW(block_dims(Shape{3}), Fault);
}

TEST(NestedBlocks, PositionsFollowTheLevels) {
  // Outer 2x3 of inner 2x2: logical (r, c) = (2R + r', 2C + c') is component
  // (3R + C) * 4 + 2r' + c' of the level-by-level layout.
  const std::vector<int32_t> at = nested_positions(Shape::blocked({2, 3}, Shape{2, 2}));
  ASSERT_EQ(at.size(), 24u);
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 6; ++c)
      EXPECT_EQ(at[static_cast<size_t>(r) * 6 + c], (3 * (r / 2) + c / 2) * 4 + 2 * (r % 2) + c % 2)
          << r << ", " << c;
}

TEST(NestedBlocks, UnnestingGivesTheLogicalBlock) {
  // One 4x4 block written level by level (2x2 of 2x2): inner block (R, C) holds 10(2R+C) + k.
  auto p = MatrixPattern::from_csr(1, 1, {0, 1}, {0});
  const Shape block = Shape::blocked({2, 2}, Shape{2, 2});
  SystemMatrix m(p, 4, 4), n(p, 4, 4, ComponentKind::Int);
  for (int i = 0; i < 16; ++i) {
    m.values()[i] = 10 * (i / 4) + i % 4;
    n.ints()[i] = 10 * (i / 4) + i % 4;
  }
  unnest_blocks(m, block);
  unnest_blocks(n, block);
  const double expected[4][4] = {
      {0, 1, 10, 11}, {2, 3, 12, 13}, {20, 21, 30, 31}, {22, 23, 32, 33}};
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) {
      EXPECT_EQ(m.component(r, c), expected[r][c]);
      EXPECT_EQ(n.component_as<int32_t>(r, c), expected[r][c]);
    }
  SystemMatrix same = m;
  unnest_blocks(same, Shape{4, 4});  // an unblocked block is already logical
  EXPECT_EQ(to_dense(same), to_dense(m));
  EXPECT_THROW(unnest_blocks(m, Shape::blocked({3, 3}, Shape{2, 2})), Fault);
}

}  // namespace
}  // namespace simit::runtime
