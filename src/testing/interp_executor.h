// The engine as the executor of `simit test`: runs `%!` tests by the rules of
// TESTFORMAT.md §3.2 and graph directives by §7.3, with the executor its options choose.
#pragma once

#include "api/engine.h"
#include "executor.h"

namespace simit::tools {

class InterpExecutor : public Executor {
 public:
  // `options.out` receives what the programs print (null: it is discarded). `record_jit`:
  // keep what the JIT made of each run for take_jit_record (`--jit-stats`).
  explicit InterpExecutor(api::EngineOptions options = {}, bool record_jit = false)
      : options_(options), record_jit_(record_jit) {}

  std::string name() const override { return "interpreter"; }
  RunResult run_test(const frontend::ast::Program& program,
                     const frontend::ast::TestDecl& test) override;
  RunResult run_graph(const frontend::ast::Program& program,
                      const std::vector<GraphStep>& steps) override;
  JitRecord take_jit_record() override;

 private:
  // Adds what the JIT made of one engine's runs (also of runs stopped by an error).
  void record(const api::Engine* engine);

  api::EngineOptions options_;
  bool record_jit_ = false;
  JitRecord jit_;
};

}  // namespace simit::tools
