// The command line's executor options: `--executor` (and its other name, `--backend`),
// `--threads`, `--jit-threshold`, `--check-jit`, `--dump`, `--jit-cache`, each parsed once into
// the choice the engine receives; bad values are usage errors naming the valid ones; a scene's
// `threads` key and the command line's precedence over it; and a scene run shows the engine
// ran the JIT with the threshold given.
#include <gtest/gtest.h>
#include <sched.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include "cli.h"
#include "scene/scene_sets.h"

namespace simit::tools {
namespace {

namespace fs = std::filesystem;

std::vector<const char*> argv_of(std::vector<std::string>& args) {
  args.insert(args.begin(), "simit");
  std::vector<const char*> argv;
  for (const auto& a : args) argv.push_back(a.c_str());
  return argv;
}

std::optional<ExecutorChoice> parse(std::vector<std::string> args, std::string* error = nullptr) {
  std::vector<const char*> argv = argv_of(args);
  std::ostringstream err;
  std::optional<ExecutorChoice> c =
      parse_executor_choice(static_cast<int>(argv.size()), argv.data(), err);
  if (error) *error = err.str();
  return c;
}

// The CPUs this process may use, counted independently of default_threads().
int cpu_count() {
  cpu_set_t set;
  CPU_ZERO(&set);
  EXPECT_EQ(sched_getaffinity(0, sizeof set, &set), 0);
  return CPU_COUNT(&set);
}

struct Result {
  int status;
  std::string out, err;
};

Result cli(std::vector<std::string> args) {
  std::vector<const char*> argv = argv_of(args);
  std::ostringstream out, err;
  const int status = run_cli(static_cast<int>(argv.size()), argv.data(), out, err);
  return {status, out.str(), err.str()};
}

TEST(ExecutorOptions, EachSpellingGivesOneChoice) {
  for (const char* spelling : {"--executor", "--backend"}) {
    std::optional<ExecutorChoice> c =
        parse({"run", "f.sim", "--call", "main", spelling, "jit", "--jit-threshold", "3",
               "--check-jit", "--dump=loop-ir,llvm", "--jit-cache", "off"});
    ASSERT_TRUE(c) << spelling;
    EXPECT_EQ(c->kind, ExecutorKind::Jit) << spelling;
    EXPECT_EQ(c->threshold, 3);
    EXPECT_TRUE(c->check);
    EXPECT_TRUE(c->dump_loop_ir);
    EXPECT_TRUE(c->dump_llvm);
    EXPECT_EQ(c->jit_cache, "off");
    EXPECT_EQ(c->threads, cpu_count());
    EXPECT_TRUE(c->eager);  // a production run
  }
  std::optional<ExecutorChoice> test = parse({"test", "--executor=jit", "--jit-threshold=0",
                                              "--jit-cache", "/tmp/k", "--threads", "5", "x.sim"});
  ASSERT_TRUE(test);
  EXPECT_EQ(test->kind, ExecutorKind::Jit);
  EXPECT_EQ(test->threshold, 0);
  EXPECT_FALSE(test->check);
  EXPECT_EQ(test->jit_cache, "/tmp/k");
  EXPECT_EQ(test->threads, 5);
  // The defaults: the interpreter on every core; `simit run` caches in the user's folder,
  // `simit test` nowhere.
  std::optional<ExecutorChoice> run = parse({"run", "s.toml"});
  ASSERT_TRUE(run);
  EXPECT_EQ(run->kind, ExecutorKind::Interpreter);
  EXPECT_EQ(run->threshold, -1);
  EXPECT_EQ(run->jit_cache, "");
  EXPECT_EQ(run->threads, cpu_count());
  std::optional<ExecutorChoice> tests = parse({"test", "x.sim"});
  ASSERT_TRUE(tests);
  EXPECT_EQ(tests->jit_cache, "off");
  EXPECT_EQ(tests->threads, cpu_count());
}

// --threads on both commands, with the interpreter too (which runs serially whatever N);
// all and 0 are every core.
TEST(ExecutorOptions, ThreadsReachTheChoice) {
  for (const char* command : {"run", "test"})
    for (const auto& [given, want] :
         {std::pair{"1", 1}, std::pair{"12", 12}, std::pair{"1024", 1024},
          std::pair{"all", cpu_count()}, std::pair{"0", cpu_count()}}) {
      std::vector<std::string> args = {command, "--threads", given, "f.sim"};
      if (std::string(command) == "run") args.insert(args.end(), {"--call", "main"});
      std::optional<ExecutorChoice> c = parse(args);
      ASSERT_TRUE(c) << command << " " << given;
      EXPECT_EQ(c->threads, want) << command << " " << given;
      EXPECT_EQ(c->kind, ExecutorKind::Interpreter);
    }
  std::optional<ExecutorChoice> jit = parse({"run", "f.sim", "--call", "main", "--executor", "jit",
                                             "--threads=2", "--jit-threshold", "0"});
  ASSERT_TRUE(jit);
  EXPECT_EQ(jit->kind, ExecutorKind::Jit);
  EXPECT_EQ(jit->threads, 2);
  EXPECT_EQ(jit->threshold, 0);
}

// --help states the option, its range and the default, counted here.
TEST(ExecutorOptions, HelpStatesTheThreadsDefault) {
  for (const char* command : {"run", "test"}) {
    Result r = cli({command, "--help"});
    EXPECT_EQ(r.status, 0);
    EXPECT_NE(r.out.find("--threads N|all"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("(default: every core, " + std::to_string(cpu_count()) + " here)"),
              std::string::npos)
        << r.out;
    EXPECT_NE(r.out.find("runs on one thread whatever N"), std::string::npos) << r.out;
  }
}

// Each bad value is a usage error (status 2) that names it and the valid ones.
TEST(ExecutorOptions, BadValuesAreRefusedWhereGiven) {
  const std::vector<std::pair<std::vector<std::string>, std::string>> cases = {
      {{"--executor", "jti"},
       "--executor: unknown executor 'jti': valid executors are interpreter, jit, gpu"},
      {{"--jit-threshold", "-1"},
       "--jit-threshold: bad JIT threshold '-1': expected a whole number of executions from 0 "
       "(0: compile at once)"},
      {{"--dump", "loop-ir,asm"},
       "--dump: unknown dump kind 'asm': valid dump kinds are loop-ir, passes, llvm, ptx"},
      {{"--jit-cache", ""}, "--jit-cache: empty JIT cache: expected 'off' or a folder"},
      {{"--gpu-arch", "sm90"},
       "--gpu-arch: bad GPU architecture 'sm90': expected sm_ and digits, e.g. sm_90"},
      {{"--threads", "1025"},
       "--threads: bad thread count '1025': expected a whole number from 1 to 1024, or all (or "
       "0): every core this process may use"},
      {{"--threads", "-2"},
       "--threads: bad thread count '-2': expected a whole number from 1 to 1024, or all (or "
       "0): every core this process may use"},
      {{"--threads", "four"},
       "--threads: bad thread count 'four': expected a whole number from 1 to 1024, or all (or "
       "0): every core this process may use"},
  };
  for (const auto& [option, message] : cases) {
    std::vector<std::string> args = {"run", "f.sim", "--call", "main"};
    args.insert(args.end(), option.begin(), option.end());
    Result r = cli(args);
    EXPECT_EQ(r.status, 2) << message;
    EXPECT_EQ(r.err.substr(0, r.err.find('\n')), "simit: error: " + message);
    std::string error;
    EXPECT_FALSE(parse(args, &error));
    EXPECT_EQ(error, "simit: error: " + message + "\n");
  }
  Result r = cli({"test", "--executor", "jti", "x.sim"});
  EXPECT_EQ(r.status, 2);
  EXPECT_EQ(r.err.substr(0, r.err.find('\n')),
            "simit: error: --executor: unknown executor 'jti': valid executors are interpreter, "
            "jit, gpu");
  r = cli({"test", "--threads", "2.5", "x.sim"});
  EXPECT_EQ(r.status, 2);
  EXPECT_EQ(r.err.substr(0, r.err.find('\n')),
            "simit: error: --threads: bad thread count '2.5': expected a whole number from 1 to "
            "1024, or all (or 0): every core this process may use");
}

// A scene folder with a one-apply program; removed at the end of the test.
struct SceneDir {
  SceneDir() {
    std::string pattern = (fs::temp_directory_path() / "simit-threads-XXXXXX").string();
    EXPECT_NE(mkdtemp(pattern.data()), nullptr);
    dir = pattern;
    std::ofstream(dir / "nudge.sim")
        << "element Point\n  x : vector[3](float);\n  w : float;\nend\n"
           "extern points : set{Point};\n"
           "func nudge(inout p : Point)\n  p.w = p.w + 1.0;\nend\n"
           "export func step()\n  apply nudge to points;\nend\n";
  }
  ~SceneDir() { fs::remove_all(dir); }
  // A scene whose top-level keys start with `keys`.
  std::string write(const std::string& name, const std::string& keys) {
    std::ofstream(dir / name) << keys
                              << "program = \"nudge.sim\"\nstep = \"step\"\nframes = 2\n"
                                 "[sets.points]\ngenerate = \"square_cloth\"\nn = 3\n"
                                 "elements = \"vertices\"\n[sets.points.fields]\n"
                                 "x = \"position\"\nw = 1.0\n";
    return (dir / name).string();
  }
  fs::path dir;
};

// The threads the scene opened by `simit ARGS...` resolves, or -1 (with the error on `err`).
int scene_threads(std::vector<std::string> args, std::string* error = nullptr) {
  std::vector<const char*> argv = argv_of(args);
  std::ostringstream err;
  std::optional<SceneOptions> o =
      parse_scene_options(static_cast<int>(argv.size()), argv.data(), err);
  std::unique_ptr<scene::Scene> s = o ? scene::Scene::open(*o, err) : nullptr;
  if (error) *error = err.str();
  return s ? scene::SceneAccess::executor(*s).threads : -1;
}

// The scene's `threads` key sets the count unless --threads was given (as `executor` and
// --executor); its bad values are located errors.
TEST(ExecutorOptions, TheScenesThreadsKeyAndTheCommandLinesPrecedence) {
  SceneDir d;
  const std::string two = d.write("two.toml", "threads = 2\n");
  EXPECT_EQ(scene_threads({"run", two}), 2);
  EXPECT_EQ(scene_threads({"run", "--threads", "5", two}), 5);
  EXPECT_EQ(scene_threads({"run", "--threads", "all", two}), cpu_count());
  EXPECT_EQ(scene_threads({"run", d.write("all.toml", "threads = \"all\"\n")}), cpu_count());
  EXPECT_EQ(scene_threads({"run", d.write("zero.toml", "threads = 0\n")}), cpu_count());
  const std::string none = d.write("none.toml", "");
  EXPECT_EQ(scene_threads({"run", none}), cpu_count());
  EXPECT_EQ(scene_threads({"run", "--threads=3", none}), 3);

  const std::string expected =
      "expected a whole number from 1 to 1024, or all (or 0): every core this process may use";
  for (const auto& [value, message] :
       {std::pair{"2000", "threads: bad thread count '2000': " + expected},
        std::pair{"-1", "threads: bad thread count '-1': " + expected},
        std::pair{"\"many\"", "threads: bad thread count 'many': " + expected},
        std::pair{"2.5", std::string("threads: expected a whole number from 1 to 1024, or "
                                     "\"all\"")}}) {
    const std::string bad = d.write("bad.toml", std::string("threads = ") + value + "\n");
    std::string error;
    EXPECT_EQ(scene_threads({"run", bad}, &error), -1) << value;
    EXPECT_EQ(error, bad + ":1:11: error: " + message + "\n") << value;
    // The whole run says the same, exit status 1.
    Result r = cli({"run", bad});
    EXPECT_EQ(r.status, 1) << value;
    EXPECT_EQ(r.err, bad + ":1:11: error: " + message + "\n") << value;
  }
}

// What the command line gives reaches the engine: the JIT runs the scene's apply, compiling
// it after `--jit-threshold` interpreted executions, whichever name chose it.
TEST(ExecutorOptions, TheEngineRunsTheChoice) {
  std::string pattern = (fs::temp_directory_path() / "simit-executor-XXXXXX").string();
  ASSERT_NE(mkdtemp(pattern.data()), nullptr);
  const fs::path dir = pattern;
  std::ofstream(dir / "nudge.sim") << "element Point\n  x : vector[3](float);\n  w : float;\nend\n"
                                      "extern points : set{Point};\n"
                                      "func nudge(inout p : Point)\n  p.w = p.w + 1.0;\nend\n"
                                      "export func step()\n  apply nudge to points;\nend\n";
  std::ofstream(dir / "scene.toml")
      << "program = \"nudge.sim\"\nstep = \"step\"\nframes = 5\n[sets.points]\n"
         "generate = \"square_cloth\"\nn = 3\nelements = \"vertices\"\n[sets.points.fields]\n"
         "x = \"position\"\nw = 1.0\n";
  const std::string scene = (dir / "scene.toml").string();
  if (!jit_available()) {
    Result r = cli({"run", "--executor", "jit", scene});
    EXPECT_EQ(r.status, 1);
    EXPECT_EQ(r.err.rfind(scene + ": error: this build has no JIT: configure with "
                                  "-DSIMIT_WITH_LLVM=ON",
                          0),
              0u)
        << r.err;
    fs::remove_all(dir);
    GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  }
  // 5 frames: with threshold T the apply runs T times interpreted, then 5 - T compiled.
  for (const auto& [spelling, threshold, calls] :
       {std::tuple{"--executor", "0", 5L}, std::tuple{"--backend", "2", 3L}}) {
    Result r = cli({"run", spelling, "jit", "--jit-threshold", threshold, "--jit-stats",
                    "--jit-cache", "off", scene});
    ASSERT_EQ(r.status, 0) << r.err;
    const size_t table = r.out.find("jit traces:\n");
    ASSERT_NE(table, std::string::npos) << r.out;
    const size_t site = r.out.find("\n  nudge (line ", table);
    ASSERT_NE(site, std::string::npos) << r.out;
    const std::string row = r.out.substr(site + 1, r.out.find('\n', site + 1) - site - 1);
    EXPECT_TRUE(row.ends_with("  compiled")) << row;
    std::istringstream fields(row.substr(row.find(')') + 1));
    double compile_ms = 0;
    long n = 0;
    fields >> compile_ms >> n;
    EXPECT_EQ(n, calls) << spelling << " " << threshold << ": " << row;
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace simit::tools
