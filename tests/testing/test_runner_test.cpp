// The `simit test` runner: judging sections, locating failures, and the executor seam.
#include "testing/test_runner.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include <unistd.h>

namespace simit::tools {
namespace {

constexpr const char* kGood = "func f(a : int) -> b : int\n  b = a;\nend\n";
constexpr const char* kUndeclared = "func f() -> b : int\n  b = zz;\nend\n";

// Records what it was asked to run and answers with a fixed result.
class FakeExecutor : public Executor {
 public:
  explicit FakeExecutor(RunResult result) : result_(std::move(result)) {}
  std::string name() const override { return "fake"; }
  RunResult run_test(const frontend::ast::Program&, const frontend::ast::TestDecl& t) override {
    tested.push_back(t.func);
    return result_;
  }
  RunResult run_graph(const frontend::ast::Program&, const std::vector<GraphStep>& s) override {
    graph_steps += s.size();
    return result_;
  }
  std::vector<std::string> tested;
  size_t graph_steps = 0;

 private:
  RunResult result_;
};

std::vector<SectionReport> run(const std::string& text, const std::string& file = "dir/t.sim",
                               Executor* executor = nullptr) {
  return run_file(file, text, executor);
}

SectionReport run_one(const std::string& text, const std::string& file = "dir/t.sim",
                      Executor* executor = nullptr) {
  auto reports = run(text, file, executor);
  EXPECT_EQ(reports.size(), 1u);
  return reports.empty() ? SectionReport{} : reports[0];
}

TEST(TestRunner, CompilingSectionPasses) {
  SectionReport r = run_one(std::string("%%% good one\n") + kGood);
  EXPECT_EQ(r.outcome, Outcome::Pass) << r.reason;
  EXPECT_EQ(r.label, "t::good one");
  EXPECT_EQ(r.file, "dir/t.sim");
  EXPECT_EQ(r.line, 1);
}

TEST(TestRunner, UnsectionedFileIsLabelledByStem) {
  SectionReport r = run_one(kGood);
  EXPECT_EQ(r.outcome, Outcome::Pass) << r.reason;
  EXPECT_EQ(r.label, "t");
}

TEST(TestRunner, CommentOnlyAndEmptySectionsPass) {
  auto reports = run("%%% a\n%%% %! f(1) == 1;\n%%%\n");
  ASSERT_EQ(reports.size(), 3u);
  for (const auto& r : reports) EXPECT_EQ(r.outcome, Outcome::Pass) << r.label << r.reason;
}

TEST(TestRunner, CompileErrorFailsWithFileRelativeLocation) {
  auto reports = run(std::string("%%% a\n") + kGood + "%%% b\n" + kUndeclared);
  ASSERT_EQ(reports.size(), 2u);
  EXPECT_EQ(reports[0].outcome, Outcome::Pass);
  const SectionReport& r = reports[1];
  EXPECT_EQ(r.outcome, Outcome::Fail);
  EXPECT_EQ(r.line, 5);
  // `zz` is on line 3 of section b, which starts at line 5 of the file.
  EXPECT_NE(r.reason.find("dir/t.sim:7:"), std::string::npos) << r.reason;
  EXPECT_NE(r.detail.find("zz"), std::string::npos) << r.detail;
}

TEST(TestRunner, DisabledSectionIsSkipped) {
  SectionReport r = run_one("%%%- later\nfunc broken(\n");
  EXPECT_EQ(r.outcome, Outcome::Skip);
  EXPECT_NE(r.reason.find("disabled"), std::string::npos);
}

TEST(TestRunner, IllegalFolderSectionsMustBeRejected) {
  auto reports = run(std::string("%%% rejected\n") + kUndeclared + "%%% accepted\n" + kGood,
                     "tests/illegal/bad.sim");
  ASSERT_EQ(reports.size(), 2u);
  EXPECT_EQ(reports[0].outcome, Outcome::Pass) << reports[0].reason;
  EXPECT_EQ(reports[1].outcome, Outcome::Fail);
  EXPECT_NE(reports[1].reason.find("but the section compiled"), std::string::npos);
}

TEST(TestRunner, ErrorCategoryMustMatchFirstDiagnostic) {
  EXPECT_EQ(run_one(std::string("%%% s\n%@ error undeclared\n") + kUndeclared).outcome,
            Outcome::Pass);
  EXPECT_EQ(run_one(std::string("%%% s\n%@ error semantic\n") + kUndeclared).outcome,
            Outcome::Pass);
  SectionReport r = run_one(std::string("%%% s\n%@ error syntax\n") + kUndeclared);
  EXPECT_EQ(r.outcome, Outcome::Fail);
  EXPECT_NE(r.reason.find("expected a syntax error first, got undeclared"), std::string::npos)
      << r.reason;
  EXPECT_EQ(run_one("%%% s\n%@ error syntax\nfunc f(\n").outcome, Outcome::Pass);
}

TEST(TestRunner, ErrorLineIsRelativeToTheSectionHeader) {
  std::string second = std::string("%%% b\n%@ error undeclared\n%@ error-line 5\n") + kUndeclared;
  auto reports = run(std::string("%%% a\n") + kGood + second);
  ASSERT_EQ(reports.size(), 2u);
  EXPECT_EQ(reports[1].outcome, Outcome::Pass) << reports[1].reason;

  std::string wrong = std::string("%%% b\n%@ error-line 2\n") + kUndeclared;
  reports = run(std::string("%%% a\n") + kGood + wrong);
  EXPECT_EQ(reports[1].outcome, Outcome::Fail);
  EXPECT_NE(reports[1].reason.find("section line 2 (file line 6)"), std::string::npos)
      << reports[1].reason;
}

TEST(TestRunner, ErrorContains) {
  EXPECT_EQ(run_one(std::string("%@ error-contains \"zz\"\n") + kUndeclared).outcome,
            Outcome::Pass);
  SectionReport r = run_one(std::string("%@ error-contains \"no such text\"\n") + kUndeclared);
  EXPECT_EQ(r.outcome, Outcome::Fail);
  EXPECT_NE(r.reason.find("no such text"), std::string::npos);
}

TEST(TestRunner, MustFailSectionThatCompilesFails) {
  SectionReport r = run_one(std::string("%@ error type\n") + kGood);
  EXPECT_EQ(r.outcome, Outcome::Fail);
  EXPECT_NE(r.reason.find("expected a type error, but the section compiled"), std::string::npos);
}

TEST(TestRunner, BadDirectiveFailsNamingFileAndLine) {
  auto reports = run(std::string("%%% a\n") + kGood + "%%% b\n%@ expext x = 1\n" + kGood);
  ASSERT_EQ(reports.size(), 2u);
  EXPECT_EQ(reports[1].outcome, Outcome::Fail);
  EXPECT_NE(reports[1].reason.find("dir/t.sim:6: unknown directive '%@ expext'"), std::string::npos)
      << reports[1].reason;
}

TEST(TestRunner, InlineTestsNeedAnExecutor) {
  std::string text = std::string("%%% t\n%! f(2) == 2;\n") + kGood;
  SectionReport r = run_one(text);
  EXPECT_EQ(r.outcome, Outcome::Skip);
  EXPECT_NE(r.reason.find("executor"), std::string::npos);

  FakeExecutor pass({});
  EXPECT_EQ(run_one(text, "t.sim", &pass).outcome, Outcome::Pass);
  EXPECT_EQ(pass.tested, std::vector<std::string>{"f"});

  FakeExecutor mismatch({RunResult::Status::Failed, "3 != 2"});
  r = run_one(text, "t.sim", &mismatch);
  EXPECT_EQ(r.outcome, Outcome::Fail);
  EXPECT_NE(r.reason.find("t.sim:2:"), std::string::npos) << r.reason;
  EXPECT_NE(r.reason.find("3 != 2"), std::string::npos) << r.reason;
}

TEST(TestRunner, GraphDirectivesGoToTheExecutor) {
  std::string text = std::string("%%% g\n%@ run f\n%@ expect r = 1\n") + kGood;
  EXPECT_EQ(run_one(text).outcome, Outcome::Skip);
  FakeExecutor pass({});
  EXPECT_EQ(run_one(text, "t.sim", &pass).outcome, Outcome::Pass);
  EXPECT_EQ(pass.graph_steps, 2u);
}

TEST(TestRunner, RuntimeErrorExpectation) {
  std::string text = std::string("%%% g\n%@ error runtime\n%@ run f\n") + kGood;
  EXPECT_EQ(run_one(text).outcome, Outcome::Skip);
  FakeExecutor fails({RunResult::Status::RuntimeError, "index out of range"});
  EXPECT_EQ(run_one(text, "t.sim", &fails).outcome, Outcome::Pass);
  FakeExecutor succeeds({});
  EXPECT_EQ(run_one(text, "t.sim", &succeeds).outcome, Outcome::Fail);
  EXPECT_EQ(run_one(std::string("%@ error runtime\n") + kGood).outcome, Outcome::Fail);
  EXPECT_EQ(run_one(std::string("%@ error runtime\n%@ run f\n") + kUndeclared).outcome,
            Outcome::Fail);
}

class TestRunnerFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    // The process id keeps parallel runs of the suite (several build trees) apart.
    root_ = std::filesystem::temp_directory_path() /
            ("simit_runner_test_" + std::to_string(::getpid()) + "_" +
             ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::remove_all(root_);
    std::filesystem::create_directories(root_ / "illegal");
  }
  void TearDown() override { std::filesystem::remove_all(root_); }
  void write(const std::string& name, const std::string& text) {
    std::ofstream(root_ / name) << text;
  }
  int run_paths(std::vector<std::string> paths, bool verbose = false) {
    out_.str("");
    err_.str("");
    return run_tests(paths, {verbose, nullptr}, out_, err_);
  }
  std::filesystem::path root_;
  std::ostringstream out_, err_;
};

TEST_F(TestRunnerFiles, SummaryAndExitStatus) {
  write("a.sim", std::string("%%% one\n") + kGood + "%%% two\n%! f(1) == 1;\n" + kGood);
  write("illegal/b.sim", std::string("%%% bad\n") + kUndeclared);
  write("notes.txt", "not a test");
  EXPECT_EQ(run_paths({root_.string()}), 0) << out_.str() << err_.str();
  EXPECT_NE(out_.str().find("2 passed, 0 failed, 1 skipped\n"), std::string::npos) << out_.str();

  write("c.sim", std::string("%%% broken\n") + kUndeclared);
  EXPECT_EQ(run_paths({root_.string()}, true), 1);
  std::string out = out_.str();
  EXPECT_NE(out.find("PASS a::one ("), std::string::npos) << out;
  EXPECT_NE(out.find("SKIP a::two ("), std::string::npos) << out;
  EXPECT_NE(out.find("FAIL c::broken (" + (root_ / "c.sim").string() + ":1): does not compile"),
            std::string::npos)
      << out;
  EXPECT_NE(out.find("2 passed, 1 failed, 1 skipped\n"), std::string::npos) << out;
  // Files are visited in the order of their sorted paths: a.sim, c.sim, illegal/b.sim.
  EXPECT_LT(out.find("a::one"), out.find("c::broken"));
  EXPECT_LT(out.find("c::broken"), out.find("b::bad"));
}

TEST_F(TestRunnerFiles, MissingPathFails) {
  write("a.sim", kGood);
  EXPECT_EQ(run_paths({(root_ / "a.sim").string(), (root_ / "nope").string()}), 1);
  EXPECT_NE(err_.str().find("cannot read"), std::string::npos);
  EXPECT_NE(out_.str().find("1 passed, 1 failed\n"), std::string::npos) << out_.str();
}

TEST_F(TestRunnerFiles, EmptyFolderIsAnError) {
  EXPECT_EQ(run_paths({(root_ / "illegal").string()}), 1);
  EXPECT_NE(err_.str().find("no .sim files"), std::string::npos);
}

}  // namespace
}  // namespace simit::tools
