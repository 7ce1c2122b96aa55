// Dense tensors: shapes with blocking levels, inline and shared storage, ranges and fills.
#include <gtest/gtest.h>

#include "runtime/fault.h"
#include "runtime/tensor.h"

namespace simit::runtime {
namespace {

TEST(Shape, ScalarAndPlainShapes) {
  Shape s;
  EXPECT_TRUE(s.is_scalar());
  EXPECT_EQ(s.size(), 1u);
  Shape m{2, 3};
  EXPECT_EQ(m.order(), 2);
  EXPECT_EQ(m.levels(), 1);
  EXPECT_EQ(m.size(), 6u);
  EXPECT_EQ(m.outer_count(), 6u);
  EXPECT_TRUE(m.block().is_scalar());
  EXPECT_EQ(m.str(), "2x3");
}

TEST(Shape, BlockedShapes) {
  Shape k = Shape::blocked({4, 4}, Shape{2, 3});
  EXPECT_EQ(k.order(), 2);
  EXPECT_EQ(k.levels(), 2);
  EXPECT_EQ(k.rank(), 4);
  EXPECT_EQ(k.size(), 96u);
  EXPECT_EQ(k.outer_count(), 16u);
  EXPECT_EQ(k.block_size(), 6u);
  EXPECT_EQ(k.block(), (Shape{2, 3}));
  EXPECT_EQ(k.logical(), (Shape{8, 12}));
  EXPECT_EQ(k.str(), "4x4 of 2x3");
  Shape nested = Shape::blocked({5}, Shape::blocked({8}, Shape{3}));
  EXPECT_EQ(nested.levels(), 3);
  EXPECT_EQ(nested.logical(), (Shape{120}));
  EXPECT_EQ(nested.block().block(), (Shape{3}));
}

TEST(Shape, MixedOrderBlocksHaveNoLogicalForm) {
  Shape odd = Shape::blocked({3}, Shape{2, 2});
  EXPECT_FALSE(odd.uniform());
  EXPECT_THROW(odd.logical(), Fault);
}

TEST(Shape, TooManyDimensionsIsAFault) {
  EXPECT_THROW(Shape::of({1, 1, 1, 1, 1, 1, 1, 1, 1}), Fault);
  EXPECT_THROW(Shape::of({-1}), Fault);
}

TEST(Shape, SizesThatWouldWrapAreAFault) {
  // 65536^4 components wrap size_t to 0; the run-time backstop refuses anything over 2^48.
  try {
    Shape::of({65536, 65536, 65536, 65536});
    FAIL() << "expected a fault";
  } catch (const Fault& f) {
    EXPECT_STREQ(f.what(),
                 "a tensor with dimensions of sizes 65536x65536x65536x65536 is too large");
  }
}

// The allocation fails at once (a pebibyte): the fault names the tensor and its size.
TEST(Tensor, OutOfMemoryNamesTheTensor) {
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "AddressSanitizer aborts on a pebibyte allocation instead of throwing";
#else
  const Shape s = Shape::of({1 << 20, 1 << 20, 1 << 7});
  const char* want =
      "out of memory while allocating a 1048576x1048576x128 float tensor (1125899906842624 "
      "bytes)";
  try {
    Tensor t(ComponentKind::Float, s);
    FAIL() << "expected a fault";
  } catch (const Fault& f) {
    EXPECT_STREQ(f.what(), want);
  }
  try {
    Tensor t;
    t.reset_uninit(ComponentKind::Float, s);
    FAIL() << "expected a fault";
  } catch (const Fault& f) {
    EXPECT_STREQ(f.what(), want);
  }
#endif
}

TEST(Tensor, ZeroInitialisedOfEveryKind) {
  Tensor f(ComponentKind::Float, Shape{3});
  Tensor i(ComponentKind::Int, Shape{2, 2});
  Tensor b(ComponentKind::Bool, Shape{2});
  Tensor c(ComponentKind::Complex, Shape{2});
  Tensor s(ComponentKind::String, Shape{2});
  for (int k = 0; k < 3; ++k) EXPECT_EQ(f.floats()[k], 0.0);
  for (int k = 0; k < 4; ++k) EXPECT_EQ(i.ints()[k], 0);
  EXPECT_FALSE(b.bools()[1]);
  EXPECT_EQ(c.complexes()[1], Complex(0.0, 0.0));
  EXPECT_EQ(s.strings()[1], "");
}

TEST(Tensor, CopiesAreIndependentInlineAndShared) {
  Tensor small(ComponentKind::Float, Shape{3, 3});  // inline storage
  small.mutable_floats()[4] = 1.5;
  Tensor copy = small;
  copy.mutable_floats()[4] = 2.5;
  EXPECT_EQ(small.floats()[4], 1.5);
  EXPECT_EQ(copy.floats()[4], 2.5);

  Tensor big(ComponentKind::Float, Shape{10, 10});  // heap storage, shared until written
  big.mutable_floats()[99] = 7.0;
  Tensor shared = big;
  EXPECT_EQ(shared.floats(), big.floats());
  shared.mutable_floats()[99] = 8.0;
  EXPECT_NE(shared.floats(), big.floats());
  EXPECT_EQ(big.floats()[99], 7.0);
  EXPECT_EQ(shared.floats()[99], 8.0);

  Tensor strings(ComponentKind::String, Shape{2});
  strings.mutable_strings()[0] = "a";
  Tensor strings2 = strings;
  strings2.mutable_strings()[0] = "b";
  EXPECT_EQ(strings.strings()[0], "a");
}

TEST(Tensor, MovedFromStorageKeepsTheValue) {
  Tensor big(ComponentKind::Int, Shape{100});
  big.mutable_ints()[50] = 3;
  Tensor moved = std::move(big);
  EXPECT_EQ(moved.ints()[50], 3);
}

TEST(Tensor, RangesFillsAndReshape) {
  Tensor t(ComponentKind::Int, Shape::blocked({2}, Shape{3}));
  t.fill(3, 3, int32_t{7});
  Tensor block = t.range(3, Shape{3});
  EXPECT_EQ(block.shape(), (Shape{3}));
  EXPECT_EQ(block.ints()[2], 7);
  Tensor src(ComponentKind::Int, Shape{3});
  src.mutable_ints()[0] = 1;
  t.write_range(0, src);
  EXPECT_EQ(t.ints()[0], 1);
  EXPECT_EQ(t.ints()[3], 7);
  EXPECT_THROW(t.range(4, Shape{3}), Fault);
  t.reshape(Shape{6});
  EXPECT_EQ(t.shape(), (Shape{6}));
  EXPECT_THROW(t.reshape(Shape{5}), Fault);
}

TEST(Tensor, EqualityComparesKindShapeAndComponents) {
  Tensor a(ComponentKind::Float, Shape{2}), b(ComponentKind::Float, Shape{2});
  EXPECT_EQ(a, b);
  b.mutable_floats()[1] = 1.0;
  EXPECT_FALSE(a == b);
  EXPECT_FALSE(a == Tensor(ComponentKind::Float, Shape{1, 2}));
  EXPECT_FALSE(a == Tensor(ComponentKind::Int, Shape{2}));
}

}  // namespace
}  // namespace simit::runtime
