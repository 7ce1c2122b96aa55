// The one driver every front end runs through: a program compiled once, the sets and extern
// tensors bound to it, and its functions run by the executor an option chooses.
#pragma once

#include <memory>
#include <ostream>
#include <string>
#include <vector>

#include "api/compiled_program.h"
#include "interp/assembly_plan.h"
#include "interp/hook.h"
#include "interp/interpreter.h"
#include "interp/value.h"
#include "runtime/set.h"
#include "simit/executor.h"

namespace simit::api {

// What executes the program's functions (simit/executor.h): the reference interpreter, or the
// tracing JIT (src/jit), which is the interpreter's site hook (interp/assembly_plan.h): it is
// offered every planned map and apply site and compiles the hot ones to native code, so the
// interpreter stays the driver of every run and the host-facing calls below do not change.
using simit::executor_name;
using simit::ExecutorChoice;
using simit::ExecutorKind;
using simit::jit_available;

// Where a JIT cache setting (ExecutorChoice::jit_cache) puts the kernels: "" the user's cache
// folder ($XDG_CACHE_HOME/simit/kernels, else $HOME/.cache/simit/kernels; no cache when
// neither is set), "off" no cache (""), anything else that folder.
std::string jit_cache_folder(const std::string& setting);

// Settings of one engine; passed down, never global.
struct EngineOptions {
  // What runs the functions, as the front end's user chose it. The engine's own default keeps
  // no kernel cache (tests and tools that build an engine directly write nothing into the
  // user's cache folder); front ends hand their user's whole choice down instead.
  ExecutorChoice executor = ExecutorChoice{.jit_cache = "off"};
  // Round every float to binary32 when produced (Simit `float` is float32).
  bool float32 = false;
  // Stop with a run-time error at the first NaN or infinity produced.
  bool check_finite = false;
  // Where `print` writes; null means standard output.
  std::ostream* out = nullptr;
  // The trap point's host-owned switch (the step debugger, Ctrl-C); null when unused.
  interp::Trap* trap = nullptr;
  // An observer of every statement for the engine's whole life (benchmarks); ignored when
  // `trap` is set.
  interp::StatementHook* hook = nullptr;
  // Offered every planned map / apply site before the interpreter runs it (tests of the
  // executor seam); null with ExecutorKind::Interpreter runs everything in the interpreter.
  // ExecutorKind::Jit installs its own.
  interp::SiteHook* sites = nullptr;
  // A distributed run's seam (interp/distribution.h); null in one process.
  const interp::Distribution* distribution = nullptr;
  // The host reads what a call leaves only through the runtime's accessors, so arrays a GPU
  // keeps newer may stay there across calls (interp::Options::host_uses_accessors).
  bool host_uses_accessors = false;
  // Where the JIT's dumps (ExecutorChoice::dump_loop_ir, dump_llvm) print; null: nowhere.
  std::ostream* dump = nullptr;
  // Tests of the JIT's check only: flips the lowest bit of a compiled map's first result value
  // (else of an apply's first written field, else of a compiled statement's first value).
  bool corrupt_for_test = false;
  // Tests of the executor seam: nonzero runs compiled maps through the test-only shuffled
  // executor (jit/executor.h) with this seed; the environment variable SIMIT_TEST_SHUFFLE_SEED
  // sets it for a whole `simit` process (the corpus, the examples).
  uint64_t shuffle_seed_for_test = 0;
};

// Runs the functions of one compiled program. Bindings and globals persist between calls,
// and so do the matrix patterns assembly builds, so repeated calls (frames) cost no set-up.
// Run-time errors throw interp::RuntimeError (front ends render them in their own terms).
class Engine {
 public:
  // Throws std::runtime_error with executor_unavailable()'s reason when this build cannot run
  // the options' executor choice (front ends check it first, to report it their own way).
  explicit Engine(std::shared_ptr<const CompiledProgram> program, EngineOptions options = {});
  // Over a program checked elsewhere (`simit test` sections); it must outlive the engine.
  explicit Engine(const frontend::ast::Program& program, EngineOptions options = {});
  ~Engine();
  Engine(const Engine&) = delete;
  Engine& operator=(const Engine&) = delete;

  const frontend::ast::Program& program() const { return compiled_->program(); }
  const CompiledProgram& compiled() const { return *compiled_; }
  const EngineOptions& options() const { return options_; }

  // Binds a set to an extern set declaration; the set must outlive the engine's use of it.
  // Throws interp::RuntimeError naming a field or endpoint that does not fit.
  void bind_set(const frontend::ast::Variable& var, runtime::Set& set);
  // Binds an extern tensor once; the program's writes to it stay in the engine.
  void set_global(const frontend::ast::Variable& var, interp::Value value);
  const interp::Value& global(const frontend::ast::Variable& var) const;

  // Runs `func` with one value per parameter and returns its results in order.
  std::vector<interp::Value> call(const frontend::ast::FuncDecl& func,
                                  std::vector<interp::Value> args);
  // A constant expression of the program (a literal), e.g. the arguments of a `%!` test.
  interp::Value evaluate_constant(const frontend::ast::Expr& expr);

  // Time in outermost assemblies since construction or reset_stats().
  const interp::Interpreter::Stats& stats() const { return executor_->stats(); }
  void reset_stats() { executor_->reset_stats(); }
  runtime::PatternRegistry& patterns() { return executor_->patterns(); }

  // The executing interpreter, for inspection between or during runs (a debugger hook also
  // receives it with every statement).
  const interp::Interpreter& interpreter() const { return *executor_; }

  // Switches the executor between calls; bindings, values and patterns stay. Throws
  // std::runtime_error when this build has no JIT.
  void set_executor(ExecutorKind kind);
  ExecutorKind executor() const { return options_.executor.kind; }
  // `--jit-stats`: each trace's site, key, compile time, calls and time spent (nothing
  // under the interpreter).
  void print_jit_stats(std::ostream& os) const;
  // The status of each trace print_jit_stats lists ("compiled", "fused", or "interpreted: "
  // and why), for front ends that add them up over many engines (`simit test --jit-stats`).
  std::vector<std::string> jit_trace_statuses() const;

 private:
  std::unique_ptr<interp::Interpreter> make_executor() const;
  void install_jit();

  std::shared_ptr<const CompiledProgram> compiled_;
  EngineOptions options_;
  std::unique_ptr<interp::SiteHook> jit_;  // declared first: outlives the interpreter using it
  std::unique_ptr<interp::Interpreter> executor_;
};

}  // namespace simit::api
