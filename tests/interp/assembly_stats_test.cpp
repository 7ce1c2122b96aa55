// Interpreter::stats(): outermost maps and applies are counted and timed once each (maps run
// inside a mapped function count with their outer map), statements outside maps add nothing,
// and reset_stats() starts over.
#include "runtime/set.h"
#include "test_util.h"

namespace simit::interp {
namespace {

namespace ast = frontend::ast;

const char* kProgram = R"(
element Node
  m : float;
end
extern nodes : set{Node};

func mass(n : Node) -> f : vector[nodes](float)
  f(n) = n.m;
end

func masses() -> f : vector[nodes](float)
  f = map mass to nodes reduce +;
end

% Runs a whole map for every element it is mapped over.
func via_inner_map(n : Node) -> f : vector[nodes](float)
  g = masses();
  f(n) = g(n);
end

func bump(inout n : Node)
  n.m = n.m + 1.0;
end

export func one_map() -> f : vector[nodes](float)
  f = map mass to nodes reduce +;
end

% A mapped function that maps again: one outermost map.
export func nested() -> f : vector[nodes](float)
  f = map via_inner_map to nodes reduce +;
end

export func map_and_apply()
  apply bump to nodes;
  f = map mass to nodes reduce +;
end

export func no_map() -> x : float
  x = 0.0;
  for i in 0:100
    x = x + 1.0;
  end
end
)";

class AssemblyStats : public ::testing::Test {
 protected:
  void SetUp() override {
    c_ = testing::compile(kProgram, "stats.sim");
    ASSERT_TRUE(c_->ok());
    in_ = std::make_unique<Interpreter>(*c_->program);
    nodes_.add_many(50);
    const ast::Variable* v = nullptr;
    for (const ast::Variable* g : c_->program->globals)
      if (g && g->name == "nodes") v = g;
    ASSERT_NE(v, nullptr);
    nodes_.add_field("m", field_type_of(*v->type->element->fields[0].type));
    in_->bind_set(*v, nodes_);
  }
  void run(const std::string& f) { in_->call(testing::func(*c_, f), {}); }

  std::unique_ptr<frontend::Compilation> c_;
  std::unique_ptr<Interpreter> in_;
  runtime::Set nodes_{"nodes"};
};

TEST_F(AssemblyStats, StartsAtZero) {
  EXPECT_EQ(in_->stats().maps, 0);
  EXPECT_EQ(in_->stats().assembly_seconds, 0.0);
}

TEST_F(AssemblyStats, CountsOutermostMapsAndApplies) {
  run("one_map");
  EXPECT_EQ(in_->stats().maps, 1);
  EXPECT_GT(in_->stats().assembly_seconds, 0.0);
  run("nested");
  EXPECT_EQ(in_->stats().maps, 2);
  run("map_and_apply");
  EXPECT_EQ(in_->stats().maps, 4);
}

TEST_F(AssemblyStats, StatementsOutsideMapsAreNotAssembly) {
  run("no_map");
  EXPECT_EQ(in_->stats().maps, 0);
  EXPECT_EQ(in_->stats().assembly_seconds, 0.0);
}

TEST_F(AssemblyStats, ResetStartsOver) {
  run("one_map");
  in_->reset_stats();
  EXPECT_EQ(in_->stats().maps, 0);
  EXPECT_EQ(in_->stats().assembly_seconds, 0.0);
  run("one_map");
  EXPECT_EQ(in_->stats().maps, 1);
}

}  // namespace
}  // namespace simit::interp
