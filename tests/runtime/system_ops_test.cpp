// Matrix and vector operations on assembled system matrices, against dense Eigen references.
#include "runtime/system_ops.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <span>

#include "runtime/sparse_convert.h"
#include "runtime_fixtures.h"

namespace simit::runtime {
namespace {

using namespace simit::runtime::testing;

double max_diff(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  return (a - b).cwiseAbs().maxCoeff();
}

class TetMatrices : public ::testing::Test {
 protected:
  TetMatrices() : tets("tets", {&verts, &verts, &verts, &verts}) {
    build_cube_tets(2, verts, tets);
  }
  // A blocked matrix through the tets with its dense reference.
  std::pair<SystemMatrix, Eigen::MatrixXd> tet_matrix(const Set& rows, const Set& cols, int br,
                                                      int bc, unsigned seed) {
    SystemMatrix m(registry.assembled(tets, rows, cols), br, bc);
    const size_t rn = members_of(tets, rows).size(), cn = members_of(tets, cols).size();
    LocalMatrix local =
        random_locals(tets.size(), static_cast<int>(rn) * br, static_cast<int>(cn) * bc, seed);
    assemble(m, tets, local);
    return {std::move(m), assemble_dense(tets, rows, cols, br, bc, local)};
  }

  Set verts{"verts"};
  Set tets;
  PatternRegistry registry;
};

TEST_F(TetMatrices, AssemblyMatchesDenseAssembly) {
  auto [m, dense] = tet_matrix(verts, verts, 3, 3, 1);
  EXPECT_LT(max_diff(to_dense(m), dense), 1e-12);
  EXPECT_EQ(m.component(5, 7), dense(5, 7));
}

TEST_F(TetMatrices, MatrixVectorProductBlocked) {
  auto [m, dense] = tet_matrix(verts, verts, 3, 3, 2);
  const std::vector<double> x = random_vector(m.scalar_cols(), 3);
  std::vector<double> y(m.scalar_rows());
  multiply(m, x, y);
  EXPECT_LT((as_eigen(y) - dense * as_eigen(x)).cwiseAbs().maxCoeff(), 1e-12);
}

// round_to_float32 rounds every value, in chunks that hold binary32 values already or not:
// each value ends as static_cast<float> of what it was (NaNs stay NaNs).
// --float32: each row block's part and the row's sum in binary32 steps (docs/arithmetic.md),
// against the same order in float arithmetic on binary32 values.
TEST_F(TetMatrices, Float32ProductsAddInBinary32Steps) {
  auto [m, dense] = tet_matrix(verts, verts, 3, 3, 12);
  round_to_float32(m);
  std::vector<double> x = random_vector(m.scalar_cols(), 13);
  for (double& v : x) v = static_cast<float>(v);
  std::vector<double> y(m.scalar_rows()), wide(m.scalar_rows());
  multiply(m, x, y, true);
  multiply(m, x, wide);
  const MatrixPattern& p = m.pattern();
  int differ = 0;
  for (int row = 0; row < m.rows(); ++row)
    for (int i = 0; i < 3; ++i) {
      float sum = 0.0f;
      for (int32_t k = p.row_ptr()[row]; k < p.row_ptr()[row + 1]; ++k) {
        float part = 0.0f;
        for (int j = 0; j < 3; ++j)
          part += static_cast<float>(m.values()[k * 9 + i * 3 + j]) *
                  static_cast<float>(x[static_cast<size_t>(p.col_idx()[k]) * 3 + j]);
        sum += part;
      }
      const size_t at = static_cast<size_t>(row) * 3 + i;
      EXPECT_EQ(y[at], static_cast<double>(sum)) << at;
      differ += static_cast<float>(wide[at]) != sum;
    }
  EXPECT_GT(differ, 0);  // the order of rounding shows: binary64 sums rounded once differ
}

TEST_F(TetMatrices, MatrixVectorProductUnblocked) {
  auto [m, dense] = tet_matrix(verts, verts, 1, 1, 4);
  const std::vector<double> x = random_vector(m.scalar_cols(), 5);
  std::vector<double> y(m.scalar_rows());
  multiply(m, x, y);
  EXPECT_LT((as_eigen(y) - dense * as_eigen(x)).cwiseAbs().maxCoeff(), 1e-12);
}

TEST_F(TetMatrices, RectangularAndOddBlocks) {
  auto [m, dense] = tet_matrix(tets, verts, 2, 3, 6);  // tet rows, vertex columns, 2x3 blocks
  EXPECT_LT(max_diff(to_dense(m), dense), 1e-12);
  const std::vector<double> x = random_vector(m.scalar_cols(), 7);
  std::vector<double> y(m.scalar_rows());
  multiply(m, x, y);
  EXPECT_LT((as_eigen(y) - dense * as_eigen(x)).cwiseAbs().maxCoeff(), 1e-12);
  const std::vector<double> z = random_vector(m.scalar_rows(), 8);
  std::vector<double> w(m.scalar_cols());
  multiply_transposed(m, z, w);
  EXPECT_LT((as_eigen(w) - dense.transpose() * as_eigen(z)).cwiseAbs().maxCoeff(), 1e-12);
}

TEST_F(TetMatrices, TransposedProductBlocked) {
  auto [m, dense] = tet_matrix(verts, verts, 3, 3, 9);
  const std::vector<double> x = random_vector(m.scalar_rows(), 10);
  std::vector<double> y(m.scalar_cols(), 123.0);  // overwritten, not accumulated
  multiply_transposed(m, x, y);
  EXPECT_LT((as_eigen(y) - dense.transpose() * as_eigen(x)).cwiseAbs().maxCoeff(), 1e-12);
}

TEST_F(TetMatrices, SumWithTheSamePattern) {
  auto [a, da] = tet_matrix(verts, verts, 3, 3, 11);
  auto [b, db] = tet_matrix(verts, verts, 3, 3, 12);
  SystemMatrix c = add(a, b, 2.0, -0.5);
  EXPECT_EQ(c.shared_pattern(), a.shared_pattern());
  EXPECT_LT(max_diff(to_dense(c), 2.0 * da - 0.5 * db), 1e-12);
}

TEST_F(TetMatrices, SumOfDifferentPatternsUsesTheUnion) {
  auto [a, da] = tet_matrix(verts, verts, 3, 3, 13);
  SystemMatrix mass(registry.assembled(verts, verts, verts), 3, 3);
  LocalMatrix local = random_locals(verts.size(), 3, 3, 14);
  assemble(mass, verts, local);
  const Eigen::MatrixXd dmass = assemble_dense(verts, verts, verts, 3, 3, local);
  const int before = registry.builds();
  SystemMatrix c = add(a, mass, 1.0, 1.0, &registry);
  SystemMatrix c2 = add(a, mass, 1.0, 1.0, &registry);
  EXPECT_EQ(registry.builds(), before + 1);  // the union is built once
  EXPECT_EQ(c.shared_pattern(), c2.shared_pattern());
  EXPECT_LT(max_diff(to_dense(c), da + dmass), 1e-12);
  SystemMatrix d = add(mass, a, 1.0, -1.0);  // without a registry
  EXPECT_LT(max_diff(to_dense(d), dmass - da), 1e-12);
}

// A sum over the union writes each block once with the bits of zeroing the result and adding
// alpha a, then beta b, into it: a negative zero of either operand becomes +0.0.
TEST_F(TetMatrices, SumsOverTheUnionKeepTheBitsOfAddingIntoZeros) {
  auto [k, dk] = tet_matrix(verts, verts, 3, 3, 31);
  SystemMatrix mass(registry.assembled(verts, verts, verts), 3, 3);
  assemble(mass, verts, random_locals(verts.size(), 3, 3, 32));
  mass.block(0)[1] = -0.0;
  const int32_t off = k.pattern().find(0, 1);
  ASSERT_GE(off, 0);
  k.block(off)[2] = -0.0;                    // a block of k alone
  k.block(k.pattern().find(0, 0))[1] = 0.0;  // 0.0 + -0.0 + -0.37 * 0.0: +0.0
  SystemMatrix sum = add(mass, k, 1.0, -0.37, &registry);
  // The reference: zeros, then each operand's blocks scaled and added where they land.
  std::vector<double> want(sum.value_count(), 0.0);
  for (const auto& [m, f] : {std::pair<const SystemMatrix*, double>{&mass, 1.0}, {&k, -0.37}})
    for (int r = 0; r < m->rows(); ++r)
      for (int32_t b = m->pattern().row_ptr()[r]; b < m->pattern().row_ptr()[r + 1]; ++b) {
        const int32_t at = sum.pattern().find(r, m->pattern().col_idx()[b]);
        for (int i = 0; i < 9; ++i) want[static_cast<size_t>(at) * 9 + i] += f * m->block(b)[i];
      }
  EXPECT_EQ(std::memcmp(want.data(), sum.values(), want.size() * sizeof(double)), 0);
  EXPECT_FALSE(std::signbit(sum.block(sum.pattern().find(0, 0))[1]));
  EXPECT_FALSE(std::signbit(sum.block(sum.pattern().find(0, 1))[2]));
  EXPECT_LT(max_diff(to_dense(sum), to_dense(mass) - 0.37 * to_dense(k)), 1e-12);
  EXPECT_GT(dk.cwiseAbs().maxCoeff(), 0.0);
}

// The sum in place (the JIT's `A = M - s * K` in K's storage) has add()'s bits, signed zeros
// included, on a sub-pattern and on the same pattern; outside the pattern it declines.
TEST_F(TetMatrices, SumIntoTheSecondOperandKeepsTheBitsOfTheSum) {
  auto [k, dk] = tet_matrix(verts, verts, 3, 3, 41);
  SystemMatrix mass(registry.assembled(verts, verts, verts), 3, 3);
  assemble(mass, verts, random_locals(verts.size(), 3, 3, 42));
  mass.block(0)[1] = -0.0;
  k.block(k.pattern().find(0, 1))[2] = -0.0;
  k.block(k.pattern().find(0, 0))[1] = 0.0;
  const SystemMatrix want = add(mass, k, 1.0, -0.37, &registry);
  SystemMatrix in_place = k;
  ASSERT_TRUE(add_into(mass, 1.0, in_place, -0.37));
  ASSERT_EQ(want.value_count(), in_place.value_count());
  EXPECT_EQ(std::memcmp(want.values(), in_place.values(), want.value_count() * sizeof(double)), 0);
  EXPECT_FALSE(std::signbit(in_place.block(in_place.pattern().find(0, 1))[2]));
  EXPECT_GT(max_diff(to_dense(in_place), dk), 0.0);  // it did change
  // The same pattern: add()'s element-wise combination, without the zero.
  auto [b, db] = tet_matrix(verts, verts, 3, 3, 43);
  b.block(2)[0] = -0.0;
  k.block(2)[0] = -0.0;
  const SystemMatrix same = add(b, k, 2.0, 0.5);
  ASSERT_TRUE(add_into(b, 2.0, k, 0.5));
  EXPECT_EQ(std::memcmp(same.values(), k.values(), same.value_count() * sizeof(double)), 0);
  EXPECT_TRUE(std::signbit(k.block(2)[0]));  // -0 + -0, as add() gives on one pattern
  // The tets' blocks do not lie in the diagonal: declined, the mass untouched.
  const SystemMatrix before = mass;
  EXPECT_FALSE(add_into(k, 1.0, mass, -1.0));
  EXPECT_EQ(std::memcmp(before.values(), mass.values(), mass.value_count() * sizeof(double)), 0);
  EXPECT_GT(db.cwiseAbs().maxCoeff(), 0.0);
}

// In tasks of rows run in any order (the JIT's threads): the same bits as in one pass.
TEST(AddInto, TasksInAnyOrderGiveTheSameBits) {
  const int n = 5000;
  std::vector<int32_t> row_ptr{0}, col_idx, diag_ptr{0}, diag_idx;
  for (int r = 0; r < n; ++r) {
    for (int c : {r, (r + 1) % n}) col_idx.push_back(c);
    std::sort(col_idx.end() - 2, col_idx.end());
    row_ptr.push_back(static_cast<int32_t>(col_idx.size()));
    diag_idx.push_back(r);
    diag_ptr.push_back(r + 1);
  }
  SystemMatrix k(MatrixPattern::from_csr(n, n, row_ptr, col_idx), 2, 2);
  SystemMatrix m(MatrixPattern::from_csr(n, n, diag_ptr, diag_idx), 2, 2);
  for (size_t i = 0; i < k.value_count(); ++i) k.values()[i] = std::sin(0.1 * i) * 1e3;
  for (size_t i = 0; i < m.value_count(); ++i) m.values()[i] = std::cos(0.7 * i) / 3;
  SystemMatrix serial = k, tasked = k;
  ASSERT_TRUE(add_into(m, 1.0, serial, -0.37));
  int64_t seen = 0;
  ASSERT_TRUE(add_into(m, 1.0, tasked, -0.37,
                       [&seen](int64_t tasks, const std::function<void(int64_t)>& task) {
                         seen = tasks;
                         for (int64_t t = tasks - 1; t >= 0; --t) task(t);
                       }));
  EXPECT_GT(seen, 1);
  EXPECT_EQ(std::memcmp(serial.values(), tasked.values(), k.value_count() * sizeof(double)), 0);
  // And each block is the sum written out: 0 + m where m has the block, then -0.37 k.
  const int32_t at = k.pattern().find(7, 7);
  const int32_t off = k.pattern().find(7, 8);
  EXPECT_EQ(tasked.block(at)[3], (0.0 + m.block(7)[3]) + -0.37 * k.block(at)[3]);
  EXPECT_EQ(tasked.block(off)[1], 0.0 + -0.37 * k.block(off)[1]);
}

TEST_F(TetMatrices, ScaleAndNegate) {
  auto [a, da] = tet_matrix(verts, verts, 3, 3, 15);
  EXPECT_LT(max_diff(to_dense(scaled(-2.5, a)), -2.5 * da), 1e-12);
  scale(0.5, a);
  EXPECT_LT(max_diff(to_dense(a), 0.5 * da), 1e-12);
}

TEST_F(TetMatrices, Transpose) {
  auto [a, da] = tet_matrix(tets, verts, 1, 3, 16);
  SystemMatrix t = transposed(a, &registry);
  EXPECT_EQ(t.block_rows(), 3);
  EXPECT_EQ(t.block_cols(), 1);
  EXPECT_LT(max_diff(to_dense(t), da.transpose()), 1e-12);
  transposed(a, &registry);
  SystemMatrix u = transposed(a, &registry);
  EXPECT_EQ(u.shared_pattern(), t.shared_pattern());
}

TEST_F(TetMatrices, SparseProduct) {
  auto [a, da] = tet_matrix(verts, tets, 3, 1, 17);
  auto [b, db] = tet_matrix(tets, verts, 1, 3, 18);
  SystemMatrix c = multiply(a, b);
  EXPECT_EQ(c.block_rows(), 3);
  EXPECT_EQ(c.block_cols(), 3);
  EXPECT_LT(max_diff(to_dense(c), da * db), 1e-12);
  EXPECT_THROW(multiply(a, a), Fault);
}

TEST_F(TetMatrices, MismatchedShapesFault) {
  auto [a, da] = tet_matrix(verts, verts, 3, 3, 19);
  auto [b, db] = tet_matrix(verts, verts, 1, 1, 20);
  EXPECT_THROW(add(a, b), Fault);
  std::vector<double> x(3), y(a.scalar_rows());
  EXPECT_THROW(multiply(a, x, y), Fault);
}

TEST(StencilOps, WrappedOffsetsSumInProducts) {
  Set points("points");
  Set grid("links", points, {2});
  PatternPtr p = MatrixPattern::stencil(grid, {{0}, {1}, {-1}});
  SystemMatrix k(p);
  for (int pt = 0; pt < 2; ++pt) {
    k.block(p->row_ptr()[pt])[0] = 4.0;
    k.block(p->row_ptr()[pt] + 1)[0] = -1.0;
    k.block(p->row_ptr()[pt] + 2)[0] = -2.0;
  }
  Eigen::Matrix2d expected;
  expected << 4.0, -3.0, -3.0, 4.0;
  EXPECT_EQ(to_dense(k), Eigen::MatrixXd(expected));
  const std::vector<double> x = {1.0, 10.0};
  std::vector<double> y(2), z(2);
  multiply(k, x, y);
  EXPECT_EQ(y, (std::vector<double>{-26.0, 37.0}));
  multiply_transposed(k, x, z);
  EXPECT_EQ(z, (std::vector<double>{-26.0, 37.0}));
  EXPECT_EQ(to_dense(transposed(k)), Eigen::MatrixXd(expected.transpose()));
  EXPECT_EQ(to_dense(add(k, k)), Eigen::MatrixXd(2.0 * expected));
}

TEST(VectorOps, ElementwiseAndReductions) {
  const std::vector<double> x = {1.0, -2.0, 3.0}, y = {4.0, 5.0, -6.0};
  std::vector<double> out(3);
  add(x, y, out);
  EXPECT_EQ(out, (std::vector<double>{5.0, 3.0, -3.0}));
  subtract(x, y, out);
  EXPECT_EQ(out, (std::vector<double>{-3.0, -7.0, 9.0}));
  multiply_elementwise(x, y, out);
  EXPECT_EQ(out, (std::vector<double>{4.0, -10.0, -18.0}));
  divide_elementwise(y, x, out);
  EXPECT_EQ(out, (std::vector<double>{4.0, -2.5, -2.0}));
  EXPECT_EQ(dot(x, y), 4.0 - 10.0 - 18.0);
  EXPECT_DOUBLE_EQ(norm(x), std::sqrt(14.0));
  std::vector<double> z = y;
  axpy(2.0, x, z);
  EXPECT_EQ(z, (std::vector<double>{6.0, 1.0, 0.0}));
  scale(-1.0, std::span<double>(z));
  EXPECT_EQ(z, (std::vector<double>{-6.0, -1.0, -0.0}));
  add(z, z, z);  // aliasing is allowed
  EXPECT_EQ(z, (std::vector<double>{-12.0, -2.0, 0.0}));
  EXPECT_THROW(dot(x, std::vector<double>(2)), Fault);
}

// docs/arithmetic.md: each element's block is summed before it joins the total, and the
// element sums go to lanes (element e to lane e) folded by a halving tree (lane i + lane
// i + w for w = 16, ..., 1). By single components, lanes 1e16, 1, 0, -1e16, 1: the tree adds
// 1e16 + 1 (lane 4 into 0, rounding to 1e16) and 1 + -1e16 (lane 3 into 1), then those: 0.0.
// By elements of three, both 1s are lost inside their elements: 0.0. By elements of two,
// (1e16, 1) (0, -1e16) (1, 0): lane 0 gets lane 2's 1 first (1e16), then lane 1's -1e16: 0.0.
TEST(VectorOps, InnerProductsSumEachElementFirst) {
  const std::vector<double> x = {1e16, 1.0, 0.0, -1e16, 1.0, 0.0}, ones(6, 1.0);
  EXPECT_EQ(dot(x, ones), 0.0);
  EXPECT_EQ(dot(x, ones, 3), 0.0);
  EXPECT_EQ(dot(x, ones, 2), 0.0);
  // Lanes 1e16, 1, -1e16: lane 2 joins lane 0 first (0), then lane 1 (1); left to right, 0.
  const std::vector<double> y = {1e16, 1.0, -1e16};
  EXPECT_EQ(dot(y, std::vector<double>(3, 1.0)), 1.0);
  EXPECT_THROW(dot(x, ones, 4), Fault);
}

}  // namespace
}  // namespace simit::runtime
