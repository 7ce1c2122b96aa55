// `simit run --jit-stats` when the run stops early: after a run-time error (a .sim run with
// --call), a NaN stop (a scene) or Ctrl-C (a scene, in a child process), the JIT's table still
// prints, after the error message, to the stream it prints to after a run that ends well.
#include "cli.h"

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <cstdio>

#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>

#include "api/engine.h"

namespace simit::tools {
namespace {

namespace fs = std::filesystem;

struct Result {
  int status;
  std::string out, err;
  std::string both;  // out and err as a terminal interleaves them
};

// Runs the command line twice: with out and err apart, and into one stream for their order.
Result cli(std::vector<std::string> args) {
  args.insert(args.begin(), "simit");
  std::vector<const char*> argv;
  for (const auto& a : args) argv.push_back(a.c_str());
  const int argc = static_cast<int>(argv.size());
  std::ostringstream out, err, both;
  const int status = run_cli(argc, argv.data(), out, err);
  run_cli(argc, argv.data(), both, both);
  return {status, out.str(), err.str(), both.str()};
}

class JitStats : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!api::jit_available()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
    std::string pattern = (fs::temp_directory_path() / "simit-jit-stats-XXXXXX").string();
    ASSERT_NE(mkdtemp(pattern.data()), nullptr);
    dir_ = pattern;
  }
  void TearDown() override {
    std::error_code ec;
    if (!dir_.empty()) fs::remove_all(dir_, ec);
  }

  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  void write(const std::string& name, const std::string& text) const {
    std::ofstream(dir_ / name) << text;
  }
  // A scene over an n x n generated cloth's points, with no output files.
  std::string scene(const std::string& program, long frames, int n) const {
    return "program = \"" + program + "\"\nstep = \"step\"\nframes = " + std::to_string(frames) +
           "\n[sets.points]\ngenerate = \"square_cloth\"\nn = " + std::to_string(n) +
           "\nelements = \"vertices\"\n[sets.points.fields]\nx = \"position\"\nw = 1.0\n";
  }

  fs::path dir_;
};

// What must follow the error message: the table (with a compiled trace when `compiled`).
void expect_stats_after(const Result& r, const std::string& error, bool compiled = true) {
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find(error), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("jit traces:"), std::string::npos) << "the table goes to out";
  const size_t at = r.both.find(error);
  ASSERT_NE(at, std::string::npos) << r.both;
  const size_t table = r.both.find("jit traces:\n", at);
  ASSERT_NE(table, std::string::npos) << "no table after the error:\n" << r.both;
  if (compiled) {
    EXPECT_NE(r.both.find(" compiled\n", table), std::string::npos) << r.both;
  }
}

// tests/tools/jit_stats_error.toml: a compiled apply divides by zero in frame 3.
TEST_F(JitStats, ScenePrintsThemAfterARuntimeError) {
  const std::string scene = std::string(SIMIT_SOURCE_DIR) + "/tests/tools/jit_stats_error.toml";
  Result r = cli({"run", "--backend", "jit", "--jit-threshold", "0", "--jit-stats", scene});
  expect_stats_after(r, "jit_stats_error.sim:12:9: runtime error: integer division by zero");
  EXPECT_NE(r.out.find("\n  countdown (line 16) "), std::string::npos) << r.out;
  // Two frames ran compiled before the third stopped.
  EXPECT_NE(r.out.find("frame 2/5"), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("frame 3/5"), std::string::npos) << r.out;
}

// A function run with --call: the table follows the run-time error too. (The JIT compiles
// map and apply sites and system statements, which need sets: this table lists no trace.)
TEST_F(JitStats, CallPrintsThemAfterARuntimeError) {
  write("divide.sim", "export func main(n : int) -> r : int\n  r = 12 / n;\nend\n");
  const std::vector<std::string> args = {
      "run", "--backend", "jit", "--jit-stats", path("divide.sim"), "--call", "main"};
  std::vector<std::string> ok = args, bad = args;
  ok.push_back("3");
  bad.push_back("0");
  Result r = cli(ok);
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(r.out.rfind("r = 4\njit traces:\n", 0), 0u) << r.out;
  expect_stats_after(cli(bad), "divide.sim:2:7: runtime error: integer division by zero", false);
}

// A scene whose compiled apply makes an infinity in frame 1: the frame-boundary check stops
// the run, and the table follows its message.
TEST_F(JitStats, ScenePrintsThemAfterANonFiniteStop) {
  write("inverse.sim",
        "element Point\n  x : vector[3](float);\n  w : float;\nend\n"
        "extern points : set{Point};\n"
        "func invert(inout p : Point)\n  p.w = 1.0 / (p.w - 1.0);\nend\n"
        "export func step()\n  apply invert to points;\nend\n");
  write("scene.toml", scene("inverse.sim", 3, 4));
  Result r =
      cli({"run", "--backend", "jit", "--jit-threshold", "0", "--jit-stats", path("scene.toml")});
  expect_stats_after(r, "error: after frame 1: field 'w' of element 0 of set 'points' is inf");
}

// Ctrl-C under --jit-stats stops the run at its next statement with an error, and the table
// follows, where without the option the process dies of the signal. On threads, every
// thread stops at its next chunk and the run reports the same.
void ctrl_c_stops(const std::function<void(const std::string&, const std::string&)>& write,
                  const std::function<std::string(const std::string&)>& path,
                  const std::string& toml, const char* threads) {
  write("nudge.sim",
        "element Point\n  x : vector[3](float);\n  w : float;\nend\n"
        "extern points : set{Point};\n"
        "func nudge(inout p : Point)\n  p.w = p.w + 0.001;\nend\n"
        "export func step()\n  apply nudge to points;\nend\n");
  write("scene.toml", toml);
  const std::string scene_path = path("scene.toml"), out_path = path("out.txt"),
                    err_path = path("err.txt");
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    if (!freopen(out_path.c_str(), "w", stdout) || !freopen(err_path.c_str(), "w", stderr))
      _exit(126);
    execl(SIMIT_EXE, SIMIT_EXE, "run", "--backend", "jit", "--jit-threshold", "0", "--jit-stats",
          "--threads", threads, scene_path.c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  // Frames are running once their progress lines reach the file (stdout is a file: buffered).
  auto running = [&] {
    std::error_code ec;  // file_size is -1 before the child creates the file
    const auto size = fs::file_size(out_path, ec);
    return !ec && size > 0;
  };
  for (int waited = 0; waited < 600000 && !running(); ++waited) usleep(100);
  ASSERT_TRUE(running());
  kill(child, SIGINT);
  int status = 0;
  ASSERT_EQ(waitpid(child, &status, 0), child);
  std::ifstream out_file(out_path), err_file(err_path);
  const std::string out((std::istreambuf_iterator<char>(out_file)), {});
  const std::string err((std::istreambuf_iterator<char>(err_file)), {});
  ASSERT_TRUE(WIFEXITED(status)) << "died of signal " << WTERMSIG(status);
  EXPECT_EQ(WEXITSTATUS(status), 1);
  EXPECT_NE(err.find("runtime error: interrupted"), std::string::npos) << err;
  const size_t table = out.find("jit traces:\n");
  ASSERT_NE(table, std::string::npos) << out.substr(out.size() > 2000 ? out.size() - 2000 : 0);
  EXPECT_NE(out.find(" compiled\n", table), std::string::npos) << out.substr(table);
}

TEST_F(JitStats, ScenePrintsThemAfterCtrlC) {
  ctrl_c_stops([&](const std::string& f, const std::string& t) { write(f, t); },
               [&](const std::string& f) { return path(f); }, scene("nudge.sim", 2000000000, 8),
               "1");
}

// A 500 x 500 cloth's points (250,000) in chunks on 3 threads.
TEST_F(JitStats, ScenePrintsThemAfterCtrlCOnThreads) {
  ctrl_c_stops([&](const std::string& f, const std::string& t) { write(f, t); },
               [&](const std::string& f) { return path(f); }, scene("nudge.sim", 2000000000, 500),
               "3");
}

}  // namespace
}  // namespace simit::tools
