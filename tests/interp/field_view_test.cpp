// Set fields read as vectors share the field's storage (LANGUAGE.md §6.12: copies only where
// the difference would show): `nodes.x` costs no copy, later field writes copy first, so a
// variable read earlier keeps its values; element reads and writes go to the array directly.
#include <utility>

#include "runtime/set.h"
#include "test_util.h"

namespace simit::interp {
namespace {

constexpr const char* kProgram = R"(
element Node
  x : vector[3](float);
  v : vector[3](float);
  m : float;
end
extern nodes : set{Node};

export func read() -> x : vector[nodes](vector[3](float))
  x = nodes.x;
end

export func read_then_write(inout e : Node) -> x : vector[nodes](vector[3](float))
  x = nodes.x;
  nodes.x(e) = [7.0, 8.0, 9.0]';
  e.m = 3.0;
end

export func read_then_element_write(inout e : Node) -> x : vector[nodes](vector[3](float))
  x = nodes.x;
  e.x(1) = -1.0;
end

export func step(h : float)
  nodes.x = nodes.x + h * nodes.v;
end

export func store(y : vector[nodes](vector[3](float)))
  nodes.x = y;
end

export func fill()
  nodes.m = 2.5;
end

func bump(inout n : Node)
  n.x(0) = n.x(0) + n.m;
  n.v = n.x;
end

export func bump_all() -> before : vector[nodes](vector[3](float))
  before = nodes.x;
  apply bump to nodes;
end

func twice(inout y : vector[nodes](vector[3](float)))
  y = 2.0 * y;
end

export func inout_field()
  twice(nodes.x);
end
)";

class FieldView : public ::testing::Test {
 protected:
  void SetUp() override {
    c_ = testing::compile(kProgram, "field_view.sim");
    in_ = std::make_unique<Interpreter>(*c_->program);
    x_ = nodes_.add_field("x", runtime::FieldType{ComponentKind::Float, {3}});
    v_ = nodes_.add_field("v", runtime::FieldType{ComponentKind::Float, {3}});
    m_ = nodes_.add_field("m", runtime::FieldType{ComponentKind::Float, {}});
    nodes_.add_many(kSize);
    double* x = nodes_.field(x_).data<double>();
    double* v = nodes_.field(v_).data<double>();
    for (int i = 0; i < 3 * kSize; ++i) {
      x[i] = i;
      v[i] = 100.0 + i;
    }
    in_->bind_set(nodes_var(), nodes_);
  }
  std::vector<Value> run(const std::string& f, std::vector<Value> args = {}) {
    return in_->call(testing::func(*c_, f), std::move(args));
  }
  const runtime::Field& field(int f) const { return std::as_const(nodes_).field(f); }
  const frontend::ast::Variable& nodes_var() const {
    for (const auto* g : c_->program->globals)
      if (g && g->name == "nodes") return *g;
    throw std::runtime_error("no extern nodes");
  }
  Value element(int e) { return Value::of_element(in_->global(nodes_var()).binding(), e); }

  static constexpr int kSize = 50;  // 150 doubles: larger than a tensor's inline storage
  std::unique_ptr<frontend::Compilation> c_;
  std::unique_ptr<Interpreter> in_;
  runtime::Set nodes_{"nodes"};
  int x_ = -1, v_ = -1, m_ = -1;
};

TEST_F(FieldView, ReadingAFieldAsAVectorSharesItsStorage) {
  const std::byte* array = field(x_).bytes();
  std::vector<Value> r = run("read");
  ASSERT_TRUE(r[0].is_tensor());
  const Tensor& x = r[0].tensor();
  EXPECT_EQ(x.shape(), Shape::blocked(std::vector<int>{kSize}, Shape{3}));
  // No copy: the result is the field's own array.
  EXPECT_EQ(x.shared_buffer(), field(x_).buffer());
  EXPECT_EQ(reinterpret_cast<const std::byte*>(x.floats()), array);
  EXPECT_EQ(x.floats()[4], 4.0);
}

TEST_F(FieldView, AWriteAfterAReadLeavesTheReadValueUnchanged) {
  std::vector<Value> r = run("read_then_write", {element(2)});
  const Tensor& x = r[0].tensor();
  EXPECT_EQ(x.floats()[6], 6.0);
  EXPECT_EQ(x.floats()[8], 8.0);
  EXPECT_NE(x.shared_buffer(), field(x_).buffer());
  EXPECT_EQ(field(x_).data<double>()[6], 7.0);
  EXPECT_EQ(field(x_).data<double>()[8], 9.0);
  EXPECT_EQ(field(x_).data<double>()[5], 5.0);
  EXPECT_EQ(field(m_).data<double>()[2], 3.0);

  r = run("read_then_element_write", {element(3)});
  EXPECT_EQ(r[0].tensor().floats()[10], 10.0);
  EXPECT_EQ(field(x_).data<double>()[10], -1.0);
}

TEST_F(FieldView, AResultHeldByTheHostKeepsItsValuesWhenTheFieldChanges) {
  std::vector<Value> r = run("read");
  EXPECT_TRUE(field(x_).shared());
  nodes_.field(x_).data<double>()[0] = 42.0;  // a host write copies first
  EXPECT_EQ(r[0].tensor().floats()[0], 0.0);
  EXPECT_EQ(field(x_).data<double>()[0], 42.0);
}

TEST_F(FieldView, UpdateOfAWholeFieldIsCorrectAndAdoptsTheNewValue) {
  run("step", {Value::of_float(0.5)});
  const double* x = field(x_).data<double>();
  for (int i = 0; i < 3 * kSize; ++i) ASSERT_EQ(x[i], i + 0.5 * (100.0 + i)) << i;
  EXPECT_EQ(field(v_).data<double>()[7], 107.0);
  EXPECT_FALSE(field(x_).shared());  // the temporary was adopted and released

  std::vector<Value> r = run("read");
  Tensor y = r[0].tensor();  // shares the field
  r.clear();
  y.mutable_floats()[0] = -5.0;  // copies: the field keeps its values
  EXPECT_EQ(field(x_).data<double>()[0], 50.0);
  run("store", {Value::of_tensor(y)});
  EXPECT_EQ(field(x_).buffer(), y.shared_buffer());  // stored without a copy
  EXPECT_EQ(field(x_).data<double>()[0], -5.0);
  EXPECT_EQ(y.floats()[0], -5.0);
  nodes_.field(x_).data<double>()[0] = 1.0;  // the host's write leaves the caller's y alone
  EXPECT_EQ(y.floats()[0], -5.0);
}

TEST_F(FieldView, BroadcastApplyAndInoutWritesLandInTheField) {
  run("fill");
  for (int e = 0; e < kSize; ++e) ASSERT_EQ(field(m_).data<double>()[e], 2.5);
  std::vector<Value> r = run("bump_all");
  for (int e = 0; e < kSize; ++e) {
    ASSERT_EQ(field(x_).data<double>()[3 * e], 3 * e + 2.5);
    ASSERT_EQ(field(v_).data<double>()[3 * e + 1], 3 * e + 1.0);
    ASSERT_EQ(r[0].tensor().floats()[3 * e], 3 * e);  // read before the apply
  }
  run("inout_field");
  EXPECT_EQ(field(x_).data<double>()[4], 8.0);
  EXPECT_EQ(field(x_).data<double>()[0], 5.0);
}

TEST_F(FieldView, Float32FieldsStillWork) {
  runtime::Set small("nodes");
  small.add_field("x", runtime::FieldType{ComponentKind::Float, {3}, true});
  small.add_field("v", runtime::FieldType{ComponentKind::Float, {3}, true});
  small.add_field("m", runtime::FieldType{ComponentKind::Float, {}, true});
  small.add_many(4);
  small.field(1).data<float>()[3] = 2.0f;
  in_->bind_set(nodes_var(), small);
  in_->call(testing::func(*c_, "step"), {Value::of_float(0.5)});
  EXPECT_EQ(small.field(0).data<float>()[3], 1.0f);
  std::vector<Value> r = in_->call(testing::func(*c_, "read_then_write"), {element(1)});
  EXPECT_EQ(r[0].tensor().floats()[3], 1.0);
  EXPECT_EQ(small.field(0).data<float>()[3], 7.0f);
  EXPECT_EQ(small.field(2).data<float>()[1], 3.0f);
}

}  // namespace
}  // namespace simit::interp
