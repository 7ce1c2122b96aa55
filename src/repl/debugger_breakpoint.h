// The step debugger's breakpoints, watchpoints and NaN trap (one numbering, as in gdb).
#pragma once

#include <memory>
#include <optional>
#include <string>

#include "debugger.h"
#include "frontend/debug_expr.h"
#include "runtime/set.h"

namespace simit::repl {

struct Debugger::Breakpoint {
  enum class Kind { Line, Function, Watch, Nan };
  Kind kind = Kind::Line;
  int number = 0;
  bool temporary = false;  // tbreak: deleted when it stops the run
  int line = 0;            // Line: the compiled line asked for
  std::string func_name;   // Function
  std::string condition;   // the text after `if`; empty for none
  int hits = 0;
  // Stop only on some hits (DAP's hitCondition): hits == n ('='), >= n, > n, every n-th ('%').
  char hit_op = 0;  // 0: every hit
  int hit_n = 0;
  bool hit_allows() const {
    switch (hit_op) {
      case '=': return hits == hit_n;
      case 'g': return hits >= hit_n;
      case '>': return hits > hit_n;
      case '%': return hit_n > 0 && hits % hit_n == 0;
      default: return true;
    }
  }

  // Resolved against the running program (against the set program outside runs). The
  // pointers are cleared when a run ends (its program may go with it); `resolved_at`
  // ("FUNC at FILE:LINE", from the last resolution) is what `info breakpoints` shows.
  std::string resolved_at;
  const frontend::ast::Stmt* stmt = nullptr;
  const frontend::ast::FuncDecl* func = nullptr;
  std::shared_ptr<frontend::DebugExpression> cond;

  // Watch: SET.FIELD[index], resolved to the bound set when a run starts.
  std::string set_name, field_name;
  int index = 0;
  const runtime::Set* set = nullptr;
  int field = -1;
  std::optional<runtime::Tensor> last;  // the value seen last

  // Nan: off once it has stopped a run (what follows a NaN is mostly NaN), on at each run.
  bool armed = true;
};

}  // namespace simit::repl
