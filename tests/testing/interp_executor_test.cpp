// `%!` tests run by the interpreter (TESTFORMAT.md §3.2): literal types with and without
// orientation, the comparison rules, run-time errors with their lines, and `simit run`.
#include "testing/interp_executor.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <fstream>
#include <sstream>

#include "commands/run_command.h"
#include "testing/test_runner.h"
#include "testing/value_match.h"

namespace simit::tools {
namespace {

SectionReport judge(const std::string& text) {
  InterpExecutor executor;
  auto reports = run_file("cases.sim", text, &executor);
  EXPECT_EQ(reports.size(), 1u);
  return reports.at(0);
}

TEST(InterpExecutor, PassingAndFailingTests) {
  const std::string f = "func f(x : int) -> r : int\n  r = 2 * x;\nend\n";
  EXPECT_EQ(judge("%! f(2) == 4;\n" + f).outcome, Outcome::Pass);
  SectionReport r = judge("%! f(2) == 4;\n%! f(3) == 7;\n" + f);
  EXPECT_EQ(r.outcome, Outcome::Fail);
  EXPECT_NE(r.reason.find("cases.sim:2:1: %! f: 6 != 7"), std::string::npos) << r.reason;
}

TEST(InterpExecutor, ArgumentOrientationMustMatchButExpectedOrientationNeedNot) {
  const std::string g = "func g(v : vector[2](float)) -> r : vector[2](float)\n  r = v;\nend\n";
  EXPECT_EQ(judge("%! g([1.0, 2.0]') == [1.0, 2.0]';\n" + g).outcome, Outcome::Pass);
  EXPECT_EQ(judge("%! g([1.0, 2.0]') == [1.0, 2.0];\n" + g).outcome, Outcome::Pass);
  SectionReport r = judge("%! g([1.0, 2.0]) == [1.0, 2.0]';\n" + g);
  EXPECT_EQ(r.outcome, Outcome::Fail);
  EXPECT_NE(r.reason.find("parameter 'v'"), std::string::npos) << r.reason;
  EXPECT_EQ(judge("%! g([1.0, 2.0]') == [1.0, 2.0, 3.0]';\n" + g).outcome, Outcome::Fail);
}

TEST(InterpExecutor, ArityAndResultCountAreChecked) {
  SectionReport r = judge("%! h(1) == 1;\nfunc h(a : int) -> (x : int, y : int)\n  x = a;\nend\n");
  EXPECT_EQ(r.outcome, Outcome::Fail);
  EXPECT_NE(r.reason.find("exactly one result"), std::string::npos) << r.reason;
}

TEST(InterpExecutor, GenericFunctionsBindFromTheLiterals) {
  const std::string s = "func s<0:N>(v : vector[N](int)) -> r : int\n  r = N;\nend\n";
  EXPECT_EQ(judge("%! s([1, 2, 3]') == 3;\n%! s([4]') == 1;\n" + s).outcome, Outcome::Pass);
}

TEST(InterpExecutor, RuntimeErrorsFailOrdinarySectionsAndPassExpectingOnes) {
  const std::string d = "func d(a : int) -> r : int\n  r = 1 / a;\nend\n";
  SectionReport r = judge("%! d(0) == 0;\n" + d);
  EXPECT_EQ(r.outcome, Outcome::Fail);
  EXPECT_NE(r.reason.find("cases.sim:3:7: runtime error: integer division by zero"),
            std::string::npos)
      << r.reason;
  EXPECT_EQ(
      judge("%%% x\n%@ error runtime\n%@ error-contains \"division by zero\"\n%! d(0) == 0;\n" + d)
          .outcome,
      Outcome::Pass);
  EXPECT_EQ(judge("%%% x\n%@ error runtime\n%! d(1) == 1;\n" + d).outcome, Outcome::Fail);
}

TEST(InterpExecutor, GraphSectionsRunAndCheckFields) {
  const std::string program =
      "element N\n  x : float;\nend\nextern nodes : set{N};\n"
      "func twice(inout n : N)\n  n.x = 2.0 * n.x;\nend\n"
      "export func main()\n  apply twice to nodes;\nend\n";
  EXPECT_EQ(judge("%@ set nodes = 2\n%@ field nodes.x = 1.0, 3.0\n%@ run main\n"
                  "%@ expect nodes.x = 2.0, 6.0\n" +
                  program)
                .outcome,
            Outcome::Pass);
  SectionReport r = judge(
      "%@ set nodes = 2\n%@ field nodes.x = 1.0, 3.0\n%@ run main\n"
      "%@ expect nodes.x = 2.0, 7.0\n" +
      program);
  EXPECT_EQ(r.outcome, Outcome::Fail);
  EXPECT_NE(r.reason.find("nodes.x[1]"), std::string::npos) << r.reason;
}

// A graph section whose map the JIT compiles at threshold 0.
const char* kMapSection =
    "element N\n  x : float;\n  y : float;\nend\nextern nodes : set{N};\n"
    "func twice(n : N) -> r : vector[nodes](float)\n  r(n) = 2.0 * n.x;\nend\n"
    "export func main()\n  nodes.y = map twice to nodes reduce +;\nend\n";

api::EngineOptions checked_jit(bool corrupt) {
  api::EngineOptions o;
  o.executor.kind = api::ExecutorKind::Jit;
  o.executor.threshold = 0;
  o.executor.check = true;
  o.corrupt_for_test = corrupt;  // flips the last bit of the compiled map's result
  return o;
}

// `simit test --check-jit`: a compiled map that differs from the interpreter fails its section
// with the check's message, also a section that expects a run-time error (the difference is
// the JIT's failure, never the program's error).
TEST(InterpExecutor, CheckJitDifferencesFailTheirSections) {
  if (!api::jit_available()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  const std::string graph = "%@ set nodes = 2\n%@ field nodes.x = 1.0, 3.0\n%@ run main\n";
  const std::string expect = "%@ expect nodes.y = 2.0, 6.0\n";
  for (bool corrupt : {false, true}) {
    InterpExecutor executor(checked_jit(corrupt));
    std::vector<SectionReport> r = run_file("cases.sim", graph + expect + kMapSection, &executor);
    ASSERT_EQ(r.size(), 1u);
    EXPECT_EQ(r[0].outcome, corrupt ? Outcome::Fail : Outcome::Pass) << r[0].reason;
    if (corrupt) {
      EXPECT_NE(r[0].reason.find("--check-jit: the compiled twice (line "), std::string::npos)
          << r[0].reason;
    }
    r = run_file("cases.sim", "%@ error runtime\n" + graph + kMapSection, &executor);
    ASSERT_EQ(r.size(), 1u);
    EXPECT_EQ(r[0].outcome, Outcome::Fail);
    const std::string want = corrupt ? "expected a run-time error, got: cases.sim:"
                                     : "expected a run-time error, but the runs succeeded";
    EXPECT_EQ(r[0].reason.rfind(want, 0), 0u) << r[0].reason;
    if (corrupt) {
      EXPECT_NE(r[0].reason.find("--check-jit: "), std::string::npos) << r[0].reason;
    }
  }
}

// `simit test --jit-stats`: the executor keeps each section's traces until asked, once.
TEST(InterpExecutor, RecordsWhatTheJitMadeWhenAsked) {
  if (!api::jit_available()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  const std::string section =
      "%@ set nodes = 2\n%@ field nodes.x = 1.0, 3.0\n%@ run main\n" + std::string(kMapSection);
  for (bool record : {false, true}) {
    InterpExecutor executor(checked_jit(false), record);
    std::vector<SectionReport> r = run_file("cases.sim", section, &executor);
    ASSERT_EQ(r.size(), 1u);
    EXPECT_EQ(r[0].jit.statuses.empty(), !record);
    EXPECT_EQ(r[0].jit.tables.find("jit traces:") != std::string::npos, record) << r[0].jit.tables;
    EXPECT_TRUE(executor.take_jit_record().statuses.empty());  // the section took them
  }
}

interp::Value value(const std::string& text) {
  LiteralResult r = parse_literal(text);
  EXPECT_TRUE(r.literal) << r.error;
  return literal_value(*r.literal);
}

TEST(ValuesMatch, FloatRelativeToleranceAndExactZero) {
  EXPECT_TRUE(values_match(value("1.0005"), value("1.0")));
  EXPECT_FALSE(values_match(value("1.002"), value("1.0")));
  EXPECT_TRUE(values_match(value("-0.0"), value("0.0")));
  EXPECT_FALSE(values_match(value("1e-300"), value("0.0")));
  EXPECT_TRUE(values_match(value("[1.0, 2000.0]"), value("[1.0, 2001.0]")));
  EXPECT_FALSE(values_match(value("[1.0, 2.0]"), value("[1.0, 2.0, 3.0]")));
  EXPECT_TRUE(values_match(value("1.0"), value("1.5"), 0.5));
  EXPECT_FALSE(values_match(value("1.0"), value("1.6"), 0.5));
}

TEST(ValuesMatch, ExactKindsAndComplexParts) {
  EXPECT_TRUE(values_match(value("3"), value("3")));
  EXPECT_FALSE(values_match(value("3"), value("4")));
  EXPECT_FALSE(values_match(value("3"), value("3.0")));
  EXPECT_TRUE(values_match(value("true"), value("true")));
  EXPECT_FALSE(values_match(value("\"a\""), value("\"b\"")));
  EXPECT_TRUE(values_match(value("<1.0, 1000.0>"), value("<1.0, 1000.5>")));
  EXPECT_FALSE(values_match(value("<1.0, 0.0>"), value("<1.0, 1e-9>")));
}

std::string write_program(const std::string& text) {
  // One file per test and process: ctest runs the tests of this binary in parallel.
  std::string path = ::testing::TempDir() + "run_command_" +
                     ::testing::UnitTest::GetInstance()->current_test_info()->name() + "_" +
                     std::to_string(::getpid()) + ".sim";
  std::ofstream(path) << text;
  return path;
}

TEST(RunCommand, PrintsOutputAndResults) {
  RunOptions o;
  o.file = write_program(
      "export func f(a : float, v : vector[2](float)) -> (s : float, w : vector[2](float))\n"
      "  println \"hello \", a;\n  s = 2.0 * a;\n  w = a * v;\nend\n");
  o.func = "f";
  o.args = {"-1.5", "[1.0, 2.0]'"};
  std::ostringstream out, err;
  EXPECT_EQ(run_function(o, out, err), 0) << err.str();
  EXPECT_EQ(out.str(), "hello -1.5\ns = -3.0\nw = [-1.5, -3.0]'\n");
}

TEST(RunCommand, RejectsBadArgumentsAndReportsRuntimeErrors) {
  RunOptions o;
  o.file = write_program(
      "export func f(v : vector[2](float), i : int) -> r : float\n  r = v(i);\nend\n"
      "func hidden() -> r : int\n  r = 1;\nend\n");
  o.func = "f";
  std::ostringstream out, err;
  o.args = {"[1.0, 2.0]", "0"};  // a row vector for a column parameter
  EXPECT_EQ(run_function(o, out, err), 1);
  EXPECT_NE(err.str().find("parameter 'v'"), std::string::npos) << err.str();
  o.args = {"[1.0, 2.0]'"};
  EXPECT_EQ(run_function(o, out, err), 1);
  o.args = {"[1.0, 2.0]'", "2"};
  err.str("");
  EXPECT_EQ(run_function(o, out, err), 1);
  EXPECT_NE(err.str().find(":2:9: runtime error: index 2 is out of range"), std::string::npos)
      << err.str();
  EXPECT_NE(err.str().find("  in f ("), std::string::npos) << err.str();
  o.func = "hidden";
  o.args = {};
  err.str("");
  EXPECT_EQ(run_function(o, out, err), 1);
  EXPECT_NE(err.str().find("not an exported function"), std::string::npos);
}

}  // namespace
}  // namespace simit::tools
