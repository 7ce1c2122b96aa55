// The executor seam: a map or apply site planned once and run many times, and the hook
// through which a compiled executor may take a planned site over from the interpreter.
//
// How a site runs (Interpreter::run_assembly):
//   1. The first time a site (`map f to S` or `apply f to S`) runs on a target set with a
//      given topology, the interpreter plans it: the mapped function, `reduce`, each
//      result's kind (system vector or matrix), block shape and matrix pattern (with the
//      pattern's per-element table of block positions, runtime::AssemblyIndex). The plan
//      is kept per site and rebuilt only when the target's topology changes.
//   2. Before running the site element by element, the interpreter offers it to the
//      SiteHook installed in Options::sites (if any). A compiled executor that has a kernel
//      for this plan runs it, writes the results into the zeroed result values it is handed
//      (field arrays and matrix values are the runtime's own, so nothing is copied), and
//      returns true; returning false leaves the site to the interpreter.
//   3. Statements the frontend marked system-level (frontend/system_statements.h: vector
//      updates, `A * p`, a whole CG loop) are offered too: each maximal run of consecutive
//      ones in a block (with the scalar assignments among them) through run_statements (a
//      CG function's set-up, loop and residual as one), then each statement the run's
//      executor did not take through run_statement; the executor reads and writes the
//      running function's variables through Interpreter::variable.
//   4. While the debugger's trap point is armed (a breakpoint, a watch, stepping, Ctrl-C),
//      nothing is offered: every statement must run interpreted so that it can stop.
#pragma once

#include <cstdint>
#include <deque>
#include <memory>
#include <vector>

#include "frontend/ast.h"
#include "interp/value.h"
#include "runtime/system_matrix.h"

namespace simit::interp {

struct AssemblyPlan {
  struct Result {
    bool is_matrix = false;       // a system matrix (else a system vector or scalar)
    Shape block;                  // one block's shape (scalar for unblocked results)
    runtime::PatternPtr pattern;  // matrices over edge sets: shared by all their matrices
    // The matrix this site produced last: reused (zeroed) when nothing else holds it.
    std::shared_ptr<runtime::SystemMatrix> last;
    // Set by a site hook that fills this matrix on a pattern of its own (the JIT's specialised
    // pattern): when the site is offered, the interpreter leaves the result null, and makes
    // it (zero, on `pattern`) only if the hook declines.
    bool hook_allocates = false;
  };
  const frontend::ast::Assembly* site = nullptr;
  const frontend::ast::FuncDecl* func = nullptr;
  const runtime::Set* target = nullptr;
  uint64_t topology = 0;  // the target's topology version the plan was made for
  bool reduce = false;
  bool grid = false;  // a stencil map through a grid (its matrices are built afterwards)
  std::vector<Result> results;
  long runs = 0;  // how many times the site ran (a compiled executor's hot counter)
};

class Interpreter;
class ExecState;

// What a compiled executor is handed for one execution of a planned site.
struct SiteCall {
  AssemblyPlan& plan;
  const std::vector<Value>& partial_args;  // the values of `map f(a, b) to S`'s a, b
  std::deque<Value>& results;              // zeroed results to accumulate into
  runtime::Set& target;                    // plan.target, writable (apply writes its fields)
  const ExecState& interpreter;            // globals, the trap (Ctrl-C)
  const frontend::SourceSpan& at;          // the map expression or apply statement
  // Set by a hook that ran the site when every value of its results is a binary32 value
  // already (--float32: a compiled reduction rounds each addition), so that the map's final
  // rounding, a pass over every value, is left out.
  bool results_binary32 = false;
};

class SiteHook {
 public:
  virtual ~SiteHook() = default;
  // Runs the site and returns true, or returns false to let the interpreter run it. May
  // throw a RuntimeError (located at the site or at the failing statement).
  virtual bool run_site(SiteCall& call) = 0;
  // Runs a system-level statement (Stmt::system_level) and returns true, or returns false
  // to let the interpreter run it.
  virtual bool run_statement(const frontend::ast::Stmt& stmt, ExecState& in) {
    (void)stmt, (void)in;
    return false;
  }
  // Runs statements block[first, first + count), or a prefix of them, and returns how many
  // it ran. The interpreter offers each maximal run of two or more consecutive statements
  // that are system-level or assign scalars (Stmt::scalar_level), at least one of them
  // system-level; when the hook returns 0 it runs block[first] and offers the rest of the
  // run (while it is still one), and the statements it runs are offered one by one.
  virtual size_t run_statements(const frontend::ast::Block& block, size_t first, size_t count,
                                ExecState& in) {
    (void)block, (void)first, (void)count, (void)in;
    return 0;
  }
  // The interpreter ran a site (or a statement) that run_site (run_statement) declined: a
  // differential check compares its results with what the compiled code computed.
  virtual void site_done(SiteCall& call) { (void)call; }
  virtual void statement_done(const frontend::ast::Stmt& stmt, ExecState& in) {
    (void)stmt, (void)in;
  }
  // A call returns to its host, which is about to get every array an executor holds newer
  // back (runtime/residency.h): the matrices the hook keeps only to reuse their storage
  // (zeroed before any reuse) are dropped there instead.
  virtual void drop_reusable() {}
};

}  // namespace simit::interp
