// The executor choice: what runs a program's functions and how, as one typed value. Each
// front end (the command line, the REPL's `:set`, a scene file's keys, the API's Options)
// parses what its user wrote once, with the functions below, and hands the value down to the
// engine unchanged.
#pragma once

#include <optional>
#include <string>
#include <string_view>

namespace simit {

// The reference interpreter, the tracing JIT (hot map and apply sites and runs of system
// statements compiled to native code with LLVM; a build with -DSIMIT_WITH_LLVM=ON), or the
// JIT with its map kernels compiled to PTX and run on an NVIDIA GPU (gpu; the rest as jit).
enum class ExecutorKind { Interpreter, Jit, Gpu };

// Whether `kind` compiles (jit and gpu): what the JIT's options (--jit-stats, --check-jit,
// threads, the kernel cache) apply to.
inline bool compiles(ExecutorKind kind) { return kind != ExecutorKind::Interpreter; }

// The most threads a choice may ask for.
inline constexpr int kMaxThreads = 1024;

// Every core this process may use: the CPUs of its affinity mask (sched_getaffinity, so a run
// under `taskset` or in a container's cpuset counts only its own), else
// std::thread::hardware_concurrency(); at least 1 and at most kMaxThreads. Read anew at each
// call (the mask may change).
int default_threads();

struct ExecutorChoice {
  ExecutorKind kind = ExecutorKind::Interpreter;
  // jit: the threads that run compiled maps and solver loops (1: serially, on the calling
  // thread), from 1 to kMaxThreads. The interpreter, and what the JIT leaves interpreted, runs
  // on one thread whatever the count: results are the same bits for every count.
  int threads = default_threads();
  // jit: executions of a site before it is compiled (0: at once); -1: the JIT's default.
  long threshold = -1;
  // jit (`--check-jit`): every compiled call also runs interpreted on the same inputs, and the
  // first result, field or variable that differs stops the run, naming it.
  bool check = false;
  // `--check-ptx` (any executor; a build with the JIT and the CUDA toolkit's ptxas): every
  // trace the run compiles for the CPU is also compiled for the GPU (PTX for sm_90) and
  // assembled by ptxas; the first PTX ptxas rejects stops the run, naming the trace.
  // check_ptx_summary() then says what was checked.
  bool check_ptx = false;
  // jit (`--dump=loop-ir,passes,llvm,ptx`): print each compiled trace's loop IR, its loop IR
  // as traced and after each pass of the lowering, its optimised LLVM IR, and/or its PTX.
  bool dump_loop_ir = false;
  bool dump_passes = false;
  bool dump_llvm = false;
  bool dump_ptx = false;
  // gpu and check_ptx: the GPU architecture, "sm_XX" ("": sm_90).
  std::string gpu_arch{};
  // jit: where compiled kernels are cached between runs: "" the user's cache folder
  // ($XDG_CACHE_HOME/simit/kernels, else $HOME/.cache/simit/kernels), "off" none, or a folder.
  std::string jit_cache{};
  // jit: a site over a large set compiles at its first execution, whatever the threshold (a
  // production run: its sites run many times). The REPL turns it off and keeps its threshold.
  bool eager = true;
};

// "interpreter", "jit" or "gpu".
const char* executor_name(ExecutorKind kind);

// The parsers of what a user writes. Each returns nullopt (or false) with `error` naming the
// bad value and listing the valid ones, e.g. "unknown executor 'jti': valid executors are
// interpreter, jit, gpu".
std::optional<ExecutorKind> parse_executor_kind(std::string_view text, std::string& error);
// One dump kind, "loop-ir", "passes", "llvm" or "ptx", switched on in `choice`.
bool parse_dump_kind(std::string_view text, ExecutorChoice& choice, std::string& error);
// A whole number of executions from 0.
std::optional<long> parse_jit_threshold(std::string_view text, std::string& error);
// "off" or a folder (not empty).
std::optional<std::string> parse_jit_cache(std::string_view text, std::string& error);
// A GPU architecture: "sm_" and its compute capability's digits (e.g. sm_90, sm_80);
// whether LLVM knows it is checked when a GPU target is made.
std::optional<std::string> parse_gpu_arch(std::string_view text, std::string& error);
// A whole number of threads from 1 to kMaxThreads, or "all" (or "0", as in other tools'
// thread options): default_threads(), the count returned.
std::optional<int> parse_threads(std::string_view text, std::string& error);

// For the tests: the environment variable SIMIT_TEST_GPU_EMULATION is set (and not 0), so
// `gpu` runs its data path over host memory with the CPU's kernels (jit/ptx/gpu_executor.h).
bool gpu_emulated_for_test();

// Whether this build has the JIT (configured with -DSIMIT_WITH_LLVM=ON).
bool jit_available();
// "" when this build can run `choice`, otherwise why not (a JIT asked of a build without one,
// a thread count outside 1..kMaxThreads, which no parser gives but a program may set,
// check_ptx without the JIT or without ptxas).
std::string executor_unavailable(const ExecutorChoice& choice);

// What `--check-ptx` checked in this process so far: "check-ptx: N traces assembled by
// ptxas, M not compiled for the GPU (K: reason; ...)" ("" in a build without the JIT).
std::string check_ptx_summary();

}  // namespace simit
