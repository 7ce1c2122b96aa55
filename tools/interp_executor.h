// The reference interpreter as the executor of `simit test`: runs `%!` tests by the rules
// of TESTFORMAT.md §3.2. Graph directives need sets, which come later; they are skipped.
#pragma once

#include "executor.h"
#include "interp/options.h"

namespace simit::tools {

class InterpExecutor : public Executor {
 public:
  // `options.out` receives what the programs print (null: it is discarded).
  explicit InterpExecutor(interp::Options options = {}) : options_(options) {}

  std::string name() const override { return "interpreter"; }
  RunResult run_test(const frontend::ast::Program& program,
                     const frontend::ast::TestDecl& test) override;
  RunResult run_graph(const frontend::ast::Program& program,
                      const std::vector<GraphStep>& steps) override;

 private:
  interp::Options options_;
};

}  // namespace simit::tools
