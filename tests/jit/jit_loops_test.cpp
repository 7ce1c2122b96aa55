// Solver loops against the interpreter: loops with ifs and error statements, runs of
// statements compiled as one trace with their loop, float32 runs, and an interrupt that stops a
// compiled loop at an iteration boundary.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <future>
#include <limits>
#include <sstream>
#include <thread>

#include "api/engine.h"
#include "jit_test_support.h"

namespace simit::jit {
namespace {

using namespace test_support;  // also ast, Value and the engine API's names

// ---------------------------------------------------------------------------
// Solver loops with ifs (jit/system_trace.cpp): a preconditioned CG whose body tests p'Ap,
// counts slow iterations, may stop with an error statement at an iteration the host chooses,
// and restarts its search direction once (a vector update in a branch).

const char* const kPcg = R"(element Point
  b : vector[3](float);
  d : float;
end
element Link
  k : float;
end
extern points : set{Point};
extern links : set{Link}(points, points);
extern stop_at : int;

const eye3 = [1.0, 0.0, 0.0; 0.0, 1.0, 0.0; 0.0, 0.0, 1.0];
const offd = [0.0, 1.0, 0.0; 1.0, 0.0, 0.0; 0.0, 0.0, 0.5];

func stiffness(l : Link, p : (Point * 2)) -> A : matrix[points,points](matrix[3,3](float))
  A(p(0), p(0)) = l.k * eye3;
  A(p(1), p(1)) = l.k * eye3;
  A(p(0), p(1)) = (-0.5 * l.k) * eye3;
  A(p(1), p(0)) = (-0.5 * l.k) * eye3;
end

func diagonal(q : Point) -> D : matrix[points,points](matrix[3,3](float))
  D(q, q) = q.d * eye3 + 0.1 * offd;
end

func jacobi(A : matrix[points,points](matrix[3,3](float)), q : Point)
    -> Pc : matrix[points,points](matrix[3,3](float))
  Pc(q, q) = inv(A(q, q));
end

export func solve() -> (x : vector[points](vector[3](float)), iterations : int, rz : float,
                        slow : int, fast : float)
  A = (map stiffness to links reduce +) + (map diagonal to points reduce +);
  Pc = map jacobi(A) to points reduce +;
  b = points.b;
  var r = b;
  var z = Pc * r;
  var p = z;
  rz = r' * z;
  var going = rz > 1.0e-24;
  while going
    Ap = A * p;
    pAp = p' * Ap;
    if pAp <= 0.0
      error "CG breakdown: p'Ap = ", pAp, " <= 0 at CG iteration ", iterations;
    end
    alpha = rz / pAp;
    x = x + alpha * p;
    r = r - alpha * Ap;
    z = Pc * r;
    rz_new = r' * z;
    if rz_new > 0.05 * rz
      slow = slow + 1;
    elif iterations == 1
      fast = fast - 1.0;
    else
      fast = max(fast, rz_new / rz);
    end
    if iterations == stop_at
      error "stopped at CG iteration ", iterations, " with r'z = ", rz_new;
    end
    if iterations == 4
      p = z;
    else
      p = z + (rz_new / rz) * p;
    end
    rz = rz_new;
    iterations = iterations + 1;
    going = (rz > 1.0e-24) and (iterations < 60);
  end
end
)";

struct PcgRun {
  std::vector<std::vector<Value>> results;  // per call that returned
  std::string error, stats, dump;
};

// Calls `solve` once per entry of `stops` (the iteration its error statement fires at, -1
// for none) on one engine; the first error ends the run.
PcgRun run_pcg(ExecutorKind kind, bool check, const std::vector<int>& stops) {
  auto compiled = CompiledProgram::from_source("pcg.sim", kPcg);
  EXPECT_TRUE(compiled->ok());
  runtime::Set points("points");
  runtime::Set links("links", {&points, &points});
  const int n = 30;
  points.add_many(n);
  points.add_field("b", runtime::FieldType{runtime::ComponentKind::Float, {3}, false});
  points.add_field("d", runtime::FieldType{runtime::ComponentKind::Float, {}, false});
  links.add_field("k", runtime::FieldType{runtime::ComponentKind::Float, {}, false});
  for (int i = 0; i < n; ++i) {
    for (int c = 0; c < 3; ++c) points.field(0).at<double>(i)[c] = std::sin(0.3 * i + c);
    points.field(1).at<double>(i)[0] = 0.2 + 0.01 * i;
    if (i + 1 < n) links.add({i, i + 1});
  }
  for (int e = 0; e < links.size(); ++e) links.field(0).at<double>(e)[0] = 1.0 + 0.5 * std::cos(e);
  EngineOptions o;
  o.executor.kind = kind;
  o.executor.threshold = 0;
  o.executor.check = check;
  std::ostringstream dump;
  o.dump = &dump;
  o.executor.dump_loop_ir = true;
  Engine engine(compiled, o);
  engine.bind_set(*compiled->find_extern("points"), points);
  engine.bind_set(*compiled->find_extern("links"), links);
  PcgRun run;
  for (int stop : stops) {
    engine.set_global(*compiled->find_extern("stop_at"), Value::of_int(stop));
    try {
      run.results.push_back(engine.call(*compiled->find_func("solve"), {}));
    } catch (const interp::RuntimeError& e) {
      run.error = e.render();
      break;
    }
  }
  std::ostringstream os;
  engine.print_jit_stats(os);
  run.stats = os.str();
  run.dump = dump.str();
  return run;
}

// The stats line of the trace that runs the while loop at `line`: the loop alone, or a run
// of statements whose lines hold it.
std::string loop_stats(const std::string& stats, int line) {
  std::istringstream in(stats);
  std::string l;
  while (std::getline(in, l)) {
    int first = 0, last = 0;
    if (l.find("  while (line " + std::to_string(line) + ")") == 0 ||
        (std::sscanf(l.c_str(), "  statements (lines %d-%d)", &first, &last) == 2 &&
         first <= line && line <= last))
      return l;
  }
  return "";
}

void expect_same_pcg_results(const std::vector<Value>& a, const std::vector<Value>& b) {
  ASSERT_EQ(a.size(), 5u);
  ASSERT_EQ(b.size(), 5u);
  expect_same(a[0], b[0], "x");
  EXPECT_EQ(a[1].as_int(), b[1].as_int());
  const double rz[2] = {a[2].as_float(), b[2].as_float()};
  expect_same_bits(&rz[0], &rz[1], 1, "rz");
  EXPECT_EQ(a[3].as_int(), b[3].as_int());
  const double fast[2] = {a[4].as_float(), b[4].as_float()};
  expect_same_bits(&fast[0], &fast[1], 1, "fast");
}

TEST(Jit, ALoopWithIfsOnScalarsIsCompiledAndComputesTheInterpretersBits) {
  if (!api::jit_available()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  const PcgRun in = run_pcg(ExecutorKind::Interpreter, false, {-1, -1});
  const PcgRun jit = run_pcg(ExecutorKind::Jit, false, {-1, -1});
  ASSERT_EQ(in.error, "");
  ASSERT_EQ(jit.error, "");
  const std::string loop = loop_stats(jit.stats, line_of(kPcg, "while going"));
  EXPECT_NE(loop.find(" compiled"), std::string::npos) << jit.stats;
  EXPECT_NE(loop.find(" 2 "), std::string::npos) << loop;  // both calls ran the kernel
  // The set-up from `b = points.b` is in the loop's run: `var going = rz > ...` (scalars
  // alone) joins it.
  EXPECT_EQ(loop.find("  statements (lines " + std::to_string(line_of(kPcg, "b = points.b")) + "-"),
            0u)
      << jit.stats;
  for (int call = 0; call < 2; ++call) expect_same_pcg_results(in.results[call], jit.results[call]);
  // The restart's two updates of p are passes under guards; the breakdown test is an if in a
  // scalar op.
  const std::string loop_ir = jit.dump.substr(jit.dump.find("system trace"));
  const size_t guarded = loop_ir.find(" when %");
  ASSERT_NE(guarded, std::string::npos) << loop_ir;
  const size_t line = loop_ir.rfind('\n', guarded) + 1;
  EXPECT_EQ(loop_ir.compare(line, 13, "    pass over"), 0) << loop_ir.substr(line, guarded - line);
  EXPECT_NE(loop_ir.find("check false else error 0"), std::string::npos) << loop_ir;
  // The branches ran: CG took real iterations, some slow and some not.
  const std::vector<Value>& r = in.results[0];
  EXPECT_GT(r[1].as_int(), 5);
  EXPECT_GT(r[3].as_int(), 0);
  EXPECT_LT(r[3].as_int(), r[1].as_int());
}

TEST(Jit, AnErrorStatementInACompiledLoopIsReportedAsTheInterpreterReportsIt) {
  if (!api::jit_available()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  // The first call stops at iteration 3; the engine then solves without stopping.
  for (bool check : {false, true}) {
    const PcgRun in = run_pcg(ExecutorKind::Interpreter, false, {3});
    const PcgRun jit = run_pcg(ExecutorKind::Jit, check, {3});
    const PcgRun jit_after = run_pcg(ExecutorKind::Jit, check, {-1, 3, -1});
    const PcgRun in_after = run_pcg(ExecutorKind::Interpreter, false, {-1, 3, -1});
    // The message prints the loop's state at iteration 3: the interpreter ran the loop from
    // the state before the kernel's call, which the controller put back.
    const std::string where = "pcg.sim:" + std::to_string(line_of(kPcg, "error \"stopped")) + ":";
    EXPECT_EQ(in.error.rfind(where, 0), 0u) << in.error;
    EXPECT_NE(in.error.find("runtime error: stopped at CG iteration 3 with r'z = "),
              std::string::npos)
        << in.error;
    EXPECT_EQ(jit.error, in.error);
    EXPECT_EQ(jit_after.error, in.error);
    EXPECT_EQ(in_after.error, in.error);
    ASSERT_EQ(jit_after.results.size(), 1u);
    expect_same_pcg_results(in_after.results[0], jit_after.results[0]);
    const std::string loop = loop_stats(jit.stats, line_of(kPcg, "while going"));
    EXPECT_NE(loop.find(" compiled"), std::string::npos) << jit.stats;
    EXPECT_NE(jit.stats.find("1 call reached an error statement and ran again interpreted"),
              std::string::npos)
        << jit.stats;
  }
}

TEST(Jit, CheckModeComparesALoopWithIfs) {
  if (!api::jit_available()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  const PcgRun in = run_pcg(ExecutorKind::Interpreter, false, {-1, -1});
  const PcgRun jit = run_pcg(ExecutorKind::Jit, true, {-1, -1});
  ASSERT_EQ(jit.error, "");
  const std::string loop = loop_stats(jit.stats, line_of(kPcg, "while going"));
  EXPECT_NE(loop.find(" compiled"), std::string::npos) << jit.stats;
  for (int call = 0; call < 2; ++call) expect_same_pcg_results(in.results[call], jit.results[call]);
}

// A loop without products whose error statement fires on two calls: both hand the loop back,
// and the stats say so once.
const char* const kHalving = R"(element P
  b : float;
end
extern ps : set{P};

export func main()
  b = ps.b;
  var x = 0.0 * b;
  var k = 0;
  while k < 10
    x = x + b;
    if x' * x > 40.0
      x = 0.5 * x;
      error "x'x = ", x' * x, " after halving at k = ", k;
    end
    k = k + 1;
  end
end
)";

TEST(Jit, EveryCallThatReachesAnErrorStatementIsHandedBack) {
  if (!api::jit_available()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  auto compiled = CompiledProgram::from_source("halving.sim", kHalving);
  ASSERT_TRUE(compiled->ok());
  runtime::Set ps("ps");
  ps.add_many(2);
  ps.add_field("b", runtime::FieldType{runtime::ComponentKind::Float, {}, false});
  ps.field(0).at<double>(0)[0] = 1.0;
  ps.field(0).at<double>(1)[0] = 2.0;
  EngineOptions o;
  o.executor.kind = ExecutorKind::Jit;
  o.executor.threshold = 0;
  Engine engine(compiled, o);
  engine.bind_set(*compiled->find_extern("ps"), ps);
  // x'x is 5, 20, then 45: halved to [1.5, 3], 11.25, at k = 2.
  const std::string where = "halving.sim:" + std::to_string(line_of(kHalving, "error \"x")) + ":";
  for (int call = 0; call < 2; ++call) {
    std::string message;
    try {
      engine.call(*compiled->find_func("main"), {});
    } catch (const interp::RuntimeError& e) {
      message = e.render();
    }
    EXPECT_EQ(message.rfind(where, 0), 0u) << message;
    EXPECT_NE(message.find("runtime error: x'x = 11.25 after halving at k = 2"), std::string::npos)
        << message;
  }
  std::ostringstream os;
  engine.print_jit_stats(os);
  const std::string stats = os.str();
  const std::string note = "2 calls reached an error statement and ran again interpreted";
  EXPECT_NE(stats.find(note), std::string::npos) << stats;
  const size_t first = stats.find("reached an error statement");
  EXPECT_EQ(stats.find("reached an error statement", first + 1), std::string::npos) << stats;
  EXPECT_NE(loop_stats(stats, line_of(kHalving, "while k")).find(" compiled"), std::string::npos)
      << stats;
}

// Runs of system-level statements: a field read and a vector update; a CG function's set-up
// (with a product inside an expression), loop and residual compiled as one trace; a run with
// a field write and read, cut before a statement the JIT does not compile (a matrix made by
// the run); the interpreter's bits either way.
const std::string kRuns = R"(element Point
  b : float;
  d : float;
  c : float;
end
element Link
  k : float;
end
extern points : set{Point};
extern links : set{Link}(points, points);
)" + std::string(kChainMatrix) +
                          R"(
func cg(A : matrix[points,points](float), b : vector[points](float),
        x0 : vector[points](float)) -> (x : vector[points](float), iterations : int,
                                        residual : float)
  x = x0;
  var r = b - A * x;
  var p = r;
  var rr = r' * r;
  while (rr > 1e-20) and (iterations < 50)
    Ap = A * p;
    alpha = rr / (p' * Ap);
    x = x + alpha * p;
    r = r - alpha * Ap;
    rr_new = r' * r;
    p = r + (rr_new / rr) * p;
    rr = rr_new;
    iterations = iterations + 1;
  end
  residual = sqrt(rr / (b' * b));
end

export func solve() -> (x : vector[points](float), iterations : int, residual : float,
                        s : vector[points](float), w : vector[points](float))
  A = (map stiffness to links reduce +) + (map diagonal to points reduce +);
  b = points.b;
  x0 = 0.25 * b;
  x, iterations, residual = cg(A, b, x0);
  s = 2.0 * x + b;
  t = s - x;
  points.c = t;
  s = s + points.c;
  var u = s - b;
  w = u + u;
  B = 2.0 * A;
  w = w - u;
end
)";

struct RunsRun {
  std::vector<Value> results;
  std::vector<double> c;  // points.c
  std::string stats, dump;
};

// float32: the engine's float32 mode, with the points' fields stored as binary32.
RunsRun run_runs(ExecutorKind kind, bool check, bool float32 = false) {
  auto compiled = CompiledProgram::from_source("runs.sim", kRuns);
  EXPECT_TRUE(compiled->ok());
  runtime::Set points("points");
  runtime::Set links("links", {&points, &points});
  const int n = 40;
  points.add_many(n);
  for (const char* f : {"b", "d", "c"})
    points.add_field(f, runtime::FieldType{runtime::ComponentKind::Float, {}, float32});
  auto set = [&](int field, int i, double v) {
    if (float32)
      points.field(field).at<float>(i)[0] = static_cast<float>(v);
    else
      points.field(field).at<double>(i)[0] = v;
  };
  for (int i = 0; i < n; ++i) {
    set(0, i, std::sin(0.3 * i));
    set(1, i, 0.1 + 0.01 * i);
    if (i + 1 < n) links.add({i, i + 1});
  }
  links.add_field("k", runtime::FieldType{runtime::ComponentKind::Float, {}, false});
  for (int e = 0; e < links.size(); ++e) links.field(0).at<double>(e)[0] = 1.0 + 0.5 * std::cos(e);
  EngineOptions o;
  o.executor.kind = kind;
  o.float32 = float32;
  o.executor.threshold = 0;
  o.executor.check = check;
  std::ostringstream dump;
  o.dump = &dump;
  o.executor.dump_loop_ir = true;
  Engine engine(compiled, o);
  engine.bind_set(*compiled->find_extern("points"), points);
  engine.bind_set(*compiled->find_extern("links"), links);
  RunsRun run;
  for (int call = 0; call < 2; ++call) run.results = engine.call(*compiled->find_func("solve"), {});
  if (float32)
    run.c.assign(points.field(2).data<float>(), points.field(2).data<float>() + n);
  else
    run.c.assign(points.field(2).data<double>(), points.field(2).data<double>() + n);
  std::ostringstream os;
  engine.print_jit_stats(os);
  run.stats = os.str();
  run.dump = dump.str();
  return run;
}

// The stats line of the trace of the statements from the line holding `first` to the line
// holding `last`.
std::string run_stats(const std::string& stats, const std::string& text, const char* first,
                      const char* last) {
  const std::string site = "  statements (lines " + std::to_string(line_of(text, first)) + "-" +
                           std::to_string(line_of(text, last)) + ")";
  const size_t at = stats.find(site);
  return at == std::string::npos ? "" : stats.substr(at, stats.find('\n', at) - at);
}

void expect_same_runs(const RunsRun& in, const RunsRun& jit) {
  ASSERT_EQ(in.results.size(), 5u);
  ASSERT_EQ(jit.results.size(), 5u);
  expect_same(in.results[0], jit.results[0], "x");
  EXPECT_EQ(in.results[1].as_int(), jit.results[1].as_int());
  const double residual[2] = {in.results[2].as_float(), jit.results[2].as_float()};
  expect_same_bits(&residual[0], &residual[1], 1, "residual");
  expect_same(in.results[3], jit.results[3], "s");
  expect_same(in.results[4], jit.results[4], "w");
  expect_same_bits(in.c.data(), jit.c.data(), in.c.size(), "points.c");
}

TEST(Jit, ARunOfStatementsCompilesAsOneTraceWithItsLoop) {
  if (!api::jit_available()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  const RunsRun in = run_runs(ExecutorKind::Interpreter, false);
  const RunsRun jit = run_runs(ExecutorKind::Jit, false);
  expect_same_runs(in, jit);
  EXPECT_GT(in.results[1].as_int(), 5);  // CG took real iterations
  EXPECT_GT(in.results[2].as_float(), 0.0);
  // cg's six statements are one trace, called twice; its loop is not compiled on its own.
  const std::string cg = run_stats(jit.stats, kRuns, "x = x0", "residual = sqrt");
  EXPECT_NE(cg.find(" compiled"), std::string::npos) << jit.stats;
  EXPECT_NE(cg.find(" 2 "), std::string::npos) << cg;
  // Its loop-IR size, the last number before the status.
  std::istringstream fields(cg.substr(cg.find(')') + 1));
  double compile_ms = 0, run_ms = 0, cpu_ms = 0;
  long calls = 0, nodes = 0;
  fields >> compile_ms >> calls >> run_ms >> cpu_ms >> nodes;
  EXPECT_GT(nodes, 20) << cg;
  EXPECT_EQ(jit.stats.find("  while (line"), std::string::npos) << jit.stats;
  // The set-up's product (b - A * x) goes into a scratch vector; the residual's b'b is after.
  const size_t trace =
      jit.dump.find("system trace statements:" + std::to_string(line_of(kRuns, "x = x0")));
  ASSERT_NE(trace, std::string::npos) << jit.dump;
  const std::string ir = jit.dump.substr(trace);
  const size_t before = ir.find("  before"), loop = ir.find("  while "), after = ir.find("  after");
  ASSERT_TRUE(before < loop && loop < after) << ir;
  EXPECT_NE(ir.find("scratch"), std::string::npos) << ir;
  EXPECT_NE(ir.substr(before, loop - before).find(" = spmv("), std::string::npos) << ir;
  EXPECT_NE(ir.substr(after).find("pass over"), std::string::npos) << ir;
  // `b = points.b; x0 = 0.25 * b` compile; from `s = ...` the statements before `B = 2.0 * A`
  // (which makes a matrix) compile, the field write among them.
  EXPECT_NE(run_stats(jit.stats, kRuns, "b = points.b", "x0 = 0.25").find(" compiled"),
            std::string::npos)
      << jit.stats;
  EXPECT_NE(run_stats(jit.stats, kRuns, "s = 2.0", "w = u + u").find(" compiled"),
            std::string::npos)
      << jit.stats;
  EXPECT_NE(jit.dump.find("points.c f64 written"), std::string::npos) << jit.dump;
  for (double c : in.c) EXPECT_NE(c, 0.0);  // the field was written
}

// A system statement that is no part of a run (`w = w - u` after the matrix statement that
// ends the run before it) compiles alone; one that does not compile (`B = 2.0 * A` makes a
// matrix) is not listed: the interpreter runs it, as it runs most matrix statements.
TEST(Jit, ASystemStatementAloneCompilesAndOneThatCannotIsNotListed) {
  if (!api::jit_available()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  const RunsRun in = run_runs(ExecutorKind::Interpreter, false);
  for (bool check : {false, true}) {
    const RunsRun jit = run_runs(ExecutorKind::Jit, check);
    expect_same_runs(in, jit);
    const std::string site =
        "  statement (line " + std::to_string(line_of(kRuns, "w = w - u")) + ")";
    const size_t at = jit.stats.find(site);
    ASSERT_NE(at, std::string::npos) << jit.stats;
    const std::string line = jit.stats.substr(at, jit.stats.find('\n', at) - at);
    EXPECT_NE(line.find(" compiled"), std::string::npos) << line;
    EXPECT_NE(line.find(" 2 "), std::string::npos) << line;  // both calls
    EXPECT_EQ(
        jit.stats.find("  statement (line " + std::to_string(line_of(kRuns, "B = 2.0 * A")) + ")"),
        std::string::npos)
        << jit.stats;
  }
}

TEST(Jit, CheckModeComparesARunOfStatements) {
  if (!api::jit_available()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  const RunsRun in = run_runs(ExecutorKind::Interpreter, false);
  const RunsRun jit = run_runs(ExecutorKind::Jit, true);
  expect_same_runs(in, jit);
  const std::string cg = run_stats(jit.stats, kRuns, "x = x0", "residual = sqrt");
  EXPECT_NE(cg.find(" compiled"), std::string::npos) << jit.stats;
  EXPECT_EQ(jit.stats.find("  while (line"), std::string::npos) << jit.stats;
  EXPECT_NE(run_stats(jit.stats, kRuns, "s = 2.0", "w = u + u").find(" compiled"),
            std::string::npos)
      << jit.stats;
}

// Under float32 (every operator, call and literal rounded to binary32) with binary32 fields,
// the same runs compile: each product's and each operator's value rounded, the fields
// widened at each read and rounded at each write; the bits are the interpreter's, also
// under --check-jit, and differ from the binary64 run's.
TEST(Jit, RunsCompileInFloat32ModeWithBinary32Fields) {
  if (!api::jit_available()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  const RunsRun in = run_runs(ExecutorKind::Interpreter, false, true);
  for (bool check : {false, true}) {
    const RunsRun jit = run_runs(ExecutorKind::Jit, check, true);
    expect_same_runs(in, jit);
    EXPECT_NE(run_stats(jit.stats, kRuns, "x = x0", "residual = sqrt").find(" compiled"),
              std::string::npos)
        << jit.stats;
    EXPECT_NE(run_stats(jit.stats, kRuns, "s = 2.0", "w = u + u").find(" compiled"),
              std::string::npos)
        << jit.stats;
    if (!check) {
      EXPECT_NE(jit.dump.find("points.c f32 written"), std::string::npos) << jit.dump;
      EXPECT_NE(jit.dump.find("round32("), std::string::npos) << jit.dump;
    }
  }
  const RunsRun wide = run_runs(ExecutorKind::Interpreter, false, false);
  EXPECT_NE(wide.results[2].as_float(), in.results[2].as_float());  // the rounding is real
  for (double c : in.c) EXPECT_EQ(c, static_cast<double>(static_cast<float>(c)));
}

// A run whose loop reaches an error statement: the interpreter runs the statements again
// from the first and stops at the error; neither the rest of the run nor the loop alone is
// compiled for it.
const char* const kRunError = R"(element P
  b : float;
end
extern ps : set{P};

func grow(b : vector[ps](float)) -> x : vector[ps](float)
  x = 0.0 * b;
  var y = b + b;
  var n = b' * b;
  while n < 100.0
    x = x + y;
    n = x' * x;
    if n > 40.0
      error "x'x = ", n, " above 40";
    end
  end
end

export func main() -> x : vector[ps](float)
  x = grow(ps.b);
end
)";

TEST(Jit, ARunWhoseLoopReachesAnErrorStatementIsInterpretedOnce) {
  if (!api::jit_available()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  std::string message[2], stats;
  for (int k = 0; k < 2; ++k) {
    auto compiled = CompiledProgram::from_source("grow.sim", kRunError);
    ASSERT_TRUE(compiled->ok());
    runtime::Set ps("ps");
    ps.add_many(2);
    ps.add_field("b", runtime::FieldType{runtime::ComponentKind::Float, {}, false});
    ps.field(0).at<double>(0)[0] = 1.0;
    ps.field(0).at<double>(1)[0] = 2.0;
    EngineOptions o;
    o.executor.kind = k ? ExecutorKind::Jit : ExecutorKind::Interpreter;
    o.executor.threshold = 0;
    Engine engine(compiled, o);
    engine.bind_set(*compiled->find_extern("ps"), ps);
    try {
      engine.call(*compiled->find_func("main"), {});
    } catch (const interp::RuntimeError& e) {
      message[k] = e.render();
    }
    std::ostringstream os;
    engine.print_jit_stats(os);
    if (k) stats = os.str();
  }
  // y = [2, 4]: x'x is 20, then 80.
  EXPECT_NE(message[0].find("runtime error: x'x = 80"), std::string::npos) << message[0];
  EXPECT_NE(message[0].find(" above 40"), std::string::npos) << message[0];
  EXPECT_EQ(message[1], message[0]);
  EXPECT_NE(stats.find("1 call reached an error statement and ran again interpreted"),
            std::string::npos)
      << stats;
  EXPECT_EQ(stats.find("  while (line"), std::string::npos) << stats;
  EXPECT_EQ(stats.find("statements (lines " + std::to_string(line_of(kRunError, "var y"))),
            std::string::npos)
      << stats;
}

// Ctrl-C in a compiled loop that never ends (a solver that does not converge): the kernel
// reads the interrupt flag once per iteration and stops at an iteration boundary; the call
// ends with the interpreter's Interrupted error, the fields and the global scalar the loop
// writes hold the values of one whole number of iterations, and the engine runs the next call
// (the interrupt was taken).
const char* const kSpin = R"(element P
  b : float;
  c : float;
  d : float;
end
extern ps : set{P};
extern count : float;

export func spin(limit : float)
  var x = 0.0 * ps.b;
  var n = 0.0;
  while n < limit
    x = x + ps.b;
    ps.c = x;
    n = n + 1.0;
    ps.d = n * ps.b;
    count = count + 1.0;
  end
end
)";

// The calls of the trace that holds line `line` (a loop alone or a run; 0 when absent).
long trace_calls(const std::string& stats, int line) {
  const std::string l = loop_stats(stats, line);
  if (l.empty()) return 0;
  std::istringstream fields(l.substr(l.find(')') + 1));
  double compile_ms = 0;
  long calls = 0;
  fields >> compile_ms >> calls;
  return calls;
}

TEST(Jit, AnInterruptStopsACompiledLoopAtAnIterationBoundary) {
  if (!api::jit_available()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  auto compiled = CompiledProgram::from_source("spin.sim", kSpin);
  ASSERT_TRUE(compiled->ok());
  runtime::Set ps("ps");
  const int n = 1000;
  ps.add_many(n);
  for (const char* f : {"b", "c", "d"})
    ps.add_field(f, runtime::FieldType{runtime::ComponentKind::Float, {}, false});
  for (int i = 0; i < n; ++i) ps.field(0).at<double>(i)[0] = 1.0 + i % 7;  // small integers
  interp::Trap trap;  // what the REPL's SIGINT handler asks to interrupt
  EngineOptions o;
  o.executor.kind = ExecutorKind::Jit;
  o.executor.threshold = 0;
  o.trap = &trap;
  Engine engine(compiled, o);
  engine.bind_set(*compiled->find_extern("ps"), ps);
  const ast::Variable& count = *compiled->find_extern("count");
  engine.set_global(count, Value::of_float(0.0));
  const ast::FuncDecl& spin = *compiled->find_func("spin");
  const int loop_line = line_of(kSpin, "while n");
  auto stats = [&] {
    std::ostringstream os;
    engine.print_jit_stats(os);
    return os.str();
  };
  // c and d after `iterations` whole iterations, in exact (small integer) arithmetic.
  auto expect_boundary = [&](double iterations) {
    for (int i = 0; i < n; ++i) {
      const double b = ps.field(0).at<double>(i)[0];
      ASSERT_EQ(ps.field(1).at<double>(i)[0], iterations * b) << "c at element " << i;
      ASSERT_EQ(ps.field(2).at<double>(i)[0], iterations * b) << "d at element " << i;
    }
  };
  // The first call compiles the loop (a bounded one): 3 iterations.
  engine.call(spin, {Value::of_float(3.0)});
  expect_boundary(3.0);
  ASSERT_EQ(engine.global(count).as_float(), 3.0);
  ASSERT_EQ(trace_calls(stats(), loop_line), 1) << stats();
  // The second never ends: its kernel runs until the flag is set, as SIGINT sets it.
  auto run = std::async(std::launch::async, [&]() -> std::string {
    try {
      engine.call(spin, {Value::of_float(1e300)});
    } catch (const interp::Interrupted& e) {
      return "interrupted: " + e.render();
    } catch (const interp::RuntimeError& e) {
      return "error: " + e.render();
    }
    return "returned";
  });
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  trap.request_interrupt();
  if (run.wait_for(std::chrono::seconds(30)) != std::future_status::ready) {
    // The kernel never looked at the flag: end the test process rather than hang.
    std::fprintf(stderr, "FAIL: the compiled loop did not stop within 30 s of the interrupt\n");
    std::fflush(stderr);
    std::_Exit(1);
  }
  const std::string outcome = run.get();
  EXPECT_EQ(outcome.rfind("interrupted: ", 0), 0u) << outcome;
  EXPECT_NE(outcome.find("spin.sim:"), std::string::npos) << outcome;
  EXPECT_FALSE(trap.interrupt_pending());  // taken, as the interpreter takes it
  // The kernel ran and stopped itself (the interpreter did not catch the interrupt before
  // it), after a whole number of iterations (at least one: 300 ms).
  EXPECT_EQ(trace_calls(stats(), loop_line), 2) << stats();
  const double iterations = ps.field(1).at<double>(0)[0] / ps.field(0).at<double>(0)[0];
  EXPECT_GE(iterations, 1.0);
  EXPECT_EQ(iterations, std::floor(iterations));
  expect_boundary(iterations);
  EXPECT_EQ(engine.global(count).as_float(), 3.0 + iterations);  // a scalar handed back
  // The engine goes on: the next call runs compiled, to its end.
  engine.call(spin, {Value::of_float(5.0)});
  expect_boundary(5.0);
  EXPECT_EQ(engine.global(count).as_float(), 8.0 + iterations);
  EXPECT_EQ(trace_calls(stats(), loop_line), 3) << stats();
  EXPECT_NE(loop_stats(stats(), loop_line).find(" compiled"), std::string::npos) << stats();
}

}  // namespace
}  // namespace simit::jit
