// The frontend's analysis passes: the hoisting plan (frontend/hoisting.h) and the
// system-statement marks (frontend/system_statements.h), checked on hand-written programs.
#include <gtest/gtest.h>

#include "frontend/frontend.h"

namespace simit::frontend {
namespace {

namespace ast = frontend::ast;

std::unique_ptr<Compilation> compile(const char* text) {
  auto c = compile_source("analyses.sim", text);
  EXPECT_TRUE(c->ok()) << c->diagnostics.render_all();
  return c;
}

const ast::Block& body(const Compilation& c, const char* name) {
  const ast::FuncDecl* f = c.program->find_func(name);
  EXPECT_NE(f, nullptr);
  return f->body;
}

const ast::Expr& value_of(const ast::Stmt& s) { return *static_cast<const ast::Assign&>(s).value; }

TEST(Hoisting, NestedCallsRunFirstInnermostLeftToRight) {
  auto c = compile(R"(
func inc(x : float) -> y : float
  y = x + 1.0;
end
func twice(x : float) -> y : float
  y = 2.0 * x;
end
export func main() -> r : float
  a = 1.0;
  r = twice(inc(a)) + inc(a);
  r = inc(a);
  r = a + 1.0;
end
)");
  const ast::Block& b = body(*c, "main");
  // `twice(inc(a)) + inc(a)`: inc (inside twice), twice, then the right inc.
  const auto& h = value_of(*b[1]).hoisted;
  ASSERT_EQ(h.size(), 3u);
  EXPECT_EQ(h[0]->callee, "inc");
  EXPECT_EQ(h[1]->callee, "twice");
  EXPECT_EQ(h[2]->callee, "inc");
  EXPECT_EQ(h[0]->args[0]->kind, ast::NodeKind::VarRef);
  EXPECT_NE(h[0], h[2]);
  // A call that is the whole expression runs last anyway; no call, no plan.
  EXPECT_TRUE(value_of(*b[2]).hoisted.empty());
  EXPECT_TRUE(value_of(*b[3]).hoisted.empty());
}

TEST(SystemStatements, VectorUpdatesAndCallFreeLoopsAreMarked) {
  auto c = compile(R"(
element V
  m : float;
end
extern verts : set{V};
func one(p : V) -> o : vector[verts](float)
  o(p) = 1.0;
end
func scale(x : float) -> y : float
  y = 3.0 * x;
end
export func main() -> s : float
  var x = verts.m;
  alpha = 0.5;
  var k = 0;
  while k < 3
    x = x + alpha * x;
    k = k + 1;
  end
  o = map one to verts reduce +;
  s = scale(dot(x, o));
  y = 2.0 * x;
end
)");
  const ast::Block& b = body(*c, "main");
  ASSERT_EQ(b.size(), 7u);
  EXPECT_TRUE(b[0]->system_level);   // var x = verts.m
  EXPECT_FALSE(b[1]->system_level);  // a scalar
  EXPECT_FALSE(b[2]->system_level);
  EXPECT_TRUE(b[3]->system_level);  // the loop: vector updates, no calls
  const auto& loop = static_cast<const ast::While&>(*b[3]);
  EXPECT_TRUE(loop.body[0]->system_level);
  EXPECT_FALSE(loop.body[1]->system_level);
  EXPECT_FALSE(b[4]->system_level);  // a map runs user code
  EXPECT_FALSE(b[5]->system_level);  // so does a call
  EXPECT_TRUE(b[6]->system_level);
}

TEST(AssemblyWrites, TargetsIndexingSystemResultsAreMarked) {
  auto c = compile(R"(
element V
  m : float;
end
element E
  k : float;
end
extern verts : set{V};
extern edges : set{E}(verts, verts);
func both(e : E, p : (V * 2)) -> (f : vector[verts](vector[2](float)),
                                  K : matrix[verts,verts](matrix[2,2](float)))
  var local : vector[2](float);
  local(0) = e.k;
  f(p(0)) = local;
  K(p(0), p(1)) = [1.0, 0.0; 0.0, 1.0];
  K(p(1), p(0))(1, 1) = e.k;
end
func dense(x : float) -> (y : vector[2](float))
  y(0) = x;
end
)");
  const ast::Block& b = body(*c, "both");
  auto target = [&](size_t i) -> const ast::TensorRead& {
    return *static_cast<const ast::Assign&>(*b[i]).targets[0]->as<ast::TensorRead>();
  };
  EXPECT_EQ(target(1).assembles_result, -1);  // a local
  EXPECT_EQ(target(2).assembles_result, 0);   // f
  EXPECT_EQ(target(3).assembles_result, 1);   // K
  EXPECT_EQ(target(4).assembles_result, 1);   // a component of K's block
  const ast::Block& d = body(*c, "dense");
  // A result without a set dimension is not assembled.
  EXPECT_EQ(
      static_cast<const ast::Assign&>(*d[0]).targets[0]->as<ast::TensorRead>()->assembles_result,
      -1);
}

TEST(IndexRanges, LoopsAndRangingReadsOfAMatrixProduct) {
  auto c = compile(R"(
func matmul(A : matrix[2,3](float), B : matrix[3,2](float)) -> C : matrix[2,2](float)
  ivar i;
  ivar j;
  ivar k;
  C(i, j) = A(i, k) * B(k, j) + A(i, k) * B(k, j);
end
)");
  const ast::Block& b = body(*c, "matmul");
  const auto& a = static_cast<const ast::Assign&>(*b[3]);
  ASSERT_TRUE(a.index_notation);
  ASSERT_EQ(a.loop_free.size(), 2u);
  EXPECT_EQ(a.loop_free[0]->name, "i");
  EXPECT_EQ(a.loop_free[1]->name, "j");
  ASSERT_EQ(a.loop_reduction.size(), 1u);  // k once, though it appears four times
  EXPECT_EQ(a.loop_reduction[0]->name, "k");
  // The target, then the four reads of the value, left to right.
  ASSERT_EQ(a.ranging_reads.size(), 5u);
  EXPECT_EQ(a.ranging_reads[0], a.targets[0].get());
  EXPECT_EQ(static_cast<const ast::VarRef&>(*a.ranging_reads[1]->base).name, "A");
  EXPECT_EQ(static_cast<const ast::VarRef&>(*a.ranging_reads[2]->base).name, "B");
}

TEST(ExternUses, ThroughCallsMapsAndTypes) {
  auto c = compile(R"(
element V
  m : float;
end
element E
  k : float;
end
extern verts : set{V};
extern edges : set{E}(verts, verts);
extern scale : float;
extern unused : float;
func weigh(e : E, p : (V * 2)) -> f : vector[verts](float)
  f(p(0)) = scale * e.k;
end
func total() -> f : vector[verts](float)
  f = map weigh to edges reduce +;
end
export func main() -> s : float
  s = dot(total(), verts.m);
end
export func none() -> s : float
  s = 1.0;
end
)");
  auto names = [&](const char* f) {
    std::vector<std::string> out;
    for (const ast::Variable* v : c->program->find_func(f)->extern_uses) out.push_back(v->name);
    return out;
  };
  // In declaration order: the map's set and its endpoint set, the tensor the mapped
  // function reads; never `unused`.
  EXPECT_EQ(names("main"), (std::vector<std::string>{"verts", "edges", "scale"}));
  EXPECT_EQ(names("weigh"), (std::vector<std::string>{"verts", "scale"}));
  EXPECT_TRUE(names("none").empty());
}

}  // namespace
}  // namespace simit::frontend
