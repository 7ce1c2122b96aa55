// The interpreter's single trap point: an observer called before every statement executes.
// The step debugger and the JIT's hot counters hang off it; it costs one predictable
// branch per statement when no hook is installed.
#pragma once

#include "frontend/ast.h"

namespace simit::interp {

class Interpreter;

class StatementHook {
 public:
  virtual ~StatementHook() = default;
  // `stmt` is about to run in `func`, at call depth `depth` (0 for the entry function).
  // The interpreter may be inspected (Interpreter::local) but not re-entered.
  virtual void before_statement(const frontend::ast::Stmt& stmt,
                                const frontend::ast::FuncDecl& func, int depth,
                                const Interpreter& interpreter) = 0;
};

}  // namespace simit::interp
