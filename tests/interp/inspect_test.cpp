// The interpreter's debugger interface: frames and map contexts seen from a hook, values by
// Variable, evaluate() in a chosen frame (checked against values computed here from the same
// positions), the trap switch (installing and removing a hook during a run, after_statement)
// and interrupts, from another thread and from a signal handler.
#include <signal.h>
#include <sys/time.h>

#include <chrono>
#include <cmath>
#include <thread>

#include "frontend/debug_expr.h"
#include "interp/hook.h"
#include "runtime/set.h"
#include "test_util.h"

namespace simit::interp {
namespace {

namespace ast = frontend::ast;

const char* kProgram =
    "element Vertex\n"                                          // 1
    "  x : vector[3](float);\n"                                 // 2
    "end\n"                                                     // 3
    "element Tet\n"                                             // 4
    "  J : float;\n"                                            // 5
    "end\n"                                                     // 6
    "extern verts : set{Vertex};\n"                             // 7
    "extern tets : set{Tet}(verts, verts, verts, verts);\n"     // 8
    "func edges(v : (Vertex * 4)) -> D : matrix[3,3](float)\n"  // 9
    "  for j in 0:3\n"                                          // 10
    "    e = v(j).x - v(3).x;\n"                                // 11
    "    for i in 0:3\n"                                        // 12
    "      D(i, j) = e(i);\n"                                   // 13
    "    end\n"                                                 // 14
    "  end\n"                                                   // 15
    "end\n"                                                     // 16
    "func jacobian(inout t : Tet, v : (Vertex * 4))\n"          // 17
    "  D = edges(v);\n"                                         // 18
    "  t.J = det(D);\n"                                         // 19
    "end\n"                                                     // 20
    "export func step()\n"                                      // 21
    "  apply jacobian to tets;\n"                               // 22
    "end\n"                                                     // 23
    "export func spin() -> n : int\n"                           // 24
    "  while true\n"                                            // 25
    "    n = n + 1;\n"                                          // 26
    "  end\n"                                                   // 27
    "end\n";                                                    // 28

const double kPositions[5][3] = {
    {0.0, 0.0, 0.0}, {1.0, 0.1, 0.0}, {0.2, 1.1, 0.0}, {0.1, 0.3, 0.9}, {1.2, 1.0, 1.3}};
const int kTets[2][4] = {{0, 1, 2, 3}, {1, 2, 4, 3}};

// det [x0-x3, x1-x3, x2-x3], computed here.
double edge_det(const int* t) {
  double m[3][3];
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) m[r][c] = kPositions[t[c]][r] - kPositions[t[3]][r];
  return m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
         m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
         m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
}

// The program with its sets bound, run through an interpreter with a host-owned trap.
class Fixture {
 public:
  explicit Fixture(StatementHook* hook = nullptr)
      : c_(testing::compile(kProgram, "inspect.sim")),
        tets_("tets", {&verts_, &verts_, &verts_, &verts_}) {
    verts_.add_many(5);
    for (const auto& t : kTets) tets_.add({t[0], t[1], t[2], t[3]});
    Options o;
    o.trap = &trap_;
    if (hook) trap_.install(hook);
    in_ = std::make_unique<Interpreter>(*c_->program, o);
    bind("verts", verts_);
    bind("tets", tets_);
    double* x = verts_.field("x").data<double>();
    for (int i = 0; i < 5; ++i)
      for (int d = 0; d < 3; ++d) x[3 * i + d] = kPositions[i][d];
  }
  void bind(const std::string& name, runtime::Set& s) {
    const ast::Variable& v = global(name);
    for (const ast::FieldDecl& f : v.type->element->fields)
      s.add_field(f.name, field_type_of(*f.type));
    in_->bind_set(v, s);
  }
  const ast::Variable& global(const std::string& name) const {
    for (const ast::Variable* v : c_->program->globals)
      if (v && v->name == name) return *v;
    throw std::runtime_error("no global " + name);
  }
  std::vector<Value> run(const std::string& f) { return in_->call(testing::func(*c_, f), {}); }
  Interpreter& interp() { return *in_; }
  Trap& trap() { return trap_; }
  runtime::Set& tets() { return tets_; }

 private:
  std::unique_ptr<frontend::Compilation> c_;
  runtime::Set verts_{"verts"};
  runtime::Set tets_;
  Trap trap_;
  std::unique_ptr<Interpreter> in_;
};

int line(const ast::Stmt& s) { return s.span.start().line; }

// Evaluates debugger text in frame `level` of a paused run, as the debugger does.
Value eval_text(const Interpreter& in, int level, uint32_t offset, const std::string& text) {
  FrameView v = in.frame_view(level);
  frontend::DebugExpression e =
      frontend::check_debug_expression(in.program(), v.func, offset, text);
  if (!e.ok()) throw std::runtime_error(text + ": " + e.error);
  return in.evaluate(*e.expr, level);
}

// Looks at `t.J = det(D);` (line 19) of element 1 of the apply.
class Probe : public StatementHook {
 public:
  void before_statement(const ast::Stmt& stmt, const ast::FuncDecl& func, int depth,
                        const Interpreter& in) override {
    if (func.name == "jacobian" && line(stmt) == 18)
      activations.push_back(in.frame_view(0).activation);
    if (func.name != "jacobian" || line(stmt) != 19 || in.frame_view(0).map->element != 1) return;
    seen = true;
    depth_seen = depth;
    frames = in.frame_count();
    inner = in.frame_view(0);
    outer = in.frame_view(1);
    for (const ast::Param& p : func.params)
      if (p.name == "t") t_value = *in.frame_value(0, *p.var);
    const uint32_t at = stmt.span.begin;
    det = eval_text(in, 0, at, "det(D)").as_float();
    d21 = eval_text(in, 0, at, "D(2, 1)").as_float();
    is_one = eval_text(in, 0, at, "t == 1").as_bool();
    endpoint_x = eval_text(in, 0, at, "v(2).x(0)").as_float();
    global_x = eval_text(in, 1, outer.position.begin, "verts.x(4)(2)").as_float();
    try {
      eval_text(in, 0, at, "D(5, 0)");
    } catch (const RuntimeError& e) {
      bad_index = e.message();
    }
    // A program expression with a call is refused, not run.
    const auto& assign = *func.body.front()->as<ast::Assign>();
    try {
      in.evaluate(*assign.value, 0);
    } catch (const RuntimeError& e) {
      refused = e.message();
    }
  }
  bool seen = false;
  int depth_seen = -1, frames = 0;
  FrameView inner, outer;
  Value t_value;
  double det = 0, d21 = 0, endpoint_x = 0, global_x = 0;
  bool is_one = false;
  std::string bad_index, refused;
  std::vector<uint64_t> activations;
};

TEST(Inspect, FramesMapContextAndEvaluateInsideAnApply) {
  if (!kStatementHook) GTEST_SKIP() << "built with SIMIT_STATEMENT_HOOK=OFF";
  Probe probe;
  Fixture fx(&probe);
  fx.run("step");
  ASSERT_TRUE(probe.seen);
  EXPECT_EQ(probe.depth_seen, 1);
  EXPECT_EQ(probe.frames, 2);
  EXPECT_EQ(probe.inner.func->name, "jacobian");
  ASSERT_TRUE(probe.inner.map.has_value());
  const MapView& m = *probe.inner.map;
  EXPECT_TRUE(m.is_apply);
  EXPECT_EQ(m.element, 1);
  EXPECT_EQ(m.assembly->target_set->name, "tets");
  EXPECT_EQ(m.at.start().line, 22);
  ASSERT_EQ(m.endpoints.size(), 4u);
  for (int k = 0; k < 4; ++k) {
    EXPECT_EQ(m.endpoints[k].index, kTets[1][k]);
    ASSERT_NE(m.endpoints[k].set_var, nullptr);
    EXPECT_EQ(m.endpoints[k].set_var->name, "verts");
  }
  EXPECT_EQ(probe.inner.call_site.start().line, 22);
  EXPECT_EQ(probe.outer.func->name, "step");
  EXPECT_EQ(probe.outer.position.start().line, 22);
  EXPECT_FALSE(probe.outer.map.has_value());
  EXPECT_EQ(probe.t_value.kind(), Value::Kind::Element);
  EXPECT_EQ(probe.t_value.index(), 1);
  EXPECT_NEAR(probe.det, edge_det(kTets[1]), 1e-14);
  EXPECT_DOUBLE_EQ(probe.d21, kPositions[kTets[1][1]][2] - kPositions[kTets[1][3]][2]);
  EXPECT_TRUE(probe.is_one);
  EXPECT_DOUBLE_EQ(probe.endpoint_x, kPositions[kTets[1][2]][0]);
  EXPECT_DOUBLE_EQ(probe.global_x, kPositions[4][2]);
  EXPECT_NE(probe.bad_index.find("out of range"), std::string::npos) << probe.bad_index;
  EXPECT_NE(probe.refused.find("calls of user functions"), std::string::npos) << probe.refused;
  // Every element is its own activation.
  ASSERT_EQ(probe.activations.size(), 2u);
  EXPECT_NE(probe.activations[0], probe.activations[1]);
  // Inspection left the run intact: the results are the determinants.
  const double* J = fx.tets().field("J").data<double>();
  EXPECT_NEAR(J[0], edge_det(kTets[0]), 1e-14);
  EXPECT_NEAR(J[1], edge_det(kTets[1]), 1e-14);
}

TEST(Inspect, NothingRunsNoFrames) {
  Fixture fx;
  EXPECT_EQ(fx.interp().frame_count(), 0);
  EXPECT_EQ(fx.interp().frame_view(0).func, nullptr);
}

// Records the order of before and after events, and removes itself after `limit` events.
class Recorder : public StatementHook {
 public:
  Recorder(Trap* trap, int limit) : trap_(trap), limit_(limit) {}
  void before_statement(const ast::Stmt& s, const ast::FuncDecl&, int depth,
                        const Interpreter&) override {
    note("b", s, depth);
  }
  void after_statement(const ast::Stmt& s, const ast::FuncDecl&, int depth,
                       const Interpreter&) override {
    note("a", s, depth);
  }
  std::vector<std::string> events;

 private:
  void note(const char* what, const ast::Stmt& s, int depth) {
    events.push_back(std::string(what) + std::to_string(line(s)) + "@" + std::to_string(depth));
    if (static_cast<int>(events.size()) == limit_) trap_->install(nullptr);
  }
  Trap* trap_;
  int limit_;
};

TEST(Trap, AfterEventsCloseStatementsAndAHookMayRemoveItself) {
  if (!kStatementHook) GTEST_SKIP() << "built with SIMIT_STATEMENT_HOOK=OFF";
  auto c = testing::compile(
      "func g() -> r : int\n"                    // 1
      "  r = 2;\n"                               // 2
      "end\n"                                    // 3
      "export func f() -> (a : int, b : int)\n"  // 4
      "  a = g();\n"                             // 5
      "  b = a + 1;\n"                           // 6
      "end\n");
  Trap trap;
  Recorder all(&trap, -1);
  trap.install(&all);
  Options o;
  o.trap = &trap;
  Interpreter in(*c->program, o);
  std::vector<Value> r = in.call(testing::func(*c, "f"), {});
  EXPECT_EQ(all.events, (std::vector<std::string>{"b5@0", "b2@1", "a2@1", "a5@0", "b6@0", "a6@0"}));
  EXPECT_EQ(r[1].as_int(), 3);
  Recorder three(&trap, 3);
  trap.install(&three);
  in.call(testing::func(*c, "f"), {});
  EXPECT_EQ(three.events.size(), 3u);
  EXPECT_FALSE(trap.armed());
}

TEST(Trap, InterruptFromAnotherThreadStopsTheRunAndLeavesTheInterpreterUsable) {
  if (!kStatementHook) GTEST_SKIP() << "built with SIMIT_STATEMENT_HOOK=OFF";
  Fixture fx;
  std::thread ctrl_c([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    fx.trap().request_interrupt();
  });
  try {
    fx.run("spin");
    ADD_FAILURE() << "the loop was not interrupted";
  } catch (const Interrupted& e) {
    EXPECT_EQ(e.message(), "interrupted");
    EXPECT_EQ(e.line(), 26);  // the loop body: `n = n + 1;`
  }
  ctrl_c.join();
  EXPECT_FALSE(fx.trap().interrupt_pending());
  EXPECT_FALSE(fx.trap().armed());
  fx.run("step");  // the interpreter is usable again
  EXPECT_NEAR(fx.tets().field("J").data<double>()[1], edge_det(kTets[1]), 1e-14);
}

Trap* g_alarm_trap = nullptr;
extern "C" void on_alarm(int) {
  if (g_alarm_trap) g_alarm_trap->request_interrupt();
}

TEST(Trap, InterruptFromASignalHandler) {
  if (!kStatementHook) GTEST_SKIP() << "built with SIMIT_STATEMENT_HOOK=OFF";
  Fixture fx;
  g_alarm_trap = &fx.trap();
  struct sigaction sa {
  }, saved{};
  sa.sa_handler = on_alarm;
  sigemptyset(&sa.sa_mask);
  ASSERT_EQ(sigaction(SIGALRM, &sa, &saved), 0);
  itimerval timer{};
  timer.it_value.tv_usec = 30000;
  ASSERT_EQ(setitimer(ITIMER_REAL, &timer, nullptr), 0);
  EXPECT_THROW(fx.run("spin"), Interrupted);
  sigaction(SIGALRM, &saved, nullptr);
  g_alarm_trap = nullptr;
}

TEST(Trap, AStaleInterruptIsClearedByTakeInterrupt) {
  Trap trap;
  trap.request_interrupt();
  EXPECT_TRUE(trap.armed());
  EXPECT_TRUE(trap.take_interrupt());
  EXPECT_FALSE(trap.armed());
  EXPECT_FALSE(trap.take_interrupt());
}

}  // namespace
}  // namespace simit::interp
