// The `simit` command line: help, version, usage errors and `simit check`.
#include "cli.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <vector>

#include <unistd.h>

#include "api/engine.h"

namespace simit::tools {
namespace {

struct Result {
  int status;
  std::string out, err;
};

Result cli(std::vector<std::string> args) {
  args.insert(args.begin(), "simit");
  std::vector<const char*> argv;
  for (const auto& a : args) argv.push_back(a.c_str());
  std::ostringstream out, err;
  int status = run_cli(static_cast<int>(argv.size()), argv.data(), out, err);
  return {status, out.str(), err.str()};
}

// A file in the temporary folder, removed at the end of the test.
struct TempFile {
  TempFile(const std::string& name, const std::string& text)
      : path((std::filesystem::temp_directory_path() /
              ("simit_cli_test_" + std::to_string(::getpid()) + "_" + name))
                 .string()) {
    std::ofstream(path) << text;
  }
  ~TempFile() { std::filesystem::remove(path); }
  std::string path;
};

TEST(Cli, HelpListsTheCommands) {
  Result r = cli({"--help"});
  EXPECT_EQ(r.status, 0);
  EXPECT_NE(r.out.find("check"), std::string::npos);
  EXPECT_NE(r.out.find("test"), std::string::npos);
}

TEST(Cli, Version) {
  Result r = cli({"--version"});
  EXPECT_EQ(r.status, 0);
  EXPECT_EQ(r.out.rfind("simit ", 0), 0u) << r.out;
}

TEST(Cli, UsageErrorsExitTwo) {
  Result unknown = cli({"frobnicate"});
  EXPECT_EQ(unknown.status, 2);
  EXPECT_NE(unknown.err.find("unknown command 'frobnicate'"), std::string::npos) << unknown.err;
  EXPECT_NE(unknown.err.find("check"), std::string::npos) << "usage should follow";
  // No command at all starts the REPL (tests/repl), not a usage error.
  EXPECT_EQ(cli({"check"}).status, 2);
  EXPECT_EQ(cli({"check", "--dump=llvm", "x.sim"}).status, 2);
  EXPECT_EQ(cli({"test"}).status, 2);
}

// A bad frame count names a sane bound (CLI11's own check printed the largest double).
TEST(Cli, BadFrameCountsNameTheirBound) {
  for (const char* bad : {"-1", "abc", "1e5", "99999999999999999999", "2.5"}) {
    Result r = cli({"run", "scene.toml", "--frames", bad});
    EXPECT_EQ(r.status, 2) << bad;
    EXPECT_EQ(r.err.substr(0, r.err.find('\n')),
              std::string("simit: error: --frames: expected a whole number of frames from 0 to "
                          "2147483647, got '") +
                  bad + "'");
  }
}

TEST(Cli, CheckHelpDescribesDumpAndExitStatus) {
  Result r = cli({"check", "--help"});
  EXPECT_EQ(r.status, 0);
  EXPECT_NE(r.out.find("--dump"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("Exit status"), std::string::npos) << r.out;
}

TEST(Cli, CheckCleanAndBrokenFiles) {
  TempFile good_file("good.sim", "func f(a : int) -> b : int\n  b = a;\nend\n");
  TempFile bad_file("bad.sim", "func f() -> b : int\n  b = zz;\nend\n");
  const std::string& good = good_file.path;
  const std::string& bad = bad_file.path;
  Result clean = cli({"check", good});
  EXPECT_EQ(clean.status, 0) << clean.err;
  EXPECT_EQ(clean.err, "");
  Result broken = cli({"check", good, bad});
  EXPECT_EQ(broken.status, 1);
  EXPECT_NE(broken.err.find(bad + ":2:"), std::string::npos) << broken.err;
  EXPECT_NE(broken.err.find("error:"), std::string::npos) << broken.err;
}

TEST(Cli, CheckUnreadableFile) {
  Result r = cli({"check", "/nonexistent/dir/x.sim"});
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("cannot read '/nonexistent/dir/x.sim'"), std::string::npos) << r.err;
}

TEST(Cli, CheckDumps) {
  TempFile file("dump.sim", "func f(a : int) -> b : int\n  b = a;\nend\n");
  const std::string& good = file.path;
  Result ast = cli({"check", "--dump=ast", good});
  EXPECT_EQ(ast.status, 0);
  EXPECT_FALSE(ast.out.empty());
  Result both = cli({"check", "--dump=ast,typed", good});
  EXPECT_EQ(both.status, 0);
  EXPECT_NE(both.out.find("# ast of"), std::string::npos);
  EXPECT_NE(both.out.find("# typed of"), std::string::npos);
}

// A graph section whose map the JIT compiles at threshold 0.
const char* kMapTest =
    "%@ set nodes = 2\n%@ field nodes.x = 1.0, 3.0\n%@ run main\n%@ expect nodes.y = 2.0, 6.0\n"
    "element N\n  x : float;\n  y : float;\nend\nextern nodes : set{N};\n"
    "func twice(n : N) -> r : vector[nodes](float)\n  r(n) = 2.0 * n.x;\nend\n"
    "export func main()\n  nodes.y = map twice to nodes reduce +;\nend\n";

// `simit test` takes the JIT options of `simit run`, under the same names and words.
TEST(Cli, TestAndRunShareTheJitOptions) {
  for (const char* command : {"test", "run"}) {
    Result r = cli({command, "--help"});
    EXPECT_EQ(r.status, 0);
    for (const char* option : {"--executor", "--backend", "--jit-threshold", "--jit-stats",
                               "--check-jit", "--jit-cache"})
      EXPECT_NE(r.out.find(option), std::string::npos) << command << " " << option;
    EXPECT_NE(r.out.find("--backend is another name of this option"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("that differs (bit for bit), naming it; needs --executor jit"),
              std::string::npos)
        << r.out;
  }
}

// Without the JIT they would do nothing, silently: a usage error in both commands.
TEST(Cli, JitOptionsNeedTheJitBackend) {
  TempFile file("needs_jit.sim", kMapTest);
  for (const char* command : {"test", "run"})
    for (const char* option : {"--check-jit", "--jit-stats"}) {
      std::vector<std::string> args = {command, file.path, option};
      if (std::string(command) == "run") args.insert(args.end(), {"--call", "main"});
      Result r = cli(args);
      EXPECT_EQ(r.status, 2) << command << " " << option;
      EXPECT_EQ(r.err.substr(0, r.err.find('\n')),
                std::string("simit: error: ") + command + ": " + option + " needs --executor jit");
      for (const char* spelling : {"--executor", "--backend"}) {
        r = cli({command, file.path, option, spelling, "interpreter"});
        EXPECT_EQ(r.status, 2) << command << " " << option << " " << spelling;
      }
    }
}

// `simit test --backend jit --check-jit` runs each section checked against the interpreter.
TEST(Cli, TestRunsSectionsUnderCheckJit) {
  if (!api::jit_available()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  TempFile file("check_jit.sim", kMapTest);
  Result r = cli({"test", "--backend", "jit", "--jit-threshold", "0", "--check-jit", file.path});
  EXPECT_EQ(r.status, 0) << r.out << r.err;
  EXPECT_EQ(r.out, "1 passed, 0 failed\n");
}

// `simit test --jit-stats`: the traces under each section listed, and a summary of them all
// before the last line.
TEST(Cli, TestPrintsJitStats) {
  if (!api::jit_available()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  TempFile file("jit_stats.sim", kMapTest);
  Result r =
      cli({"test", "-v", "--backend", "jit", "--jit-threshold", "0", "--jit-stats", file.path});
  EXPECT_EQ(r.status, 0) << r.out << r.err;
  const std::string pass = "PASS " + std::filesystem::path(file.path).stem().string() + " (" +
                           file.path + ":1)\n    jit traces:\n";
  EXPECT_EQ(r.out.rfind(pass, 0), 0u) << r.out;
  EXPECT_NE(r.out.find("\n      twice (line "), std::string::npos) << r.out;
  const size_t summary = r.out.find("\njit: ");
  ASSERT_NE(summary, std::string::npos) << r.out;
  EXPECT_NE(r.out.find(" in 1 section, ", summary), std::string::npos) << r.out;
  EXPECT_TRUE(r.out.ends_with(" interpreted\n1 passed, 0 failed\n")) << r.out;
  // Without -v a passing section is not listed: the summary alone.
  r = cli({"test", "--backend", "jit", "--jit-threshold", "0", "--jit-stats", file.path});
  EXPECT_EQ(r.out.rfind("jit: ", 0), 0u) << r.out;
  EXPECT_EQ(r.out.find("jit traces:"), std::string::npos) << r.out;
}

// `simit partition`: a line per part count; a mesh that does not read and more parts than
// vertices are errors (exit 1) naming the file; a part count below 1 is a usage error.
TEST(Cli, PartitionPrintsALinePerPartCount) {
  const std::string bunny = SIMIT_SOURCE_DIR "/examples/data/bunny.1.ele";
  Result r = cli({"partition", bunny, "--parts", "2,3"});
  if (r.status == 1 && r.err.find("this build has no partitioner") != std::string::npos)
    GTEST_SKIP() << r.err;
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("bunny.1.ele: "), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("\n    2  "), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("\n    3  "), std::string::npos) << r.out;
  Result csv = cli({"partition", bunny, "--parts", "4", "--csv"});
  ASSERT_EQ(csv.status, 0);
  EXPECT_NE(csv.out.find("\nparts,cut_edges,"), std::string::npos) << csv.out;
  EXPECT_NE(csv.out.find("\n4,"), std::string::npos) << csv.out;
  Result missing = cli({"partition", "no_such_mesh.ele"});
  EXPECT_EQ(missing.status, 1);
  EXPECT_NE(missing.err.find("no_such_mesh"), std::string::npos) << missing.err;
  Result too_many = cli({"partition", bunny, "--parts", "100000"});
  EXPECT_EQ(too_many.status, 1);
  EXPECT_NE(too_many.err.find("each part needs a vertex"), std::string::npos) << too_many.err;
  EXPECT_EQ(cli({"partition", bunny, "--parts", "0"}).status, 2);
}

}  // namespace
}  // namespace simit::tools
