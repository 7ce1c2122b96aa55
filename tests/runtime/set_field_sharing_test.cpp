// Set fields share their arrays with tensors read from them (no copy) and copy on write,
// so a tensor read earlier keeps its values; whole-field stores adopt the tensor's array.
#include <gtest/gtest.h>

#include "runtime/set.h"

namespace simit::runtime {
namespace {

FieldType vec3_field(bool single = false) { return FieldType{ComponentKind::Float, {3}, single}; }

Tensor vec3(double a, double b, double c) {
  Tensor t(ComponentKind::Float, Shape{3});
  t.mutable_floats()[0] = a;
  t.mutable_floats()[1] = b;
  t.mutable_floats()[2] = c;
  return t;
}

TEST(SetFieldSharing, ReadingAFieldAsATensorSharesTheArray) {
  Set nodes("nodes");
  const int x = nodes.add_field("x", vec3_field());
  nodes.add_many(100);
  nodes.set(x, 7, vec3(1, 2, 3));
  const Field& f = std::as_const(nodes).field(x);
  const std::byte* array = f.bytes();
  Tensor t = nodes.field_tensor(x);
  EXPECT_EQ(t.shape(), Shape::blocked(std::vector<int>{100}, Shape{3}));
  EXPECT_EQ(t.shared_buffer(), f.buffer());
  EXPECT_EQ(reinterpret_cast<const std::byte*>(t.floats()), array);
  EXPECT_TRUE(f.shared());
  EXPECT_EQ(t.floats()[21], 1.0);
  EXPECT_EQ(t.floats()[23], 3.0);
  Tensor u = t;  // copies of the tensor share too
  EXPECT_EQ(u.floats(), t.floats());
}

TEST(SetFieldSharing, AWriteAfterAReadLeavesTheReadValueUnchanged) {
  Set nodes("nodes");
  const int x = nodes.add_field("x", vec3_field());
  nodes.add_many(100);
  nodes.set(x, 0, vec3(1, 2, 3));
  Tensor before = nodes.field_tensor(x);
  const double* old_array = before.floats();
  nodes.set(x, 0, vec3(4, 5, 6));          // Set::set copies first
  nodes.field(x).data<double>()[3] = 9.0;  // the array is now private: no copy
  nodes.field(x).at<double>(2)[0] = 8.0;
  EXPECT_EQ(before.floats(), old_array);
  EXPECT_EQ(before.floats()[0], 1.0);
  EXPECT_EQ(before.floats()[3], 0.0);
  EXPECT_EQ(before.floats()[6], 0.0);
  EXPECT_EQ(nodes.get(x, 0), vec3(4, 5, 6));
  EXPECT_EQ(nodes.get(x, 1).floats()[0], 9.0);
  EXPECT_NE(std::as_const(nodes).field(x).bytes(), reinterpret_cast<const std::byte*>(old_array));
  EXPECT_FALSE(std::as_const(nodes).field(x).shared());
  // Writing through the tensor copies it, not the field.
  Tensor again = nodes.field_tensor(x);
  again.mutable_floats()[0] = -1.0;
  EXPECT_EQ(nodes.get(x, 0), vec3(4, 5, 6));
}

TEST(SetFieldSharing, UnsharedWritesDoNotMoveTheArray) {
  Set nodes("nodes");
  const int x = nodes.add_field("x", vec3_field());
  nodes.add_many(10);
  const double* p = nodes.field(x).data<double>();
  { Tensor t = nodes.field_tensor(x); }  // released again
  nodes.set(x, 3, vec3(1, 1, 1));
  EXPECT_EQ(nodes.field(x).data<double>(), p);
}

TEST(SetFieldSharing, AssignFieldAdoptsTheTensorsArray) {
  Set nodes("nodes");
  const int x = nodes.add_field("x", vec3_field());
  nodes.add_many(50);
  Tensor v(ComponentKind::Float, Shape::blocked(std::vector<int>{50}, Shape{3}));
  for (size_t i = 0; i < v.size(); ++i) v.mutable_floats()[i] = static_cast<double>(i);
  nodes.assign_field(x, v);
  EXPECT_EQ(std::as_const(nodes).field(x).buffer(), v.shared_buffer());
  EXPECT_EQ(nodes.get(x, 2), vec3(6, 7, 8));
  // Writing the field now leaves v alone, and the other way round.
  nodes.set(x, 2, vec3(0, 0, 0));
  EXPECT_EQ(v.floats()[6], 6.0);
  Tensor w = nodes.field_tensor(x);
  nodes.assign_field(x, w);  // storing what was read is a no-op
  EXPECT_EQ(std::as_const(nodes).field(x).buffer(), w.shared_buffer());
  // Wrong size or kind.
  EXPECT_THROW(nodes.assign_field(x, vec3(1, 2, 3)), Fault);
  EXPECT_THROW(nodes.assign_field(x, Tensor(ComponentKind::Int, Shape{150})), Fault);
  // Any shape of the right size (a flat vector) is accepted, and small tensors are copied.
  Set few("few");
  const int y = few.add_field("y", FieldType{ComponentKind::Int, {}});
  few.add_many(3);
  Tensor small(ComponentKind::Int, Shape{3});
  small.mutable_ints()[1] = 5;
  few.assign_field(y, small);
  small.mutable_ints()[1] = 6;
  EXPECT_EQ(few.get(y, 1).ints()[0], 5);
}

TEST(SetFieldSharing, TakeFieldMovesTheArrayOutAndAssignFieldPutsItBack) {
  Set nodes("nodes");
  const int x = nodes.add_field("x", vec3_field());
  nodes.add_many(20);
  const double* p = std::as_const(nodes).field(x).data<double>();
  Tensor t = nodes.take_field(x);
  EXPECT_EQ(t.floats(), p);
  t.mutable_floats()[4] = 2.5;  // not shared: written in place
  EXPECT_EQ(t.floats(), p);
  nodes.assign_field(x, t);
  EXPECT_EQ(nodes.get(x, 1).floats()[1], 2.5);
  // Taken while a reader shares it: the write copies, the reader keeps its values.
  Tensor reader = nodes.field_tensor(x);
  Tensor taken = nodes.take_field(x);
  taken.mutable_floats()[4] = 7.0;
  nodes.assign_field(x, taken);
  EXPECT_EQ(reader.floats()[4], 2.5);
  EXPECT_EQ(nodes.get(x, 1).floats()[1], 7.0);
}

TEST(SetFieldSharing, GrowingKeepsValuesAndReadersIntact) {
  Set nodes("nodes");
  const int x = nodes.add_field("x", vec3_field());
  nodes.add_many(2);
  nodes.set(x, 1, vec3(1, 2, 3));
  Tensor before = nodes.field_tensor(x);
  for (int i = 0; i < 1000; ++i) nodes.add();
  EXPECT_EQ(nodes.get(x, 1), vec3(1, 2, 3));
  EXPECT_EQ(nodes.get(x, 1000), vec3(0, 0, 0));
  EXPECT_EQ(before.size(), 6u);
  EXPECT_EQ(before.floats()[5], 3.0);
  nodes.reserve(5000);
  EXPECT_EQ(nodes.get(x, 1), vec3(1, 2, 3));
}

TEST(SetFieldSharing, Float32FieldsAreReadAsConvertedCopies) {
  Set nodes("nodes");
  const int x = nodes.add_field("x", vec3_field(true));
  nodes.add_many(4);
  nodes.set(x, 1, vec3(0.5, 1.5, 2.5));
  Tensor t = nodes.field_tensor(x);
  EXPECT_EQ(t.kind(), ComponentKind::Float);
  EXPECT_EQ(t.floats()[4], 1.5);
  EXPECT_FALSE(std::as_const(nodes).field(x).shared());
  t.mutable_floats()[0] = 4.0;
  nodes.assign_field(x, t);
  EXPECT_EQ(nodes.field(x).data<float>()[0], 4.0f);
}

// The write version counts every way a field can change, and nothing that only reads it:
// caches derived from a field's values (the JIT's specialised patterns) compare it.
TEST(SetFieldSharing, TheWriteVersionChangesWithEveryWriteAndNoRead) {
  Set nodes("nodes");
  const int x = nodes.add_field("x", vec3_field());
  nodes.add_many(10);
  const Set& view = nodes;
  uint64_t v = view.field(x).write_version();
  auto changed = [&] {
    const uint64_t now = view.field(x).write_version();
    const bool moved = now != v;
    v = now;
    return moved;
  };
  (void)view.field(x).bytes();
  (void)view.field(x).data<double>();
  (void)nodes.get(x, 3);
  EXPECT_FALSE(changed()) << "reads";
  nodes.set(x, 3, vec3(1, 2, 3));
  EXPECT_TRUE(changed()) << "set";
  Tensor whole = nodes.field_tensor(x);
  EXPECT_FALSE(changed()) << "read as a tensor";
  nodes.field(x).data<double>()[0] = 5.0;
  EXPECT_TRUE(changed()) << "a mutable access (copying the array shared with `whole`)";
  nodes.assign_field(x, whole);
  EXPECT_TRUE(changed()) << "an adopted array";
  nodes.assign_field(x, nodes.field_tensor(x));
  EXPECT_FALSE(changed()) << "S.x = S.x";
  Tensor taken = nodes.take_field(x);
  EXPECT_TRUE(changed()) << "taken";
  nodes.assign_field(x, taken);
  EXPECT_TRUE(changed()) << "put back";
  nodes.add_many(5);
  EXPECT_TRUE(changed()) << "grown";
  // The array is still the one adopted from `whole`: element 3 as set, element 0 not 5.
  EXPECT_EQ(view.field(x).data<double>()[3 * 3 + 1], 2.0);
  EXPECT_EQ(view.field(x).data<double>()[0], 0.0);
}

}  // namespace
}  // namespace simit::runtime
