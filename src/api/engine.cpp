// The engine: constructs the executor the options choose and forwards binding and runs to it.
#include "api/engine.h"

#include <cstdlib>
#include <stdexcept>

#ifdef SIMIT_HAS_JIT
#include "jit/controller.h"
#endif

namespace simit::api {

std::string jit_cache_folder(const std::string& setting) {
  if (setting == "off") return "";
  if (!setting.empty()) return setting;
  if (const char* xdg = std::getenv("XDG_CACHE_HOME"); xdg && *xdg)
    return std::string(xdg) + "/simit/kernels";
  if (const char* home = std::getenv("HOME"); home && *home)
    return std::string(home) + "/.cache/simit/kernels";
  return "";
}

namespace ast = frontend::ast;

Engine::Engine(std::shared_ptr<const CompiledProgram> program, EngineOptions options)
    : compiled_(std::move(program)), options_(options) {
  if (std::string bad = executor_unavailable(options_.executor); !bad.empty())
    throw std::runtime_error(bad);
  executor_ = make_executor();
  if (compiles(options_.executor.kind)) install_jit();
}

Engine::Engine(const ast::Program& program, EngineOptions options)
    : Engine(CompiledProgram::borrow(program), options) {}

Engine::~Engine() = default;

// The one place an executor is constructed. The JIT is the interpreter's site hook (owned by
// the engine): the interpreter offers it each planned map and apply site and runs the site
// itself when the hook declines.
std::unique_ptr<interp::Interpreter> Engine::make_executor() const {
  interp::Options o;
  o.float32 = options_.float32;
  o.check_finite = options_.check_finite;
  o.out = options_.out;
  o.trap = options_.trap;
  o.hook = options_.hook;
  o.sites = options_.sites;
  o.distribution = options_.distribution;
  o.host_uses_accessors = options_.host_uses_accessors;
  return std::make_unique<interp::Interpreter>(compiled_->program(), o);
}

void Engine::install_jit() {
#ifdef SIMIT_HAS_JIT
  // The choice mapped onto the JIT's own options; what the choice leaves open (threshold -1)
  // keeps the JIT's default.
  const ExecutorChoice& x = options_.executor;
  jit::JitOptions j;
  if (x.threshold >= 0) j.threshold = x.threshold;
  j.eager = x.eager;
  j.cache_dir = jit_cache_folder(x.jit_cache);
  j.float32 = options_.float32;
  j.check_finite = options_.check_finite;
  j.dump = options_.dump;
  j.dump_loop_ir = x.dump_loop_ir;
  j.dump_llvm = x.dump_llvm;
  j.dump_passes = x.dump_passes;
  j.check = x.check;
  j.check_ptx = x.check_ptx;
  j.dump_ptx = x.dump_ptx;
  j.corrupt_for_test = options_.corrupt_for_test;
  j.shuffle_seed = options_.shuffle_seed_for_test;
  j.threads = x.threads;
  j.gpu = x.kind == ExecutorKind::Gpu;
  j.gpu_arch = x.gpu_arch;
  j.gpu_emulated = j.gpu && gpu_emulated_for_test();
  // The tests run the corpus and the random programs, whose sets are small, on threads in
  // chunks of a few elements.
  if (const char* chunk = std::getenv("SIMIT_TEST_THREAD_CHUNK"))
    j.min_chunk_for_test = std::atoi(chunk);
  // The corpus and the examples reach the shuffled executor through `simit` itself.
  if (const char* seed = std::getenv("SIMIT_TEST_SHUFFLE_SEED"); seed && !j.shuffle_seed)
    j.shuffle_seed = std::strtoull(seed, nullptr, 10);
  jit_ = std::make_unique<jit::TraceController>(j);
  executor_->set_site_hook(jit_.get());
#else
  throw std::runtime_error(executor_unavailable(ExecutorChoice{.kind = ExecutorKind::Jit}));
#endif
}

void Engine::set_executor(ExecutorKind kind) {
  if (kind == options_.executor.kind) return;
  if (compiles(kind)) {
    // install_jit reads the kind (gpu or jit); it throws, changing nothing, when the build
    // or the machine cannot run it.
    const ExecutorKind before = options_.executor.kind;
    options_.executor.kind = kind;
    try {
      if (std::string why = executor_unavailable(options_.executor); !why.empty())
        throw std::runtime_error(why);
      install_jit();
    } catch (...) {
      options_.executor.kind = before;
      throw;
    }
    return;
  }
  options_.executor.kind = kind;
  executor_->set_site_hook(options_.sites);
  jit_.reset();
}

void Engine::print_jit_stats(std::ostream& os) const {
#ifdef SIMIT_HAS_JIT
  if (auto* c = dynamic_cast<const jit::TraceController*>(jit_.get())) c->print_stats(os);
#else
  (void)os;
#endif
}

std::vector<std::string> Engine::jit_trace_statuses() const {
  std::vector<std::string> out;
#ifdef SIMIT_HAS_JIT
  if (auto* c = dynamic_cast<const jit::TraceController*>(jit_.get()))
    for (const jit::TraceStats& s : c->stats()) out.push_back(s.status);
#endif
  return out;
}

void Engine::bind_set(const ast::Variable& var, runtime::Set& set) {
  executor_->bind_set(var, set);
}

void Engine::set_global(const ast::Variable& var, interp::Value value) {
  executor_->set_global(var, std::move(value));
}

const interp::Value& Engine::global(const ast::Variable& var) const {
  return executor_->global(var);
}

std::vector<interp::Value> Engine::call(const ast::FuncDecl& func,
                                        std::vector<interp::Value> args) {
  return executor_->call(func, std::move(args));
}

interp::Value Engine::evaluate_constant(const ast::Expr& expr) {
  return executor_->evaluate_constant(expr);
}

}  // namespace simit::api
