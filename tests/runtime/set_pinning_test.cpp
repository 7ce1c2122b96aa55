// Pinned sets (Set::pin_fields): a field's array never moves once pinned, whatever reads or
// stores the whole field, while a tensor read earlier still keeps the values it was read with;
// growth is refused; pinning unshares an array a tensor shares. Also a program run by the
// interpreter on a pinned set: its whole-field stores land in the array that was there.
#include <gtest/gtest.h>

#include <complex>
#include <utility>

#include "frontend/frontend.h"
#include "interp/interpreter.h"
#include "runtime/set.h"

namespace simit::runtime {
namespace {

constexpr int kSize = 50;  // 150 doubles: the tensors of a whole field live on the heap

FieldType vec3_field() { return FieldType{ComponentKind::Float, {3}}; }

// A whole vec3 field's worth of components: component i is `first + i`.
Tensor ramp(int elements, double first) {
  Tensor t(ComponentKind::Float, Shape::blocked(std::vector<int>{elements}, Shape{3}));
  for (size_t i = 0; i < t.size(); ++i) t.mutable_floats()[i] = first + static_cast<double>(i);
  return t;
}

// A set `nodes` with a vec3 field x holding 0, 1, 2, ... and a scalar field m holding 0.5 e.
class PinnedSet : public ::testing::Test {
 protected:
  void SetUp() override {
    x_ = nodes_.add_field("x", vec3_field());
    m_ = nodes_.add_field("m", FieldType{ComponentKind::Float, {}});
    nodes_.add_many(kSize);
    double* x = nodes_.field(x_).data<double>();
    for (int i = 0; i < 3 * kSize; ++i) x[i] = i;
    double* m = nodes_.field(m_).data<double>();
    for (int e = 0; e < kSize; ++e) m[e] = 0.5 * e;
  }
  const Field& field(int f) const { return std::as_const(nodes_).field(f); }
  const double* x() const { return field(x_).data<double>(); }

  Set nodes_{"nodes"};
  int x_ = -1, m_ = -1;
};

TEST_F(PinnedSet, WholeFieldReadsAndStoresKeepTheArray) {
  EXPECT_FALSE(nodes_.fields_pinned());
  nodes_.pin_fields();
  EXPECT_TRUE(nodes_.fields_pinned());
  const double* array = x();

  // A read copies: the tensor has the values in its own block.
  Tensor read = nodes_.field_tensor(x_);
  EXPECT_EQ(read.shape(), Shape::blocked(std::vector<int>{kSize}, Shape{3}));
  EXPECT_NE(read.floats(), array);
  EXPECT_FALSE(field(x_).shared());
  for (int i = 0; i < 3 * kSize; ++i) ASSERT_EQ(read.floats()[i], i) << i;

  // A store copies into the array instead of adopting the tensor's block.
  Tensor other = ramp(kSize, 1000.0);
  nodes_.assign_field(x_, other);
  EXPECT_EQ(x(), array);
  EXPECT_NE(field(x_).buffer(), other.shared_buffer());
  for (int i = 0; i < 3 * kSize; ++i) ASSERT_EQ(x()[i], 1000.0 + i) << i;
  other.mutable_floats()[0] = -1.0;  // the tensor and the field are apart
  EXPECT_EQ(x()[0], 1000.0);

  // take_field leaves the array where it is (with its values); putting the tensor back
  // after a write copies the written values into that same array.
  Tensor taken = nodes_.take_field(x_);
  EXPECT_EQ(x(), array);
  EXPECT_EQ(x()[7], 1007.0);
  EXPECT_NE(taken.floats(), array);
  EXPECT_EQ(taken.floats()[7], 1007.0);
  taken.mutable_floats()[7] = 2.5;
  EXPECT_EQ(x()[7], 1007.0);
  nodes_.assign_field(x_, taken);
  EXPECT_EQ(x(), array);
  EXPECT_EQ(x()[7], 2.5);
  EXPECT_EQ(x()[8], 1008.0);
  // `S.x = S.x` on a pinned set: still the same array and values.
  nodes_.assign_field(x_, nodes_.field_tensor(x_));
  EXPECT_EQ(x(), array);
  EXPECT_EQ(x()[7], 2.5);
  // The element accessors write in place.
  Tensor v(ComponentKind::Float, Shape{3});
  v.mutable_floats()[1] = 9.0;
  nodes_.set(x_, 4, v);
  EXPECT_EQ(x(), array);
  EXPECT_EQ(x()[13], 9.0);
  EXPECT_EQ(nodes_.get(x_, 4).floats()[1], 9.0);
}

TEST_F(PinnedSet, ATensorReadBeforeAWriteKeepsTheOldValues) {
  nodes_.pin_fields();
  const double* array = x();
  Tensor before = nodes_.field_tensor(x_);
  Tensor m_before = nodes_.field_tensor(m_);
  nodes_.field(x_).data<double>()[5] = -5.0;
  nodes_.field(x_).at<double>(10)[0] = -30.0;
  nodes_.assign_field(m_, Tensor(ComponentKind::Float, Shape{kSize}));  // zeros
  EXPECT_EQ(before.floats()[5], 5.0);
  EXPECT_EQ(before.floats()[30], 30.0);
  EXPECT_EQ(m_before.floats()[3], 1.5);
  EXPECT_EQ(x(), array);
  EXPECT_EQ(x()[5], -5.0);
  EXPECT_EQ(x()[30], -30.0);
  EXPECT_EQ(field(m_).data<double>()[3], 0.0);
  // Writing through the tensor leaves the field alone.
  before.mutable_floats()[6] = 66.0;
  EXPECT_EQ(x()[6], 6.0);
}

TEST_F(PinnedSet, GrowthIsRefusedAndTheSetIsUnchanged) {
  Set edges("edges", {&nodes_, &nodes_});
  const int k = edges.add_field("k", FieldType{ComponentKind::Float, {}});
  edges.add({0, 1});
  nodes_.pin_fields();
  edges.pin_fields();
  const double* array = x();
  EXPECT_THROW(nodes_.add(), Fault);
  EXPECT_THROW(nodes_.add_many(3), Fault);
  EXPECT_THROW(edges.add({1, 2}), Fault);
  const int32_t flat[] = {2, 3, 3, 4};
  EXPECT_THROW(edges.add_edges(flat), Fault);
  EXPECT_EQ(nodes_.size(), kSize);
  EXPECT_EQ(edges.size(), 1);
  EXPECT_EQ(edges.endpoint(0, 1), 1);
  // Reserving is harmless: nothing moves.
  nodes_.reserve(10 * kSize);
  EXPECT_EQ(x(), array);
  EXPECT_EQ(x()[149], 149.0);
  EXPECT_EQ(std::as_const(edges).field(k).data<double>()[0], 0.0);
}

TEST_F(PinnedSet, PinningUnsharesAnArrayATensorShares) {
  Tensor shared = nodes_.field_tensor(x_);  // before pinning: shares the array
  ASSERT_TRUE(field(x_).shared());
  ASSERT_EQ(shared.floats(), x());
  nodes_.pin_fields();
  EXPECT_FALSE(field(x_).shared());
  EXPECT_NE(field(x_).buffer(), shared.shared_buffer());
  const double* array = x();
  EXPECT_NE(array, shared.floats());
  for (int i = 0; i < 3 * kSize; ++i) ASSERT_EQ(array[i], i) << i;
  // From now on writes stay in the array, and the earlier tensor keeps its values.
  nodes_.field(x_).data<double>()[0] = 42.0;
  nodes_.assign_field(x_, ramp(kSize, 500.0));
  EXPECT_EQ(x(), array);
  EXPECT_EQ(x()[1], 501.0);
  EXPECT_EQ(shared.floats()[0], 0.0);
  EXPECT_EQ(shared.floats()[1], 1.0);
  // An unshared field is left where it is by pinning.
  const double* m = field(m_).data<double>();
  EXPECT_EQ(m[4], 2.0);
}

TEST(PinnedSetKinds, ReadsCopyEveryComponentKindAndLateFieldsArePinned) {
  Set s("s");
  const int i = s.add_field("i", FieldType{ComponentKind::Int, {2}});
  const int b = s.add_field("b", FieldType{ComponentKind::Bool, {}});
  s.add_many(kSize);
  for (int e = 0; e < kSize; ++e) {
    s.field(i).at<int32_t>(e)[0] = e;
    s.field(i).at<int32_t>(e)[1] = -e;
    s.field(b).at<bool>(e)[0] = e % 3 == 0;
  }
  s.pin_fields();
  // A field added after pinning is pinned too (and starts at zero).
  const int c = s.add_field("c", FieldType{ComponentKind::Complex, {}});
  const int f = s.add_field("f", FieldType{ComponentKind::Float, {}, true});
  s.field(c).at<std::complex<double>>(7)[0] = {1.5, -2.5};
  s.field(f).at<float>(8)[0] = 0.25f;
  const std::byte* arrays[] = {std::as_const(s).field(i).bytes(), std::as_const(s).field(b).bytes(),
                               std::as_const(s).field(c).bytes(),
                               std::as_const(s).field(f).bytes()};

  Tensor ti = s.field_tensor(i), tb = s.field_tensor(b), tc = s.field_tensor(c);
  Tensor tf = s.field_tensor(f);
  EXPECT_EQ(ti.ints()[2 * 17], 17);
  EXPECT_EQ(ti.ints()[2 * 17 + 1], -17);
  EXPECT_TRUE(tb.bools()[9]);
  EXPECT_FALSE(tb.bools()[10]);
  EXPECT_EQ(tc.complexes()[7], std::complex<double>(1.5, -2.5));
  EXPECT_EQ(tf.floats()[8], 0.25);
  EXPECT_NE(reinterpret_cast<const std::byte*>(tc.complexes()), arrays[2]);
  EXPECT_FALSE(std::as_const(s).field(c).shared());

  ti.mutable_ints()[0] = 99;
  tb.mutable_bools()[1] = true;
  tc.mutable_complexes()[0] = {3.0, 4.0};
  tf.mutable_floats()[0] = 0.5;
  s.assign_field(i, ti);
  s.assign_field(b, tb);
  s.assign_field(c, tc);
  s.assign_field(f, tf);
  const std::byte* after[] = {std::as_const(s).field(i).bytes(), std::as_const(s).field(b).bytes(),
                              std::as_const(s).field(c).bytes(), std::as_const(s).field(f).bytes()};
  for (int k = 0; k < 4; ++k) EXPECT_EQ(after[k], arrays[k]) << k;
  EXPECT_EQ(std::as_const(s).field(i).data<int32_t>()[0], 99);
  EXPECT_TRUE(std::as_const(s).field(b).data<bool>()[1]);
  EXPECT_EQ(std::as_const(s).field(c).data<std::complex<double>>()[0],
            std::complex<double>(3.0, 4.0));
  EXPECT_EQ(std::as_const(s).field(f).data<float>()[0], 0.5f);
  EXPECT_THROW(s.add(), Fault);
}

// The interpreter on a pinned set: whole-field updates (`S.x = S.x + 1.0`, a stored vector,
// an apply) write into the arrays that were there, and a result read from a field keeps its
// values when the field changes later.
constexpr const char* kProgram = R"(
element Node
  x : vector[3](float);
  m : float;
end
extern nodes : set{Node};

export func bump()
  nodes.x = nodes.x + 1.0;
  nodes.m = nodes.m + 1.0;
end

export func store(y : vector[nodes](vector[3](float)))
  nodes.x = y;
end

export func doubled() -> before : vector[nodes](vector[3](float))
  before = nodes.x;
  nodes.x = 2.0 * nodes.x;
end

func scale(inout n : Node)
  n.x(2) = n.m * n.x(2);
end

export func scale_all()
  apply scale to nodes;
end
)";

class PinnedSetRun : public PinnedSet {
 protected:
  void SetUp() override {
    PinnedSet::SetUp();
    c_ = frontend::compile_source("pinned.sim", kProgram);
    ASSERT_TRUE(c_->ok()) << c_->diagnostics.render_all();
    nodes_.pin_fields();  // as a host that holds views pins before it binds
    in_ = std::make_unique<interp::Interpreter>(*c_->program);
    for (const auto* g : c_->program->globals)
      if (g && g->name == "nodes") in_->bind_set(*g, nodes_);
  }
  std::vector<interp::Value> run(const std::string& name, std::vector<interp::Value> args = {}) {
    return in_->call(*c_->program->find_func(name), std::move(args));
  }

  std::unique_ptr<frontend::Compilation> c_;
  std::unique_ptr<interp::Interpreter> in_;
};

TEST_F(PinnedSetRun, WholeFieldUpdatesWriteIntoThePinnedArrays) {
  const double* array = x();
  const double* m = field(m_).data<double>();
  run("bump");
  EXPECT_EQ(x(), array);
  EXPECT_EQ(field(m_).data<double>(), m);
  for (int i = 0; i < 3 * kSize; ++i) ASSERT_EQ(x()[i], i + 1.0) << i;
  for (int e = 0; e < kSize; ++e) ASSERT_EQ(m[e], 0.5 * e + 1.0) << e;

  run("store", {interp::Value::of_tensor(ramp(kSize, -100.0))});
  EXPECT_EQ(x(), array);
  for (int i = 0; i < 3 * kSize; ++i) ASSERT_EQ(x()[i], -100.0 + i) << i;

  std::vector<interp::Value> r = run("doubled");
  EXPECT_EQ(x(), array);
  const Tensor& before = r.at(0).tensor();
  EXPECT_NE(before.floats(), array);
  for (int i = 0; i < 3 * kSize; ++i) {
    ASSERT_EQ(before.floats()[i], -100.0 + i) << i;
    ASSERT_EQ(x()[i], 2.0 * (-100.0 + i)) << i;
  }

  run("scale_all");
  EXPECT_EQ(x(), array);
  // Element 4: x(2) was 2 * (-100 + 14), m is 0.5 * 4 + 1 = 3.
  EXPECT_EQ(x()[14], 3.0 * 2.0 * (-100.0 + 14));
  EXPECT_EQ(x()[13], 2.0 * (-100.0 + 13));
}

}  // namespace
}  // namespace simit::runtime
