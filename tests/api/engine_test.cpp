// The engine, the one driver of every front end: a program compiled once and run many times
// with its bindings, globals and matrix patterns kept between calls, its options passed down
// (float32, print output, the trap point) and its run-time errors located.
#include "api/engine.h"

#include <gtest/gtest.h>

#include <sstream>

namespace simit::api {
namespace {

namespace ast = frontend::ast;
using interp::Value;

const char* kProgram = R"(
element Point
  x : float;
end
element Link
  k : float;
end
extern points : set{Point};
extern links : set{Link}(points, points);
extern scale : float;

func grow(inout p : Point)
  p.x = scale * p.x + 1.0;
end

func stiffness(l : Link, p : (Point * 2)) -> K : tensor[points, points](float)
  K(p(0), p(0)) = l.k;
  K(p(0), p(1)) = -l.k;
  K(p(1), p(0)) = -l.k;
  K(p(1), p(1)) = l.k;
end

export func step() -> (total : float)
  apply grow to points;
  scale = 2.0 * scale;
  total = points.x' * points.x;
end

export func assemble() -> (K : tensor[points, points](float))
  K = map stiffness to links reduce +;
end

export func third(a : float) -> (b : float)
  print a / 3.0;
  b = a / 3.0;
end

export func divide(n : int) -> (q : int)
  q = 7 / n;
end
)";

struct Fixture {
  std::shared_ptr<const CompiledProgram> compiled =
      CompiledProgram::from_source("engine_test.sim", kProgram);
  runtime::Set points{"points"};
  runtime::Set links{"links", {&points, &points}};

  Fixture() {
    points.add_many(3);
    points.add_field("x", runtime::FieldType{runtime::ComponentKind::Float, {}, false});
    const int32_t ends[] = {0, 1, 1, 2};
    links.add_edges(ends);
    links.add_field("k", runtime::FieldType{runtime::ComponentKind::Float, {}, false});
    for (int i = 0; i < 3; ++i) points.field(0).at<double>(i)[0] = i;  // 0, 1, 2
    links.field(0).at<double>(0)[0] = 10.0;
    links.field(0).at<double>(1)[0] = 20.0;
  }
  const ast::Variable& var(const char* name) const { return *compiled->find_extern(name); }
  const ast::FuncDecl& func(const char* name) const { return *compiled->find_func(name); }
  void bind(Engine& e) {
    e.bind_set(var("points"), points);
    e.bind_set(var("links"), links);
    e.set_global(var("scale"), Value::of_float(3.0));
  }
};

TEST(Engine, CompilesOnceAndFindsDeclarations) {
  Fixture f;
  ASSERT_TRUE(f.compiled->ok());
  EXPECT_NE(f.compiled->find_func("step"), nullptr);
  EXPECT_EQ(f.compiled->find_func("nosuch"), nullptr);
  EXPECT_EQ(f.compiled->find_extern("scale")->name, "scale");
  EXPECT_EQ(f.compiled->find_extern("grow"), nullptr);
  auto bad = CompiledProgram::from_source("bad.sim", "func f(\n");
  EXPECT_FALSE(bad->ok());
  EXPECT_TRUE(bad->compilation()->diagnostics.has_errors());
}

TEST(Engine, BindingsAndGlobalsPersistBetweenCalls) {
  Fixture f;
  Engine e(f.compiled);
  f.bind(e);
  // x = 3 x + 1 on 0, 1, 2 gives 1, 4, 7 (squares 66); then scale = 6: 7, 25, 43 (2523).
  EXPECT_DOUBLE_EQ(e.call(f.func("step"), {}).at(0).to_tensor().floats()[0], 66.0);
  EXPECT_DOUBLE_EQ(e.global(f.var("scale")).to_tensor().floats()[0], 6.0);
  EXPECT_DOUBLE_EQ(e.call(f.func("step"), {}).at(0).to_tensor().floats()[0], 2523.0);
  EXPECT_DOUBLE_EQ(f.points.field(0).at<double>(2)[0], 43.0);  // the host's set, in place
}

TEST(Engine, AssemblesAndKeepsPatternsAcrossCalls) {
  Fixture f;
  Engine e(f.compiled);
  f.bind(e);
  std::vector<Value> r = e.call(f.func("assemble"), {});
  const runtime::SystemMatrix& K = *r.at(0).matrix();
  EXPECT_DOUBLE_EQ(K.component(0, 0), 10.0);
  EXPECT_DOUBLE_EQ(K.component(1, 1), 30.0);
  EXPECT_DOUBLE_EQ(K.component(1, 2), -20.0);
  EXPECT_DOUBLE_EQ(K.component(0, 2), 0.0);
  const int builds = e.patterns().builds();
  e.call(f.func("assemble"), {});
  EXPECT_EQ(e.patterns().builds(), builds);  // the second assembly reuses the pattern
  EXPECT_EQ(e.stats().maps, 2);
  e.reset_stats();
  EXPECT_EQ(e.stats().maps, 0);
}

TEST(Engine, OptionsReachTheExecutor) {
  Fixture f;
  std::ostringstream printed;
  EngineOptions o;
  o.out = &printed;
  Engine wide(f.compiled, o);
  const double b64 =
      wide.call(f.func("third"), {Value::of_float(1.0)}).at(0).to_tensor().floats()[0];
  EXPECT_DOUBLE_EQ(b64, 1.0 / 3.0);
  EXPECT_FALSE(printed.str().empty());
  o.float32 = true;
  Engine narrow(f.compiled, o);
  const double b32 =
      narrow.call(f.func("third"), {Value::of_float(1.0)}).at(0).to_tensor().floats()[0];
  EXPECT_EQ(b32, static_cast<double>(1.0f / 3.0f));
}

TEST(Engine, RunTimeErrorsNameTheLine) {
  Fixture f;
  Engine e(f.compiled);
  try {
    e.call(f.func("divide"), {Value::of_int(0)});
    FAIL() << "expected a run-time error";
  } catch (const interp::RuntimeError& err) {
    EXPECT_EQ(err.line(), 39);
    EXPECT_NE(err.render().find("engine_test.sim:39:"), std::string::npos) << err.render();
  }
  EXPECT_EQ(e.call(f.func("divide"), {Value::of_int(2)}).at(0).to_tensor().ints()[0], 3);
}

// Declines every site it is offered (so the interpreter runs them) and records them.
class CountingSites : public interp::SiteHook {
 public:
  bool run_site(interp::SiteCall& call) override {
    ++offers;
    mapped = call.plan.func->name;
    return false;
  }
  int offers = 0;
  std::string mapped;
};

TEST(Engine, OffersMapSitesToTheExecutorSeam) {
  Fixture f;
  CountingSites sites;
  EngineOptions o;
  o.sites = &sites;
  Engine e(f.compiled, o);
  f.bind(e);
  std::vector<Value> r = e.call(f.func("assemble"), {});
  EXPECT_EQ(sites.offers, 1);
  EXPECT_EQ(sites.mapped, "stiffness");
  EXPECT_DOUBLE_EQ(r.at(0).matrix()->component(1, 1), 30.0);  // declined: the interpreter ran it
}

// A hook installed through the trap switch sees the engine's own interpreter.
class Counter : public interp::StatementHook {
 public:
  void before_statement(const ast::Stmt&, const ast::FuncDecl& func, int,
                        const interp::Interpreter& in) override {
    ++statements;
    seen = &in;
    if (func.name == "third") ++in_third;
  }
  int statements = 0, in_third = 0;
  const interp::Interpreter* seen = nullptr;
};

TEST(Engine, TheTrapPointReachesHooks) {
  if (!interp::kStatementHook) GTEST_SKIP() << "built without the trap point";
  Fixture f;
  interp::Trap trap;
  Counter counter;
  trap.install(&counter);
  std::ostringstream printed;
  EngineOptions o;
  o.trap = &trap;
  o.out = &printed;
  Engine e(f.compiled, o);
  e.call(f.func("third"), {Value::of_float(3.0)});
  EXPECT_EQ(counter.in_third, 2);  // print, assignment
  EXPECT_EQ(counter.seen, &e.interpreter());
}

}  // namespace
}  // namespace simit::api
