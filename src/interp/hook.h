// The interpreter's single trap point: an observer called around every statement, and the
// switch that arms it. The step debugger, Ctrl-C and the JIT's hot counters hang off it; it
// costs one predictable branch per statement when nothing is armed, and nothing at all in a
// build configured with SIMIT_STATEMENT_HOOK=OFF.
#pragma once

#include <atomic>

#include "frontend/ast.h"
#include "interp/runtime_error.h"

#ifndef SIMIT_STATEMENT_HOOK
#define SIMIT_STATEMENT_HOOK 1
#endif

namespace simit::interp {

class Interpreter;

// Whether this build has the trap point (hooks and interrupts do nothing without it).
inline constexpr bool kStatementHook = SIMIT_STATEMENT_HOOK != 0;

class StatementHook {
 public:
  virtual ~StatementHook() = default;
  // `stmt` is about to run in `func`, at call depth `depth` (0 for the entry function).
  // The interpreter may be inspected (the Interpreter's inspection API, including
  // evaluate) but not re-entered. May throw (a RuntimeError stops the run cleanly).
  virtual void before_statement(const frontend::ast::Stmt& stmt,
                                const frontend::ast::FuncDecl& func, int depth,
                                const Interpreter& interpreter) = 0;
  // `stmt` has just completed (not called when it threw); the frame is still the one it ran
  // in. Compound statements (if, loops) complete after their bodies.
  virtual void after_statement(const frontend::ast::Stmt& stmt, const frontend::ast::FuncDecl& func,
                               int depth, const Interpreter& interpreter) {
    (void)stmt, (void)func, (void)depth, (void)interpreter;
  }
};

// The run stopped because an interrupt was requested (Ctrl-C), at the statement it names.
class Interrupted : public RuntimeError {
 public:
  using RuntimeError::RuntimeError;
};

// The switch the trap point reads: which hook is installed, and whether an interrupt is
// pending. A host owns one and passes it in Options::trap; it may install or remove the hook
// at any time, also from inside the hook (a debugger removes itself when nothing needs it).
// request_interrupt() is async-signal-safe: call it from a SIGINT handler.
class Trap {
 public:
  // The trap point's one test: true when a hook is installed or an interrupt is pending.
  bool armed() const { return armed_.load(std::memory_order_relaxed); }
  StatementHook* hook() const { return hook_.load(std::memory_order_relaxed); }

  // Installs `hook` (null removes it). Not for signal handlers.
  void install(StatementHook* hook) {
    hook_.store(hook, std::memory_order_relaxed);
    rearm();
  }
  // Stops the running computation at its next statement with an Interrupted error.
  void request_interrupt() {
    interrupt_.store(true, std::memory_order_relaxed);
    armed_.store(true, std::memory_order_relaxed);
  }
  bool interrupt_pending() const { return interrupt_.load(std::memory_order_relaxed); }
  // The flag request_interrupt() sets, for compiled code that cannot call back: a byte,
  // nonzero while an interrupt is pending (a compiled while loop reads it once per
  // iteration; jit/target.h).
  const std::atomic<bool>* interrupt_flag() const { return &interrupt_; }
  // Clears a pending interrupt; true when there was one.
  bool take_interrupt() {
    if (!interrupt_.exchange(false, std::memory_order_relaxed)) return false;
    rearm();
    return true;
  }

 private:
  static_assert(std::atomic<bool>::is_always_lock_free, "signal handlers need lock-free flags");
  static_assert(sizeof(std::atomic<bool>) == 1, "compiled code reads the flag as a byte");
  void rearm() {
    armed_.store(hook() != nullptr || interrupt_pending(), std::memory_order_relaxed);
    // A signal handled between the test and the store above set armed_ first; keep its request.
    if (interrupt_pending()) armed_.store(true, std::memory_order_relaxed);
  }

  std::atomic<bool> armed_{false};
  std::atomic<StatementHook*> hook_{nullptr};
  std::atomic<bool> interrupt_{false};
};

}  // namespace simit::interp
