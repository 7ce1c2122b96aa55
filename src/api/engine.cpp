// The engine: constructs the executor the options choose and forwards binding and runs to it.
#include "api/engine.h"

#include <stdexcept>

#ifdef SIMIT_HAS_JIT
#include "jit/controller.h"
#endif

namespace simit::api {

const char* executor_name(ExecutorKind k) { return k == ExecutorKind::Jit ? "jit" : "interpreter"; }

bool executor_from_name(const std::string& name, ExecutorKind& kind) {
  if (name == "interpreter") kind = ExecutorKind::Interpreter;
  else if (name == "jit") kind = ExecutorKind::Jit;
  else return false;
  return true;
}

std::string configure_backend(EngineOptions& o, const std::string& backend, long threshold,
                              const std::vector<std::string>& dump, std::ostream* dump_to) {
  if (!executor_from_name(backend, o.executor))
    return "unknown backend '" + backend + "' (interpreter or jit)";
  if (o.executor == ExecutorKind::Jit && !jit_available())
    return "this build has no JIT: configure with -DSIMIT_WITH_LLVM=ON (LLVM 19)";
  o.jit.threshold = threshold;
  for (const std::string& d : dump) {
    if (d == "loop-ir") o.jit.dump_loop_ir = true;
    else if (d == "llvm") o.jit.dump_llvm = true;
    else return "unknown dump '" + d + "' (loop-ir, llvm)";
  }
  if (!dump.empty()) o.jit.dump = dump_to;
  return "";
}

bool jit_available() {
#ifdef SIMIT_HAS_JIT
  return true;
#else
  return false;
#endif
}

namespace ast = frontend::ast;

Engine::Engine(std::shared_ptr<const CompiledProgram> program, EngineOptions options)
    : compiled_(std::move(program)), options_(options) {
  executor_ = make_executor();
  if (options_.executor == ExecutorKind::Jit) install_jit();
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
  return std::make_unique<interp::Interpreter>(compiled_->program(), o);
}

void Engine::install_jit() {
#ifdef SIMIT_HAS_JIT
  jit::JitOptions j;
  if (options_.jit.threshold >= 0) j.threshold = options_.jit.threshold;
  j.float32 = options_.float32;
  j.check_finite = options_.check_finite;
  j.dump = options_.jit.dump;
  j.dump_loop_ir = options_.jit.dump_loop_ir;
  j.dump_llvm = options_.jit.dump_llvm;
  j.check = options_.jit.check;
  j.corrupt_for_test = options_.jit.corrupt_for_test;
  jit_ = std::make_unique<jit::TraceController>(j);
  executor_->set_site_hook(jit_.get());
#else
  throw std::runtime_error("this build has no JIT: configure with -DSIMIT_WITH_LLVM=ON (LLVM 19)");
#endif
}

void Engine::set_executor(ExecutorKind kind) {
  if (kind == options_.executor) return;
  if (kind == ExecutorKind::Jit) {
    install_jit();  // throws, changing nothing, without a JIT
    options_.executor = kind;
    return;
  }
  options_.executor = kind;
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

void Engine::bind_set(const ast::Variable& var, runtime::Set& set) { executor_->bind_set(var, set); }

void Engine::set_global(const ast::Variable& var, interp::Value value) {
  executor_->set_global(var, std::move(value));
}

const interp::Value& Engine::global(const ast::Variable& var) const { return executor_->global(var); }

std::vector<interp::Value> Engine::call(const ast::FuncDecl& func, std::vector<interp::Value> args) {
  return executor_->call(func, std::move(args));
}

interp::Value Engine::evaluate_constant(const ast::Expr& expr) {
  return executor_->evaluate_constant(expr);
}

}  // namespace simit::api
