// The registry of arrays whose newest contents are elsewhere (runtime/residency.h): every
// accessor of tensors, fields and system matrices brings such an array back before the host
// touches it, the raw accessors do not, and an array freed or set anew is dropped, never
// copied into.
#include <gtest/gtest.h>

#include <cstring>
#include <map>
#include <memory>
#include <vector>

#include "runtime/residency.h"
#include "runtime/set.h"
#include "runtime/system_matrix.h"
#include "runtime/tensor.h"

namespace simit::runtime {
namespace {

// A holder whose "memory" is a copy per array: bring_back writes it into the host array.
class FakeHolder : public residency::Holder {
 public:
  void keep(void* host, std::vector<double> newer) {
    newer_[host] = std::move(newer);
    residency::mark_elsewhere(host, *this);
  }
  void bring_back(void* host) override {
    const std::vector<double>& v = newer_.at(host);
    std::memcpy(host, v.data(), v.size() * sizeof(double));
    ++brought;
  }
  void released(const void* host) noexcept override {
    newer_.erase(host);
    ++dropped;
  }
  int brought = 0, dropped = 0;

 private:
  std::map<const void*, std::vector<double>> newer_;
};

class Residency : public ::testing::Test {
 protected:
  void TearDown() override {
    residency::bring_back_all();
    EXPECT_EQ(residency::count(), 0);
  }
  FakeHolder holder;
};

Tensor vector_of(int n, double value) {
  Tensor t(ComponentKind::Float, Shape::blocked(std::vector<int>{n}, Shape::of({})));
  for (int i = 0; i < n; ++i) t.mutable_floats()[i] = value;
  return t;
}

TEST_F(Residency, ATensorIsBroughtBackOnceWhenTheHostReadsIt) {
  Tensor t = vector_of(100, 1.0);  // 800 bytes: on the heap
  ASSERT_TRUE(t.shared_buffer());
  holder.keep(const_cast<double*>(t.raw_floats()), std::vector<double>(100, 7.0));
  EXPECT_TRUE(residency::is_elsewhere(t.raw_floats(), holder));
  EXPECT_EQ(residency::count(), 1);
  // The raw accessors see the host's old copy and bring nothing back.
  EXPECT_EQ(t.raw_floats()[5], 1.0);
  EXPECT_EQ(holder.brought, 0);
  // A read brings the newer copy back, once.
  EXPECT_EQ(t.floats()[5], 7.0);
  EXPECT_EQ(t.floats()[99], 7.0);
  EXPECT_EQ(holder.brought, 1);
  EXPECT_EQ(residency::count(), 0);
  EXPECT_FALSE(residency::any_elsewhere());
}

TEST_F(Residency, AWriteBringsItBackFirstSoThatUnwrittenValuesAreTheNewerOnes) {
  Tensor t = vector_of(100, 1.0);
  holder.keep(t.raw_mutable_floats(), std::vector<double>(100, 7.0));
  t.mutable_floats()[0] = -1.0;
  EXPECT_EQ(holder.brought, 1);
  EXPECT_EQ(t.floats()[0], -1.0);
  EXPECT_EQ(t.floats()[1], 7.0);
}

TEST_F(Residency, ACopyOfASharedTensorIsTakenFromTheNewerContents) {
  Tensor a = vector_of(100, 1.0);
  holder.keep(a.raw_mutable_floats(), std::vector<double>(100, 7.0));
  Tensor b = a;  // shares the block: nothing read yet
  EXPECT_EQ(holder.brought, 0);
  // Writing through b unshares it: the copy is made from the newer contents.
  b.raw_mutable_floats()[0] = 2.0;
  EXPECT_EQ(holder.brought, 1);
  EXPECT_EQ(b.floats()[1], 7.0);
  EXPECT_EQ(a.floats()[0], 7.0);
}

TEST_F(Residency, AnArrayFreedWhileElsewhereIsDroppedNotCopiedInto) {
  {
    Tensor t = vector_of(100, 1.0);
    holder.keep(t.raw_mutable_floats(), std::vector<double>(100, 7.0));
    SystemMatrix m(MatrixPattern::from_csr(2, 2, {0, 1, 2}, {0, 1}), 3, 3);
    holder.keep(m.raw_values(), std::vector<double>(18, 7.0));
    EXPECT_EQ(residency::count(), 2);
  }
  EXPECT_EQ(holder.brought, 0);
  EXPECT_EQ(holder.dropped, 2);
  EXPECT_EQ(residency::count(), 0);
}

TEST_F(Residency, AMatrixIsBroughtBackByItsValuesItsBlocksAndItsCopies) {
  SystemMatrix m(MatrixPattern::from_csr(2, 2, {0, 1, 2}, {0, 1}), 3, 3);
  holder.keep(m.raw_values(), std::vector<double>(18, 7.0));
  EXPECT_EQ(std::as_const(m).block(1)[2], 7.0);
  EXPECT_EQ(holder.brought, 1);
  holder.keep(m.raw_values(), std::vector<double>(18, 8.0));
  const SystemMatrix copy = m;
  EXPECT_EQ(holder.brought, 2);
  EXPECT_EQ(copy.raw_values()[17], 8.0);
  // Moving keeps the array where it is, and elsewhere.
  holder.keep(m.raw_values(), std::vector<double>(18, 9.0));
  SystemMatrix moved = std::move(m);
  EXPECT_EQ(holder.brought, 2);
  EXPECT_EQ(moved.values()[0], 9.0);
  EXPECT_EQ(holder.brought, 3);
}

TEST_F(Residency, ZeroingAMatrixDropsItsNewerValues) {
  SystemMatrix m(MatrixPattern::from_csr(2, 2, {0, 1, 2}, {0, 1}), 3, 3);
  holder.keep(m.raw_values(), std::vector<double>(18, 7.0));
  m.set_zero();
  EXPECT_EQ(holder.brought, 0);
  EXPECT_EQ(holder.dropped, 1);
  EXPECT_EQ(m.values()[4], 0.0);
}

TEST_F(Residency, AFieldIsBroughtBackByItsAccessorsAndNotByItsRawOnes) {
  Set verts("verts");
  verts.add_many(20);
  verts.add_field("x", FieldType{ComponentKind::Float, {}, false});
  Field& x = verts.field(0);
  const uint64_t version = x.write_version();
  holder.keep(x.raw_bytes(), std::vector<double>(20, 7.0));
  EXPECT_EQ(x.write_version(), version + 1);  // the raw mutable access counts as a write
  EXPECT_EQ(reinterpret_cast<const double*>(std::as_const(x).raw_bytes())[3], 0.0);
  EXPECT_EQ(holder.brought, 0);
  EXPECT_EQ(*std::as_const(x).at<double>(3), 7.0);
  EXPECT_EQ(holder.brought, 1);
  // Growing the set copies the array into a larger one: from the newer contents.
  holder.keep(x.raw_bytes(), std::vector<double>(20, 8.0));
  verts.add_many(1000);
  EXPECT_EQ(holder.brought, 2);
  EXPECT_EQ(*std::as_const(verts).field(0).at<double>(19), 8.0);
  EXPECT_EQ(*std::as_const(verts).field(0).at<double>(20), 0.0);
}

TEST_F(Residency, BringBackAllEmptiesTheRegistry) {
  Tensor a = vector_of(100, 1.0), b = vector_of(50, 1.0);
  holder.keep(a.raw_mutable_floats(), std::vector<double>(100, 3.0));
  holder.keep(b.raw_mutable_floats(), std::vector<double>(50, 4.0));
  residency::bring_back_all_of(holder);
  EXPECT_EQ(holder.brought, 2);
  EXPECT_EQ(residency::count(), 0);
  EXPECT_EQ(a.raw_floats()[99], 3.0);
  EXPECT_EQ(b.raw_floats()[49], 4.0);
  // Settled: the holder drops it, and the host's copy stands.
  holder.keep(a.raw_mutable_floats(), std::vector<double>(100, 5.0));
  residency::settle(a.raw_floats());
  EXPECT_EQ(holder.dropped, 1);
  EXPECT_EQ(a.floats()[0], 3.0);
}

}  // namespace
}  // namespace simit::runtime
