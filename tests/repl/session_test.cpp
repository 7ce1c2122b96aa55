// The REPL session driven directly: inputs in, printed output compared.
#include "repl/session.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <fstream>
#include <sstream>
#include <thread>

namespace simit::repl {
namespace {

struct Repl {
  std::ostringstream out, err;
  Session s{out, err};
  std::string feed(const std::string& text) {
    out.str("");
    err.str("");
    std::istringstream in(text);
    std::string line;
    while (std::getline(in, line)) s.feed_line(line);
    return out.str() + err.str();
  }
};

TEST(Session, ExpressionPrintsValueAndType) {
  Repl r;
  EXPECT_EQ(r.feed("1.0 + 2.0"), "3.0 : float\n");
  EXPECT_EQ(r.feed("[1.0, 2.0]'"), "[1.0, 2.0]' : vector[2](float)\n");
}

TEST(Session, DeclarationsThenCalls) {
  Repl r;
  EXPECT_EQ(r.feed("func twice(x : float) -> (y : float)\n  y = 2.0 * x;\nend"), "");
  EXPECT_EQ(r.feed("twice(4.0)"), "8.0 : float\n");
}

TEST(Session, VariablesPersist) {
  Repl r;
  EXPECT_EQ(r.feed("x = 3.0;"), "");
  EXPECT_EQ(r.feed("x = x + 1.0;"), "");
  EXPECT_EQ(r.feed("x"), "4.0 : float\n");
}

TEST(Session, MultiLineBlocks) {
  EXPECT_FALSE(Session::is_complete("func f()\n"));
  EXPECT_FALSE(Session::is_complete("x = [1.0,\n"));
  EXPECT_TRUE(Session::is_complete("extern func g(x : float);\n"));
  Repl r;
  r.feed("x = 1.0;");
  EXPECT_EQ(r.feed("if x > 0.0\n  x = 5.0;\nend"), "");
  EXPECT_EQ(r.feed("x"), "5.0 : float\n");
}

TEST(Session, ErrorsLeaveTheSessionAlive) {
  Repl r;
  std::string e = r.feed("y + 1.0");
  EXPECT_NE(e.find("<repl>:1:1: error:"), std::string::npos) << e;
  e = r.feed("func bad(\n) -> (z : float)\n  z = q;\nend");
  EXPECT_NE(e.find("<repl>:3:7: error:"), std::string::npos) << e;
  EXPECT_EQ(r.feed("2 + 3"), "5 : int\n");
}

TEST(Session, Commands) {
  Repl r;
  EXPECT_NE(r.feed(":help").find(":load"), std::string::npos);
  EXPECT_EQ(r.feed(":h :type"), "  :type EXPR            the type of an expression\n");
  EXPECT_EQ(r.feed(":type [1.0, 2.0]"), "vector[2](float)'\n");
  EXPECT_EQ(r.feed(":frob"), "unknown command ':frob' (:help lists the commands)\n");
  EXPECT_EQ(r.feed(":re"), "ambiguous command ':re': could be :reload :reset\n");
  r.feed("x = 1.0;");
  EXPECT_EQ(r.feed(":reset"), "");
  EXPECT_NE(r.feed("x").find("error"), std::string::npos);
  EXPECT_NE(r.feed(":load /nonexistent.sim").find("cannot read"), std::string::npos);
  EXPECT_EQ(r.s.completions(":rel"), std::vector<std::string>{":reload"});
  EXPECT_TRUE(r.s.feed_line(":help"));
  EXPECT_FALSE(r.s.feed_line(":q"));
}

TEST(Session, LoadAndReload) {
  std::string path = ::testing::TempDir() + "/repl_load_" + std::to_string(::getpid()) + ".sim";
  {
    std::ofstream f(path);
    f << "func half(x : float) -> (y : float)\n  y = x / 2.0;\nend\n";
  }
  Repl r;
  EXPECT_EQ(r.feed(":load " + path), "loaded " + path + "\n");
  EXPECT_EQ(r.feed("half(3.0)"), "1.5 : float\n");
  EXPECT_EQ(r.feed(":reload"), "reloaded 1 file(s)\n");
  EXPECT_EQ(r.s.completions("hal"), std::vector<std::string>{"half"});
}

// A scene as the `simit` tool would give it: a vertex set with a position field and a flag.
struct FakeScene {
  std::shared_ptr<runtime::Set> verts = std::make_shared<runtime::Set>("verts");
  FakeScene() {
    verts->add_many(3);
    verts->add_field("x", runtime::FieldType{runtime::ComponentKind::Float, {3}, false});
    verts->add_field("pinned", runtime::FieldType{runtime::ComponentKind::Bool, {}, false});
    for (int i = 0; i < 3; ++i)
      for (int d = 0; d < 3; ++d) verts->field(0).at<double>(i)[d] = i + 0.5 * d;
    verts->field(1).at<bool>(2)[0] = true;
  }
  SceneLoader loader(std::string program) {
    return [this, program](const std::string& path, bool, std::ostream&) {
      SceneData d;
      d.path = path;
      d.program_path = program;
      d.step = "lift";
      d.sets.emplace_back("verts", verts.get());
      d.tensors.emplace_back("dy", interp::Value::of_float(0.25));
      d.owner = verts;
      return std::optional<SceneData>(d);
    };
  }
};

std::string scene_program() {
  std::string path = ::testing::TempDir() + "/repl_scene_" + std::to_string(::getpid()) + ".sim";
  std::ofstream f(path);
  f << "element Vertex\n  x : vector[3](float);\n  pinned : bool;\nend\n"
       "extern verts : set{Vertex};\nextern dy : float;\n"
       "func lift_one(inout v : Vertex)\n  if not v.pinned\n    v.x(1) = v.x(1) + dy;\n  end\nend\n"
       "export func lift() -> (moved : int)\n  apply lift_one to verts;\n  moved = 2;\n  dy = 2.0 "
       "* dy;\nend\n";
  return path;
}

TEST(Session, SceneSetsFieldsAndRuns) {
  FakeScene scene;
  Repl r;
  r.s.set_scene_loader(scene.loader(scene_program()));
  EXPECT_NE(r.feed(":scene fake.toml").find("scene fake.toml: verts (3)"), std::string::npos);
  EXPECT_EQ(r.feed(":print verts.x[1]"), "[1.0, 1.5, 2.0] : vector[3](float)\n");
  EXPECT_EQ(r.feed(":print verts.pinned[2]"), "true : bool\n");
  EXPECT_EQ(r.feed(":fields verts"),
            "verts: 3 elements\n  x : vector[3](float)  min 0  max 3  NaN/Inf 0\n"
            "  pinned : bool  min 0  max 1  NaN/Inf 0\n");
  // lift adds dy (0.25) to x(1) of the unpinned vertices, then doubles dy: the extern tensor
  // keeps its new value for the next run.
  std::string run = r.feed(":run lift 2");
  EXPECT_NE(run.find("[2/2] lift: "), std::string::npos) << run;
  EXPECT_NE(run.find("moved = 2"), std::string::npos) << run;
  EXPECT_DOUBLE_EQ(scene.verts->field(0).at<double>(0)[1], 0.5 + 0.25 + 0.5);
  EXPECT_DOUBLE_EQ(scene.verts->field(0).at<double>(2)[1], 2.5);  // pinned
  EXPECT_EQ(r.feed("dy"), "1.0 : float\n");
  // Statements see the scene's sets too.
  EXPECT_EQ(r.feed("verts.pinned"), "[false, false, true]' : vector[verts](bool)\n");
  EXPECT_EQ(r.s.completions("verts.p"), std::vector<std::string>{"verts.pinned"});
  EXPECT_EQ(r.s.completions("ver"), std::vector<std::string>{"verts"});
  EXPECT_NE(r.feed(":print verts.x[3]").find("out of range"), std::string::npos);
}

// `:set executor jit` (or its former name, `:set backend jit`) is parsed once and reaches the
// `:run` engine whole: the JIT, compiling each site at its first execution (threshold 0, no
// eager compiles), with the interpreter's values; a bad value keeps the current setting.
TEST(Session, SetExecutorReachesTheEngine) {
  FakeScene scene;
  Repl r;
  r.s.set_scene_loader(scene.loader(scene_program()));
  r.feed(":scene fake.toml");
  EXPECT_EQ(r.s.options().executor.kind, ExecutorKind::Interpreter);
  std::string bad = r.feed(":set executor jti");
  EXPECT_EQ(bad,
            ":set executor: unknown executor 'jti': valid executors are interpreter, jit, gpu\n");
  EXPECT_EQ(r.s.options().executor.kind, ExecutorKind::Interpreter);
  if (!jit_available()) {
    EXPECT_EQ(r.feed(":set executor jit")
                  .rfind(":set executor: this build has no JIT: configure "
                         "with -DSIMIT_WITH_LLVM=ON",
                         0),
              0u);
    EXPECT_EQ(r.s.options().executor.kind, ExecutorKind::Interpreter);
    GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  }
  EXPECT_EQ(r.feed(":set executor jit"), "");
  const ExecutorChoice& x = r.s.options().executor;
  EXPECT_EQ(x.kind, ExecutorKind::Jit);
  EXPECT_EQ(x.threshold, 0);
  EXPECT_FALSE(x.eager);
  EXPECT_FALSE(x.check);
  EXPECT_EQ(r.feed(":set backend fast"),
            ":set backend: unknown executor 'fast': valid executors are interpreter, jit, gpu\n");
  EXPECT_EQ(r.s.options().executor.kind, ExecutorKind::Jit);
  std::string run = r.feed(":run lift 2");
  EXPECT_NE(run.find("moved = 2"), std::string::npos) << run;
  EXPECT_DOUBLE_EQ(scene.verts->field(0).at<double>(0)[1], 0.5 + 0.25 + 0.5);
  EXPECT_DOUBLE_EQ(scene.verts->field(0).at<double>(2)[1], 2.5);  // pinned
  // The apply compiled at its first run and ran compiled both times.
  std::string traces = r.feed(":jit");
  EXPECT_EQ(traces.rfind("jit traces:\n", 0), 0u) << traces;
  const size_t site = traces.find("\n  lift_one (line ");
  ASSERT_NE(site, std::string::npos) << traces;
  const std::string row = traces.substr(site + 1, traces.find('\n', site + 1) - site - 1);
  EXPECT_TRUE(row.ends_with("  compiled")) << row;
  std::istringstream fields(row.substr(row.find(')') + 1));
  double compile_ms = 0;
  long calls = 0;
  fields >> compile_ms >> calls;
  EXPECT_EQ(calls, 2) << row;
  EXPECT_EQ(r.feed(":set backend interpreter"), "");
  EXPECT_EQ(r.s.options().executor.kind, ExecutorKind::Interpreter);
  EXPECT_EQ(r.feed(":jit"), "no traces: :set executor jit, then :run a function\n");
}

// The calls of the `lift_one` trace in `:jit`'s table, or -1.
long lift_calls(Repl& r) {
  const std::string traces = r.feed(":jit");
  const size_t site = traces.find("\n  lift_one (line ");
  if (site == std::string::npos) return -1;
  const std::string row = traces.substr(site + 1, traces.find('\n', site + 1) - site - 1);
  std::istringstream fields(row.substr(row.find(')') + 1));
  double compile_ms = 0;
  long calls = -1;
  fields >> compile_ms >> calls;
  return calls;
}

// `:set threads N` (all, 0: every core) is parsed as --threads is, listed by `:set` alone, and
// reaches the `:run` engine: a new count is a new engine (its traces start over), with the
// same values; a bad count keeps the current one.
TEST(Session, SetThreadsReachesTheEngine) {
  FakeScene scene;
  Repl r;
  r.s.set_scene_loader(scene.loader(scene_program()));
  r.feed(":scene fake.toml");
  const int every_core = default_threads();
  EXPECT_EQ(r.s.options().executor.threads, every_core);
  EXPECT_EQ(r.feed(":set"),
            "float32 off\ncheck_finite off\nprint_limit 20\nexecutor "
            "interpreter\nthreads " +
                std::to_string(every_core) + "\n");
  EXPECT_EQ(r.feed(":set threads 3"), "");
  EXPECT_EQ(r.s.options().executor.threads, 3);
  EXPECT_EQ(r.feed(":set threads 1025"),
            ":set threads: bad thread count '1025': expected a whole number from 1 to 1024, or "
            "all (or 0): every core this process may use\n");
  EXPECT_EQ(r.feed(":set threads"),
            ":set needs an option and a value (float32 on|off, check_finite on|off, print_limit "
            "N, executor interpreter|jit|gpu, threads N|all)\n");
  EXPECT_EQ(r.s.options().executor.threads, 3);
  EXPECT_EQ(r.feed(":set threads all"), "");
  EXPECT_EQ(r.s.options().executor.threads, every_core);
  EXPECT_EQ(r.feed(":set threads 0"), "");
  EXPECT_EQ(r.s.options().executor.threads, every_core);
  // The interpreter runs serially whatever the count: lift adds dy (0.25, then 0.5).
  EXPECT_EQ(r.feed(":set threads 4"), "");
  EXPECT_NE(r.feed(":run lift 2").find("moved = 2"), std::string::npos);
  EXPECT_DOUBLE_EQ(scene.verts->field(0).at<double>(0)[1], 0.5 + 0.25 + 0.5);
  if (!jit_available()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  EXPECT_EQ(r.feed(":set executor jit"), "");
  EXPECT_EQ(r.s.options().executor.threads, 4);  // the kind changes, the count stays
  EXPECT_EQ(r.feed(":set"),
            "float32 off\ncheck_finite off\nprint_limit 20\nexecutor "
            "jit\nthreads 4\n");
  EXPECT_NE(r.feed(":run lift 2").find("moved = 2"), std::string::npos);
  EXPECT_EQ(lift_calls(r), 2);
  EXPECT_NE(r.feed(":run lift 1").find("moved = 2"), std::string::npos);
  EXPECT_EQ(lift_calls(r), 3);  // one engine while nothing changes
  EXPECT_EQ(r.feed(":set threads 2"), "");
  EXPECT_NE(r.feed(":run lift 1").find("moved = 2"), std::string::npos);
  EXPECT_EQ(lift_calls(r), 1);  // a new engine for the new count
  // dy, doubled by each run: 0.25, 0.5 interpreted; 1, 2, 4 and (2 threads) 8 compiled.
  EXPECT_DOUBLE_EQ(scene.verts->field(0).at<double>(0)[1], 0.5 + 0.25 + 0.5 + 1 + 2 + 4 + 8);
  EXPECT_DOUBLE_EQ(scene.verts->field(0).at<double>(2)[1], 2.5);  // pinned
}

TEST(Session, RuntimeErrorsNameTheInputLine) {
  Repl r;
  r.feed("v = [1.0, 2.0]';");
  // One input of four lines; the bad index is on its third.
  std::string e = r.feed("if true\n  w = 2.0 * v;\n  z = v(5);\nend");
  EXPECT_NE(e.find("<repl>:3:9: runtime error"), std::string::npos) << e;
  EXPECT_NE(e.find("runtime error"), std::string::npos) << e;
  EXPECT_EQ(r.feed("v(1)"), "2.0 : float\n");
}

TEST(Session, Options) {
  Repl r;
  EXPECT_EQ(r.feed(":set float32 on"), "");
  EXPECT_EQ(r.feed("1.0 / 3.0"), "0.3333333432674408 : float\n");  // binary32's 1/3
  EXPECT_EQ(r.feed(":set float32 off"), "");
  EXPECT_EQ(r.feed(":set check_finite on"), "");
  EXPECT_NE(r.feed("x = 0.0 / 0.0;").find("runtime error"), std::string::npos);
  EXPECT_NE(r.feed(":set float32 maybe").find("expected on or off"), std::string::npos);
  EXPECT_NE(r.feed(":set nope 1").find("no option 'nope'"), std::string::npos);
}

// Ctrl-C (Session::interrupt, from another thread here) stops an endless loop at its next
// statement; the variables keep their values from before the input.
TEST(Session, InterruptStopsARunAndKeepsTheSession) {
  if (!interp::kStatementHook)
    GTEST_SKIP() << "built with SIMIT_STATEMENT_HOOK=OFF: no trap point to interrupt at";
  Repl r;
  r.feed("i = 5;");
  std::thread stopper([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
    r.s.interrupt();
  });
  std::string e = r.feed("while true\n  i = i + 1;\nend");
  stopper.join();
  EXPECT_TRUE(e.starts_with("interrupted at <repl>:")) << e;
  EXPECT_EQ(r.feed("i"), "5 : int\n");
  // A stale request (Ctrl-C at the prompt) does not stop the next input.
  r.s.interrupt();
  EXPECT_EQ(r.feed("i + 1"), "6 : int\n");
}

TEST(Session, TimeRunsTheStatement) {
  Repl r;
  std::string t = r.feed(":time x = 6 * 7;");
  EXPECT_TRUE(t.starts_with("time: ")) << t;
  EXPECT_EQ(r.feed("x"), "42 : int\n");
}

}  // namespace
}  // namespace simit::repl
