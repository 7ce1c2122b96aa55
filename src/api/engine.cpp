// The engine: constructs the executor the options choose and forwards binding and runs to it.
#include "api/engine.h"

namespace simit::api {

namespace ast = frontend::ast;

Engine::Engine(std::shared_ptr<const CompiledProgram> program, EngineOptions options)
    : compiled_(std::move(program)), options_(options) {
  executor_ = make_executor();
}

Engine::Engine(const ast::Program& program, EngineOptions options)
    : Engine(CompiledProgram::borrow(program), options) {}

Engine::~Engine() = default;

// The one place an executor is constructed. A compiled executor plugs in here: a new
// ExecutorKind case makes the JIT's SiteHook (owned by the engine) and sets `o.sites` to it;
// the interpreter offers it each planned map and apply site and runs the site itself when
// the hook declines.
std::unique_ptr<interp::Interpreter> Engine::make_executor() const {
  interp::Options o;
  o.float32 = options_.float32;
  o.check_finite = options_.check_finite;
  o.out = options_.out;
  o.trap = options_.trap;
  o.hook = options_.hook;
  o.sites = options_.sites;
  switch (options_.executor) {
    case ExecutorKind::Interpreter: break;
  }
  return std::make_unique<interp::Interpreter>(compiled_->program(), o);
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
