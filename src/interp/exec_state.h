// What a site hook (the JIT) sees of the executing interpreter: the running function's
// variables and the globals, the matrix patterns, the trap point, and a way to run a
// statement interpreted. The interpreter implements it; a hook depends on this, not on the
// interpreter's class.
#pragma once

#include "frontend/ast.h"
#include "interp/hook.h"
#include "interp/value.h"
#include "runtime/system_matrix.h"

namespace simit::interp {

class ExecState {
 public:
  // The storage of a variable of the running function (or a global): reads and writes go
  // straight to the interpreter's own values.
  virtual Value& variable(const frontend::ast::Variable& var) = 0;
  virtual const Value& global(const frontend::ast::Variable& var) const = 0;
  // A checked expression evaluated in frame `level` (0: the running function), running no
  // statement and writing nothing.
  virtual Value evaluate(const frontend::ast::Expr& expr, int level) const = 0;
  // Runs a statement of the running function without offering it to the site hook.
  virtual void exec_interpreted(const frontend::ast::Stmt& s) = 0;
  // The patterns the program's assemblies share (by edge set, row and column sets).
  virtual runtime::PatternRegistry& patterns() = 0;
  virtual const frontend::ast::Program& program() const = 0;
  // The trap point's switch: a pending interrupt (Ctrl-C) is looked at between chunks.
  virtual Trap& trap() const = 0;

 protected:
  ~ExecState() = default;
};

}  // namespace simit::interp
