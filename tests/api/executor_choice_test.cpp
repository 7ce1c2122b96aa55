// The executor choice (simit/executor.h): its parsers' values and errors, the default thread
// count (the process's affinity mask), the API's spellings of it (Options::executor,
// init("cpu")), the choice reaching the engine whole, and the engine's resolution of the JIT
// cache setting.
#include <gtest/gtest.h>
#include <sched.h>

#include <cstdlib>
#include <optional>
#include <string>
#include <vector>

#include "api/engine.h"
#include "api_test_util.h"
#include "simit/simit.h"

namespace {

using simit::ExecutorChoice;
using simit::ExecutorKind;
using simit::testing::message_of;

constexpr const char* kNoJit = "this build has no JIT: configure with -DSIMIT_WITH_LLVM=ON";

TEST(ExecutorChoice, ParsesTheKindsAndNamesTheValidOnes) {
  std::string error;
  EXPECT_EQ(simit::parse_executor_kind("interpreter", error), ExecutorKind::Interpreter);
  EXPECT_EQ(simit::parse_executor_kind("jit", error), ExecutorKind::Jit);
  EXPECT_EQ(error, "");
  EXPECT_EQ(simit::parse_executor_kind("jti", error), std::nullopt);
  EXPECT_EQ(error, "unknown executor 'jti': valid executors are interpreter, jit, gpu");
  EXPECT_EQ(simit::parse_executor_kind("", error), std::nullopt);
  EXPECT_EQ(error, "unknown executor '': valid executors are interpreter, jit, gpu");
  EXPECT_STREQ(simit::executor_name(ExecutorKind::Jit), "jit");
  EXPECT_STREQ(simit::executor_name(ExecutorKind::Interpreter), "interpreter");
  EXPECT_EQ(simit::parse_executor_kind("gpu", error), ExecutorKind::Gpu);
  EXPECT_STREQ(simit::executor_name(ExecutorKind::Gpu), "gpu");
  EXPECT_TRUE(simit::compiles(ExecutorKind::Gpu));
  EXPECT_TRUE(simit::compiles(ExecutorKind::Jit));
  EXPECT_FALSE(simit::compiles(ExecutorKind::Interpreter));
}

TEST(ExecutorChoice, ParsesGpuArchitectures) {
  std::string error;
  EXPECT_EQ(simit::parse_gpu_arch("sm_90", error), "sm_90");
  EXPECT_EQ(simit::parse_gpu_arch("sm_100", error), "sm_100");
  EXPECT_EQ(error, "");
  for (const char* bad : {"sm90", "sm_", "sm_9a", "compute_90", ""}) {
    EXPECT_EQ(simit::parse_gpu_arch(bad, error), std::nullopt) << bad;
    EXPECT_EQ(error, "bad GPU architecture '" + std::string(bad) +
                         "': expected sm_ and digits, e.g. sm_90");
  }
}

TEST(ExecutorChoice, ParsesDumpKindsThresholdsAndCaches) {
  std::string error;
  ExecutorChoice c;
  EXPECT_TRUE(simit::parse_dump_kind("llvm", c, error));
  EXPECT_TRUE(c.dump_llvm);
  EXPECT_FALSE(c.dump_loop_ir);
  EXPECT_TRUE(simit::parse_dump_kind("loop-ir", c, error));
  EXPECT_TRUE(c.dump_loop_ir);
  EXPECT_FALSE(simit::parse_dump_kind("asm", c, error));
  EXPECT_EQ(error, "unknown dump kind 'asm': valid dump kinds are loop-ir, passes, llvm, ptx");

  EXPECT_EQ(simit::parse_jit_threshold("0", error), 0L);
  EXPECT_EQ(simit::parse_jit_threshold("17", error), 17L);
  for (const char* bad : {"-1", "2.5", "x", "", "3 "}) {
    EXPECT_EQ(simit::parse_jit_threshold(bad, error), std::nullopt) << bad;
    EXPECT_EQ(error, std::string("bad JIT threshold '") + bad +
                         "': expected a whole number of executions from 0 (0: compile at once)");
  }

  EXPECT_EQ(simit::parse_jit_cache("off", error), "off");
  EXPECT_EQ(simit::parse_jit_cache("/tmp/kernels", error), "/tmp/kernels");
  EXPECT_EQ(simit::parse_jit_cache("", error), std::nullopt);
  EXPECT_EQ(error, "empty JIT cache: expected 'off' or a folder");
}

TEST(ExecutorChoice, ParsesThreadCounts) {
  std::string error;
  EXPECT_EQ(simit::parse_threads("1", error), 1);
  EXPECT_EQ(simit::parse_threads("3", error), 3);
  EXPECT_EQ(simit::parse_threads("1024", error), 1024);
  EXPECT_EQ(error, "");
  // "all" and 0: every core this process may use.
  EXPECT_EQ(simit::parse_threads("all", error), simit::default_threads());
  EXPECT_EQ(simit::parse_threads("0", error), simit::default_threads());
  for (const char* bad :
       {"1025", "-1", "2.5", "x", "", "3 ", " 3", "+2", "ALL", "4096", "99999999999999999999"}) {
    EXPECT_EQ(simit::parse_threads(bad, error), std::nullopt) << bad;
    EXPECT_EQ(error, std::string("bad thread count '") + bad +
                         "': expected a whole number from 1 to 1024, or all (or 0): every core "
                         "this process may use");
  }
}

// The CPUs this thread may run on, as a set of their numbers.
std::vector<int> allowed_cpus() {
  cpu_set_t set;
  CPU_ZERO(&set);
  EXPECT_EQ(sched_getaffinity(0, sizeof set, &set), 0);
  std::vector<int> cpus;
  for (int i = 0; i < CPU_SETSIZE; ++i)
    if (CPU_ISSET(i, &set)) cpus.push_back(i);
  return cpus;
}

// Restricts this thread to `cpus` for one test, restoring the mask it had after it.
struct ScopedAffinity {
  explicit ScopedAffinity(const std::vector<int>& cpus) {
    EXPECT_EQ(sched_getaffinity(0, sizeof old_, &old_), 0);
    cpu_set_t set;
    CPU_ZERO(&set);
    for (int c : cpus) CPU_SET(c, &set);
    EXPECT_EQ(sched_setaffinity(0, sizeof set, &set), 0);
  }
  ~ScopedAffinity() { EXPECT_EQ(sched_setaffinity(0, sizeof old_, &old_), 0); }
  cpu_set_t old_;
};

// The default is the number of CPUs in the affinity mask, not the machine's: a run restricted
// to one CPU (taskset -c 0) defaults to one thread.
TEST(ExecutorChoice, TheDefaultThreadCountIsTheAffinityMasks) {
  const std::vector<int> cpus = allowed_cpus();
  ASSERT_FALSE(cpus.empty());
  EXPECT_EQ(simit::default_threads(), static_cast<int>(cpus.size()));
  EXPECT_EQ(ExecutorChoice{}.threads, static_cast<int>(cpus.size()));
  {
    ScopedAffinity one({cpus.back()});
    EXPECT_EQ(simit::default_threads(), 1);
    EXPECT_EQ(ExecutorChoice{}.threads, 1);
    std::string error;
    EXPECT_EQ(simit::parse_threads("all", error), 1);
  }
  if (cpus.size() >= 2) {
    ScopedAffinity two({cpus[0], cpus[1]});
    EXPECT_EQ(simit::default_threads(), 2);
  }
  EXPECT_EQ(simit::default_threads(), static_cast<int>(cpus.size()));
}

TEST(ExecutorChoice, TheDefaultsAndWhatThisBuildRuns) {
  const ExecutorChoice c;
  EXPECT_EQ(c.kind, ExecutorKind::Interpreter);
  EXPECT_EQ(c.threads, static_cast<int>(allowed_cpus().size()));
  EXPECT_EQ(c.threshold, -1);
  EXPECT_FALSE(c.check);
  EXPECT_EQ(c.jit_cache, "");
  EXPECT_TRUE(c.eager);
  EXPECT_EQ(simit::executor_unavailable(c), "");
  // Any count from 1 to 1024, whatever the executor (the interpreter runs serially).
  for (int n : {1, 4, 1024}) {
    ExecutorChoice threads;
    threads.threads = n;
    EXPECT_EQ(simit::executor_unavailable(threads), "") << n;
  }
  // A count no parser gives, set by a program: refused.
  for (int n : {0, -2, 1025}) {
    ExecutorChoice threads;
    threads.threads = n;
    EXPECT_EQ(simit::executor_unavailable(threads),
              "bad thread count " + std::to_string(n) +
                  ": expected a whole number from 1 to 1024 (default_threads(): every core this "
                  "process may use)");
  }
  ExecutorChoice jit;
  jit.kind = ExecutorKind::Jit;
  if (simit::jit_available())
    EXPECT_EQ(simit::executor_unavailable(jit), "");
  else
    EXPECT_EQ(simit::executor_unavailable(jit).rfind(kNoJit, 0), 0u)
        << simit::executor_unavailable(jit);
}

// init("cpu") is the original's name of its JIT; a build without one says how to get it.
TEST(ExecutorChoice, InitSpellings) {
  EXPECT_EQ(simit::init("interpreter").executor.kind, ExecutorKind::Interpreter);
  if (simit::jit_available()) {
    EXPECT_EQ(simit::init("cpu").executor.kind, ExecutorKind::Jit);
    EXPECT_EQ(simit::init("jit", 4).executor.kind, ExecutorKind::Jit);
  } else {
    EXPECT_EQ(message_of<simit::Error>([] { (void)simit::init("cpu"); }).rfind(kNoJit, 0), 0u);
  }
  EXPECT_EQ(message_of<simit::Error>([] { (void)simit::init("jti"); }),
            "unknown executor 'jti': valid executors are interpreter, jit, gpu (or cpu, the JIT)");
  // A GPU executor where no GPU opens (this build without the JIT, or no driver or device)
  // says why; with the test emulation it is chosen.
  if (!simit::jit_available()) {
    EXPECT_EQ(message_of<simit::Error>([] { (void)simit::init("gpu"); }).rfind(kNoJit, 0), 0u);
  } else if (simit::gpu_emulated_for_test()) {
    EXPECT_EQ(simit::init("gpu").executor.kind, ExecutorKind::Gpu);
  } else {
    const std::string why = simit::executor_unavailable(ExecutorChoice{.kind = ExecutorKind::Gpu});
    if (why.empty()) {
      EXPECT_EQ(simit::init("gpu").executor.kind, ExecutorKind::Gpu);
    } else {
      EXPECT_EQ(why.rfind("no GPU to run on: ", 0), 0u) << why;
      EXPECT_EQ(message_of<simit::Error>([] { (void)simit::init("gpu"); }), why);
    }
  }
}

const char* kProgram = R"(
element Node
  x : float;
end
extern nodes : set{Node};

func grow(inout n : Node)
  n.x = 2.0 * n.x + 1.0;
end

export func step()
  apply grow to nodes;
end
)";

// Options::executor is handed to the function's engine unchanged: the engine runs the JIT with
// the threshold and check asked for, and the values are the interpreter's.
TEST(ExecutorChoice, OptionsReachTheEngine) {
  if (!simit::jit_available()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  simit::Options o;
  o.executor.kind = ExecutorKind::Jit;
  o.executor.threshold = 0;
  o.executor.check = true;
  o.executor.jit_cache = "off";
  o.executor.threads = 3;
  simit::Program p(o);
  p.load_string(kProgram, "grow.sim");
  simit::Function step = p.compile("step");
  simit::Set nodes("nodes");
  simit::FieldRef<double> x = nodes.add_field<double>("x");
  for (int i = 0; i < 3; ++i) x.set(nodes.add(), 1.0 * i);
  step.bind("nodes", nodes);
  step.init();
  const ExecutorChoice& got = step.executor();
  EXPECT_EQ(got.kind, ExecutorKind::Jit);
  EXPECT_EQ(got.threshold, 0);
  EXPECT_TRUE(got.check);
  EXPECT_EQ(got.jit_cache, "off");
  EXPECT_EQ(got.threads, 3);
  step.run();
  step.run();
  // x -> 2x + 1, twice: 0 -> 3, 1 -> 7, 2 -> 11.
  EXPECT_EQ(double(x(simit::ElementRef(0))), 3.0);
  EXPECT_EQ(double(x(simit::ElementRef(1))), 7.0);
  EXPECT_EQ(double(x(simit::ElementRef(2))), 11.0);
}

// The interpreter takes any thread count and runs serially: the values of one thread.
TEST(ExecutorChoice, TheInterpreterRunsAnyThreadCount) {
  for (int n : {1, 2, 7}) {
    simit::Options o;
    o.executor.threads = n;
    simit::Program p(o);
    p.load_string(kProgram, "grow.sim");
    simit::Function step = p.compile("step");
    simit::Set nodes("nodes");
    simit::FieldRef<double> x = nodes.add_field<double>("x");
    for (int i = 0; i < 3; ++i) x.set(nodes.add(), 1.0 * i);
    step.bind("nodes", nodes);
    step.init();
    EXPECT_EQ(step.executor().threads, n);
    step.run();
    // x -> 2x + 1: 0 -> 1, 1 -> 3, 2 -> 5.
    EXPECT_EQ(double(x(simit::ElementRef(0))), 1.0) << n;
    EXPECT_EQ(double(x(simit::ElementRef(1))), 3.0) << n;
    EXPECT_EQ(double(x(simit::ElementRef(2))), 5.0) << n;
  }
}

// A choice this build cannot run is refused where the API meets it, naming why.
TEST(ExecutorChoice, OptionsThisBuildCannotRunAreRefused) {
  simit::Options o;
  o.executor.threads = 0;
  simit::Program p(o);
  p.load_string(kProgram, "grow.sim");
  EXPECT_EQ(message_of<simit::Error>([&] { (void)p.compile("step"); }),
            "bad thread count 0: expected a whole number from 1 to 1024 (default_threads(): "
            "every core this process may use)");
  if (simit::jit_available()) return;
  simit::Options jit;
  jit.executor.kind = ExecutorKind::Jit;
  simit::Program q(jit);
  q.load_string(kProgram, "grow.sim");
  EXPECT_EQ(message_of<simit::Error>([&] { (void)q.compile("step"); }).rfind(kNoJit, 0), 0u);
}

// An environment variable set (or unset) for one test, restored after it.
struct ScopedEnv {
  ScopedEnv(const char* name, const char* value) : name_(name) {
    if (const char* old = std::getenv(name)) old_ = old;
    if (value)
      setenv(name, value, 1);
    else
      unsetenv(name);
  }
  ~ScopedEnv() {
    if (old_)
      setenv(name_, old_->c_str(), 1);
    else
      unsetenv(name_);
  }
  const char* name_;
  std::optional<std::string> old_;
};

TEST(ExecutorChoice, TheJitCacheSettingResolves) {
  using simit::api::jit_cache_folder;
  EXPECT_EQ(jit_cache_folder("off"), "");
  EXPECT_EQ(jit_cache_folder("/data/kernels"), "/data/kernels");
  {
    ScopedEnv xdg("XDG_CACHE_HOME", "/xdg/cache");
    ScopedEnv home("HOME", "/home/someone");
    EXPECT_EQ(jit_cache_folder(""), "/xdg/cache/simit/kernels");
  }
  {
    ScopedEnv xdg("XDG_CACHE_HOME", nullptr);
    ScopedEnv home("HOME", "/home/someone");
    EXPECT_EQ(jit_cache_folder(""), "/home/someone/.cache/simit/kernels");
  }
  {
    ScopedEnv xdg("XDG_CACHE_HOME", nullptr);
    ScopedEnv home("HOME", nullptr);
    EXPECT_EQ(jit_cache_folder(""), "");
  }
}

// The engine keeps the choice it is given; built directly (tests, tools) it keeps no cache.
TEST(ExecutorChoice, TheEngineKeepsItsChoice) {
  auto compiled = simit::api::CompiledProgram::from_source("grow.sim", kProgram);
  ASSERT_TRUE(compiled->ok());
  EXPECT_EQ(simit::api::EngineOptions{}.executor.jit_cache, "off");
  simit::api::EngineOptions o;
  o.executor.kind = ExecutorKind::Jit;
  o.executor.threshold = 5;
  o.executor.check = true;
  if (!simit::jit_available()) {
    try {
      simit::api::Engine engine(compiled, o);
      ADD_FAILURE() << "a JIT engine in a build without one";
    } catch (const std::runtime_error& e) {
      EXPECT_EQ(std::string(e.what()).rfind(kNoJit, 0), 0u) << e.what();
    }
    return;
  }
  simit::api::Engine engine(compiled, o);
  EXPECT_EQ(engine.executor(), ExecutorKind::Jit);
  EXPECT_EQ(engine.options().executor.threshold, 5);
  EXPECT_TRUE(engine.options().executor.check);
  engine.set_executor(ExecutorKind::Interpreter);
  EXPECT_EQ(engine.options().executor.kind, ExecutorKind::Interpreter);
  EXPECT_EQ(engine.options().executor.threshold, 5);  // the rest of the choice stays
}

}  // namespace
