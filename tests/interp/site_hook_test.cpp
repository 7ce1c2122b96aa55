// The executor seam (interp/assembly_plan.h): planned map sites are offered to a SiteHook,
// which may run them instead of the interpreter; nothing is offered while the trap point is
// armed; a site's matrix is reused once the program has dropped it.
#include "interp/frame.h"
#include "runtime/set.h"
#include "runtime/sparse_convert.h"
#include "test_util.h"

namespace simit::interp {
namespace {

namespace ast = frontend::ast;

constexpr const char* kProgram = R"(
element N
  m : float;
end
extern nodes : set{N};
func weigh(s : float, n : N) -> f : vector[nodes](float)
  f(n) = s * n.m;
end
func diag(n : N) -> K : matrix[nodes,nodes](float)
  K(n, n) = n.m;
end
export func forces(s : float) -> f : vector[nodes](float)
  f = map weigh(s) to nodes reduce +;
end
export func stiffness() -> t : float
  K = map diag to nodes reduce +;
  t = dot(K * nodes.m, nodes.m);  % sum of m^3
end
export func assembled() -> K : matrix[nodes,nodes](float)
  K = map diag to nodes reduce +;
end
export func doubled() -> (y : vector[nodes](float), s : float)
  y = 2.0 * nodes.m;
  s = 1.5;
end
)";

// Takes over every site of `weigh`, writing 100 + element index into the result (a value
// the interpreter would never produce), and records what it was handed.
class TakeOver : public SiteHook {
 public:
  bool run_site(SiteCall& call) override {
    ++offers;
    last_runs = call.plan.runs;
    if (call.plan.func->name != "weigh") return false;
    scale = call.partial_args.at(0).as_float();
    Tensor& f = call.results.at(0).tensor();
    for (size_t i = 0; i < f.size(); ++i) f.mutable_floats()[i] = 100.0 + static_cast<double>(i);
    return true;
  }
  int offers = 0;
  long last_runs = 0;
  double scale = 0.0;
};

// Takes over system-level statements: every one it is offered sets its target to 5.
class StatementTaker : public SiteHook {
 public:
  bool run_site(SiteCall&) override { return false; }
  bool run_statement(const ast::Stmt& stmt, ExecState& in) override {
    offered.push_back(&stmt);
    const auto& a = static_cast<const ast::Assign&>(stmt);
    const ast::Variable& y = *a.targets[0]->as<ast::VarRef>()->var;
    Tensor t(ComponentKind::Float, Shape{4});
    for (int i = 0; i < 4; ++i) t.mutable_floats()[i] = 5.0;
    in.variable(y) = Value::of_tensor(std::move(t));
    return true;
  }
  std::vector<const ast::Stmt*> offered;
};

class NoHook : public StatementHook {
 public:
  void before_statement(const ast::Stmt&, const ast::FuncDecl&, int, const Interpreter&) override {}
};

struct Fixture {
  explicit Fixture(Options options) : c(testing::compile(kProgram, "sites.sim")) {
    in = std::make_unique<Interpreter>(*c->program, options);
    nodes.add_many(4);
    for (const ast::Variable* v : c->program->globals)
      if (v && v->name == "nodes") {
        nodes.add_field("m", field_type_of(*v->type->element->fields[0].type));
        in->bind_set(*v, nodes);
      }
    for (int i = 0; i < 4; ++i) nodes.field("m").data<double>()[i] = 1.0 + i;
  }
  std::vector<Value> run(const char* f, std::vector<Value> args = {}) {
    return in->call(testing::func(*c, f), std::move(args));
  }
  std::unique_ptr<frontend::Compilation> c;
  runtime::Set nodes{"nodes"};
  std::unique_ptr<Interpreter> in;
};

TEST(SiteHook, HookRunsTheSiteInsteadOfTheInterpreter) {
  TakeOver hook;
  Options options;
  options.sites = &hook;
  Fixture fx(options);
  auto r = fx.run("forces", {Value::of_float(2.0)});
  ASSERT_EQ(r.size(), 1u);
  for (int i = 0; i < 4; ++i) EXPECT_EQ(r[0].tensor().floats()[i], 100.0 + i);
  EXPECT_EQ(hook.offers, 1);
  EXPECT_EQ(hook.scale, 2.0);
  EXPECT_EQ(hook.last_runs, 1);
  fx.run("forces", {Value::of_float(3.0)});
  EXPECT_EQ(hook.last_runs, 2);  // one plan per site, counting its runs
  // A site the hook declines runs interpreted: 1 + 8 + 27 + 64.
  auto k = fx.run("stiffness");
  EXPECT_EQ(k[0].as_float(), 100.0);
  EXPECT_EQ(hook.offers, 3);
}

TEST(SiteHook, SystemLevelStatementsAreOffered) {
  StatementTaker hook;
  Options options;
  options.sites = &hook;
  Fixture fx(options);
  auto r = fx.run("doubled");
  // Only `y = 2.0 * nodes.m` is system-level; `s = 1.5` ran interpreted.
  ASSERT_EQ(hook.offered.size(), 1u);
  for (int i = 0; i < 4; ++i) EXPECT_EQ(r[0].tensor().floats()[i], 5.0);
  EXPECT_EQ(r[1].as_float(), 1.5);
  // Without the hook the interpreter computes it: 2 m.
  Fixture plain(Options{});
  auto p = plain.run("doubled");
  for (int i = 0; i < 4; ++i) EXPECT_EQ(p[0].tensor().floats()[i], 2.0 * (1.0 + i));
}

TEST(SiteHook, ArmedTrapRunsEverySiteInterpreted) {
  TakeOver hook;
  NoHook statements;
  Trap trap;
  trap.install(&statements);
  Options options;
  options.sites = &hook;
  options.trap = &trap;
  Fixture fx(options);
  auto r = fx.run("forces", {Value::of_float(2.0)});
  for (int i = 0; i < 4; ++i) EXPECT_EQ(r[0].tensor().floats()[i], 2.0 * (1.0 + i));
  EXPECT_EQ(hook.offers, 0);
}

TEST(SiteHook, DroppedMatrixIsReusedAndZeroed) {
  Fixture fx(Options{});
  auto first = fx.run("assembled");
  const runtime::SystemMatrix* address = first[0].matrix().get();
  EXPECT_EQ(runtime::to_dense(*first[0].matrix())(0, 0), 1.0);
  first.clear();  // the host drops the matrix
  fx.nodes.field("m").data<double>()[0] = 7.0;
  // The second run gets the first run's matrix back, zeroed: K(0, 0) is the new mass, not
  // the sum of both runs.
  auto second = fx.run("assembled");
  EXPECT_EQ(second[0].matrix().get(), address);
  EXPECT_EQ(runtime::to_dense(*second[0].matrix())(0, 0), 7.0);
  EXPECT_EQ(runtime::to_dense(*second[0].matrix())(1, 1), 2.0);
  // Locals are released when the next activation at their depth starts, so a matrix held
  // only by a finished call's local is reused too.
  EXPECT_EQ(fx.run("stiffness")[0].as_float(), 343.0 + 8.0 + 27.0 + 64.0);
}

TEST(SiteHook, HeldMatrixIsNotReused) {
  constexpr const char* kHold = R"(
element N
  m : float;
end
extern nodes : set{N};
func diag(n : N) -> K : matrix[nodes,nodes](float)
  K(n, n) = n.m;
end
export func two() -> (a : matrix[nodes,nodes](float), b : matrix[nodes,nodes](float))
  a = map diag to nodes reduce +;
  b = map diag to nodes reduce +;
end
export func one() -> a : matrix[nodes,nodes](float)
  a = map diag to nodes reduce +;
end
)";
  auto c = testing::compile(kHold, "hold.sim");
  Interpreter in(*c->program);
  runtime::Set nodes("nodes");
  nodes.add_many(3);
  for (const ast::Variable* v : c->program->globals)
    if (v && v->name == "nodes") {
      nodes.add_field("m", field_type_of(*v->type->element->fields[0].type));
      in.bind_set(*v, nodes);
    }
  for (int i = 0; i < 3; ++i) nodes.field("m").data<double>()[i] = 2.0 + i;
  auto held = in.call(testing::func(*c, "one"), {});
  auto again = in.call(testing::func(*c, "one"), {});
  // `held` still holds the first matrix: the second map must not have overwritten it.
  EXPECT_NE(held[0].matrix().get(), again[0].matrix().get());
  EXPECT_EQ(runtime::to_dense(*held[0].matrix())(1, 1), 3.0);
  auto both = in.call(testing::func(*c, "two"), {});
  EXPECT_NE(both[0].matrix().get(), both[1].matrix().get());
  EXPECT_EQ(runtime::to_dense(*both[1].matrix())(2, 2), 4.0);
}

}  // namespace
}  // namespace simit::interp
