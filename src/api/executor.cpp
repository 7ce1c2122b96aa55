// The executor choice's parsers (simit/executor.h): the one place each spelling a user writes
// is turned into the typed value, with the one wording of its errors.
#include "simit/executor.h"

#include <algorithm>
#include <charconv>
#include <cstdlib>

#include "runtime/cpus.h"

#ifdef SIMIT_HAS_JIT
#include "jit/ptx/cuda_driver.h"
#include "jit/ptx/ptx_check.h"
#endif

namespace simit {

bool gpu_emulated_for_test() {
  const char* e = std::getenv("SIMIT_TEST_GPU_EMULATION");
  return e && *e && std::string_view(e) != "0";
}

const char* executor_name(ExecutorKind kind) {
  switch (kind) {
    case ExecutorKind::Interpreter: return "interpreter";
    case ExecutorKind::Jit: return "jit";
    case ExecutorKind::Gpu: return "gpu";
  }
  return "interpreter";
}

std::optional<ExecutorKind> parse_executor_kind(std::string_view text, std::string& error) {
  if (text == "interpreter") return ExecutorKind::Interpreter;
  if (text == "jit") return ExecutorKind::Jit;
  if (text == "gpu") return ExecutorKind::Gpu;
  error = "unknown executor '" + std::string(text) + "': valid executors are interpreter, jit, gpu";
  return std::nullopt;
}

bool parse_dump_kind(std::string_view text, ExecutorChoice& choice, std::string& error) {
  if (text == "loop-ir") {
    choice.dump_loop_ir = true;
  } else if (text == "llvm") {
    choice.dump_llvm = true;
  } else if (text == "passes") {
    choice.dump_passes = true;
  } else if (text == "ptx") {
    choice.dump_ptx = true;
  } else {
    error = "unknown dump kind '" + std::string(text) +
            "': valid dump kinds are loop-ir, passes, llvm, ptx";
    return false;
  }
  return true;
}

std::optional<long> parse_jit_threshold(std::string_view text, std::string& error) {
  long n = 0;
  auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), n);
  if (ec == std::errc() && end == text.data() + text.size() && n >= 0) return n;
  error = "bad JIT threshold '" + std::string(text) +
          "': expected a whole number of executions from 0 (0: compile at once)";
  return std::nullopt;
}

std::optional<std::string> parse_gpu_arch(std::string_view text, std::string& error) {
  const bool digits = text.size() >= 5 && text.substr(0, 3) == "sm_" &&
                      text.substr(3).find_first_not_of("0123456789") == std::string_view::npos;
  if (digits) return std::string(text);
  error = "bad GPU architecture '" + std::string(text) + "': expected sm_ and digits, e.g. sm_90";
  return std::nullopt;
}

std::optional<std::string> parse_jit_cache(std::string_view text, std::string& error) {
  if (!text.empty()) return std::string(text);
  error = "empty JIT cache: expected 'off' or a folder";
  return std::nullopt;
}

int default_threads() { return std::min(runtime::usable_cpus(), kMaxThreads); }

std::optional<int> parse_threads(std::string_view text, std::string& error) {
  if (text == "all") return default_threads();
  int n = -1;
  auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), n);
  if (ec == std::errc() && end == text.data() + text.size() && n >= 0 && n <= kMaxThreads)
    return n == 0 ? default_threads() : n;
  error = "bad thread count '" + std::string(text) + "': expected a whole number from 1 to " +
          std::to_string(kMaxThreads) + ", or all (or 0): every core this process may use";
  return std::nullopt;
}

bool jit_available() {
#ifdef SIMIT_HAS_JIT
  return true;
#else
  return false;
#endif
}

std::string executor_unavailable(const ExecutorChoice& choice) {
  if (compiles(choice.kind) && !jit_available())
    return "this build has no JIT: configure with -DSIMIT_WITH_LLVM=ON (LLVM 19)";
  if (choice.kind == ExecutorKind::Gpu) {
#ifdef SIMIT_HAS_JIT
    // The tests of the GPU's data path run it over host memory where there is no GPU.
    if (!gpu_emulated_for_test())
      if (std::string why = jit::cuda::gpu_unavailable_reason(); !why.empty())
        return "no GPU to run on: " + why;
#endif
  }
  if (choice.threads < 1 || choice.threads > kMaxThreads)
    return "bad thread count " + std::to_string(choice.threads) +
           ": expected a whole number from 1 to " + std::to_string(kMaxThreads) +
           " (default_threads(): every core this process may use)";
  if (choice.check_ptx) {
#ifdef SIMIT_HAS_JIT
    std::string why;
    if (jit::ptx::find_ptxas(why).empty()) return why;
#else
    return "--check-ptx needs the JIT, which this build has not: configure with "
           "-DSIMIT_WITH_LLVM=ON (LLVM 19)";
#endif
  }
  return "";
}

std::string check_ptx_summary() {
#ifdef SIMIT_HAS_JIT
  return jit::ptx::tally_summary();
#else
  return "";
#endif
}

}  // namespace simit
