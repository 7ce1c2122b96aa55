// The seam through which an executor (the interpreter, a JIT) runs what `simit test` found.
#pragma once

#include <string>
#include <vector>

#include "directives.h"
#include "frontend/ast.h"

namespace simit::tools {

// The outcome of running a `%!` test or a section's graph directives.
struct RunResult {
  enum class Status {
    Passed,
    Failed,        // ran to the end, but an expectation did not hold
    RuntimeError,  // the program stopped with a run-time error (`%@ error runtime`)
    Skipped,       // the executor cannot run this yet; `message` says why
  };
  Status status = Status::Passed;
  std::string message;  // why it did not pass
  int line = 0;         // RuntimeError: the file line it was reported at (0: unknown)

  bool passed() const { return status == Status::Passed; }
};

// What the JIT made of an executor's runs (`simit test --jit-stats`).
struct JitRecord {
  std::string tables;                 // Engine::print_jit_stats of each run that made a trace
  std::vector<std::string> statuses;  // each trace's: "compiled", "fused", "interpreted: ..."
};

// Runs checked programs. The runner holds at most one; without one, sections that have
// something to run are reported as skipped.
class Executor {
 public:
  virtual ~Executor() = default;
  // A short name for reports ("interpreter", "cpu-jit").
  virtual std::string name() const = 0;
  // Runs one inline test of a checked program (TESTFORMAT.md §3.2); each call is independent.
  virtual RunResult run_test(const frontend::ast::Program& program,
                             const frontend::ast::TestDecl& test) = 0;
  // Builds the sets, runs and checks the expectations of a section's graph directives, in
  // order (TESTFORMAT.md §7.3).
  virtual RunResult run_graph(const frontend::ast::Program& program,
                              const std::vector<GraphStep>& steps) = 0;
  // What the JIT made of the runs since the last call, if the executor records it; forgotten
  // here, so that each section reports its own.
  virtual JitRecord take_jit_record() { return {}; }
};

}  // namespace simit::tools
