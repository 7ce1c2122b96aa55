// The engine as the executor of `simit test`: runs `%!` tests by the rules of
// TESTFORMAT.md §3.2 and graph directives by §7.3, with the executor its options choose.
#pragma once

#include "executor.h"
#include "api/engine.h"

namespace simit::tools {

class InterpExecutor : public Executor {
 public:
  // `options.out` receives what the programs print (null: it is discarded).
  explicit InterpExecutor(api::EngineOptions options = {}) : options_(options) {}

  std::string name() const override { return "interpreter"; }
  RunResult run_test(const frontend::ast::Program& program,
                     const frontend::ast::TestDecl& test) override;
  RunResult run_graph(const frontend::ast::Program& program,
                      const std::vector<GraphStep>& steps) override;

 private:
  api::EngineOptions options_;
};

}  // namespace simit::tools
