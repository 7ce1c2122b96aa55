// Small dense linear algebra: blocking conversion, products, transpose, det, inv, solves.
#include <gtest/gtest.h>

#include <cmath>

#include "runtime/dense_linalg.h"
#include "runtime/fault.h"

namespace simit::runtime {
namespace {

Tensor floats(const Shape& s, std::initializer_list<double> values) {
  Tensor t(ComponentKind::Float, s);
  size_t i = 0;
  for (double v : values) t.mutable_floats()[i++] = v;
  return t;
}

Tensor ints(const Shape& s, std::initializer_list<int32_t> values) {
  Tensor t(ComponentKind::Int, s);
  size_t i = 0;
  for (int32_t v : values) t.mutable_ints()[i++] = v;
  return t;
}

void expect_floats(const Tensor& t, std::initializer_list<double> values, double tol = 1e-12) {
  ASSERT_EQ(t.size(), values.size());
  size_t i = 0;
  for (double v : values) {
    EXPECT_NEAR(t.floats()[i], v, tol) << "component " << i;
    ++i;
  }
}

TEST(Blocking, UnblockPlacesBlocksInTheirLogicalPositions) {
  // A 2x2 matrix of 2x2 blocks, blocks stored one after another.
  Tensor k =
      ints(Shape::blocked({2, 2}, Shape{2, 2}),
           {1, 2, 3, 4, /*(0,1)*/ 5, 6, 7, 8, /*(1,0)*/ 9, 10, 11, 12, /*(1,1)*/ 13, 14, 15, 16});
  Tensor l = unblock(k);
  EXPECT_EQ(l.shape(), (Shape{4, 4}));
  const int32_t expected[16] = {1, 2, 5, 6, 3, 4, 7, 8, 9, 10, 13, 14, 11, 12, 15, 16};
  for (int i = 0; i < 16; ++i) EXPECT_EQ(l.ints()[i], expected[i]) << i;
  EXPECT_EQ(reblock(l, k.shape()), k);
}

TEST(Blocking, NestedBlockedVectorsRoundTrip) {
  Shape s = Shape::blocked({2}, Shape::blocked({2}, Shape{3}));
  Tensor t(ComponentKind::Float, s);
  for (size_t i = 0; i < t.size(); ++i) t.mutable_floats()[i] = static_cast<double>(i);
  Tensor l = unblock(t);
  EXPECT_EQ(l.shape(), (Shape{12}));
  EXPECT_EQ(l, reblock(l, Shape{12}));
  EXPECT_EQ(reblock(l, s), t);
  // Vectors of vectors keep their order when unblocked.
  for (size_t i = 0; i < 12; ++i) EXPECT_EQ(l.floats()[i], static_cast<double>(i));
}

TEST(Products, MatrixMatrixVectorAndOuter) {
  Tensor a = floats(Shape{2, 3}, {1, 2, 3, 4, 5, 6});
  Tensor b = floats(Shape{3, 2}, {1, 0, 0, 1, 1, 1});
  expect_floats(matrix_product(a, b), {4, 5, 10, 11});
  Tensor x = floats(Shape{3}, {1, -1, 2});
  expect_floats(matrix_vector_product(a, x), {5, 11});
  Tensor y = floats(Shape{2}, {1, 1});
  expect_floats(vector_matrix_product(y, a), {5, 7, 9});
  expect_floats(outer_product(y, x), {1, -1, 2, 1, -1, 2});
  expect_floats(inner_product(x, x), {6});
  EXPECT_THROW(matrix_product(a, a), Fault);
}

// --float32: each product and addition of a sum rounded to binary32, as float arithmetic
// computes it; 1 + 2^-24 + 2^-24 - 1 then sums to 0, and to 2^-23 in binary64.
TEST(Products, Float32SumsAddInBinary32Steps) {
  const double tiny = std::ldexp(1.0, -24);
  Tensor a = floats(Shape{2, 4}, {1, tiny, tiny, -1, 0.5, 0.25, 3, -0.75});
  Tensor x = floats(Shape{4}, {1, 1, 1, 1});
  expect_floats(matrix_vector_product(a, x, true), {0, 3});
  expect_floats(matrix_vector_product(a, x), {2 * tiny, 3});
  Tensor u = floats(Shape{4}, {1, tiny, tiny, -1});
  expect_floats(inner_product(u, x, true), {0});
  expect_floats(inner_product(u, x), {2 * tiny});
  // Against float arithmetic on binary32 values that round at each step (0.1f * 3 is not a
  // binary32 product without rounding): a 3 x 5 times 5 x 2 product.
  Tensor l(ComponentKind::Float, Shape{3, 5}), r(ComponentKind::Float, Shape{5, 2});
  for (size_t i = 0; i < l.size(); ++i) l.mutable_floats()[i] = static_cast<float>(0.1 * (i + 1));
  for (size_t i = 0; i < r.size(); ++i) r.mutable_floats()[i] = static_cast<float>(0.37 / (i + 1));
  const Tensor p = matrix_product(l, r, true);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 2; ++j) {
      float sum = 0.0f;
      for (int k = 0; k < 5; ++k)
        sum +=
            static_cast<float>(l.floats()[i * 5 + k]) * static_cast<float>(r.floats()[k * 2 + j]);
      EXPECT_EQ(p.floats()[i * 2 + j], static_cast<double>(sum)) << i << ", " << j;
    }
}

TEST(Products, IntegerProductsWrap) {
  Tensor a = ints(Shape{1, 1}, {65536});
  Tensor p = matrix_product(a, a);
  EXPECT_EQ(p.ints()[0], 0);
  Tensor c(ComponentKind::Complex, Shape{1});
  c.mutable_complexes()[0] = Complex(1, 1);
  EXPECT_EQ(inner_product(c, c).complexes()[0], Complex(0, 2));  // no conjugation
}

TEST(Transpose, MatricesAndBlockedMatrices) {
  Tensor a = ints(Shape{2, 3}, {1, 2, 3, 4, 5, 6});
  Tensor t = transpose(a);
  EXPECT_EQ(t, ints(Shape{3, 2}, {1, 4, 2, 5, 3, 6}));
  Tensor k = ints(Shape::blocked({1, 2}, Shape{2, 1}), {1, 2, 3, 4});
  Tensor kt = transpose(k);
  EXPECT_EQ(kt.shape(), Shape::blocked({2, 1}, Shape{1, 2}));
  EXPECT_EQ(unblock(kt), transpose(unblock(k)));
}

TEST(Inverse, DeterminantsAndInverses) {
  Tensor m2 = floats(Shape{2, 2}, {4, 7, 2, 6});
  EXPECT_NEAR(determinant(m2), 10.0, 1e-14);
  expect_floats(inverse(m2), {0.6, -0.7, -0.2, 0.4});
  Tensor m3 = floats(Shape{3, 3}, {2, 0, 0, 0, 3, 0, 0, 0, 4});
  EXPECT_NEAR(determinant(m3), 24.0, 1e-14);
  expect_floats(inverse(m3), {0.5, 0, 0, 0, 1.0 / 3, 0, 0, 0, 0.25});
  Tensor m4 = floats(Shape{4, 4}, {1, 0, 0, 0, 0, 2, 0, 0, 0, 0, 4, 0, 1, 0, 0, 1});
  EXPECT_NEAR(determinant(m4), 8.0, 1e-14);
  expect_floats(inverse(m4), {1, 0, 0, 0, 0, 0.5, 0, 0, 0, 0, 0.25, 0, -1, 0, 0, 1});
}

TEST(Inverse, SingularMatricesAreFaults) {
  EXPECT_THROW(inverse(floats(Shape{2, 2}, {1, 2, 2, 4})), Fault);
  EXPECT_THROW(inverse(floats(Shape{3, 3}, {0, 0, 0, 0, 1, 0, 0, 0, 1})), Fault);
  EXPECT_THROW(determinant(floats(Shape{5, 5}, {})), Fault);
  EXPECT_THROW(inverse(floats(Shape{2, 3}, {})), Fault);
}

TEST(Solve, DenseAndTriangular) {
  Tensor a = floats(Shape{2, 2}, {0, 1, 1, 0});
  expect_floats(solve(a, floats(Shape{2}, {3, 4})), {4, 3});
  EXPECT_THROW(solve(floats(Shape{2, 2}, {1, 1, 1, 1}), floats(Shape{2}, {1, 2})), Fault);
  EXPECT_THROW(solve(ints(Shape{1, 1}, {1}), ints(Shape{1}, {1})), Fault);
  Tensor l = floats(Shape{2, 2}, {2, 99, 1, 4});  // the strict upper part is ignored
  expect_floats(lower_triangular_solve(l, floats(Shape{2}, {2, 5})), {1, 1});
  EXPECT_THROW(lower_triangular_solve(floats(Shape{2, 2}, {1, 0, 0, 0}), floats(Shape{2}, {1, 1})),
               Fault);
}

TEST(Floats, RoundingAndFiniteness) {
  Tensor t = floats(Shape{2}, {0.1, 1.0});
  round_to_float32(t);
  EXPECT_EQ(t.floats()[0], static_cast<double>(0.1f));
  EXPECT_TRUE(all_finite(t));
  t.mutable_floats()[1] = 1.0 / 0.0;
  EXPECT_FALSE(all_finite(t));
}

}  // namespace
}  // namespace simit::runtime
