// `simit test` as the command line runs it: the test runner with the engine as executor.
#include "interp_executor.h"
#include "simit/testing.h"
#include "test_runner.h"

namespace simit::tools {

int run_test_command(const std::vector<std::string>& paths, const TestCommandOptions& options,
                     std::ostream& out, std::ostream& err) {
  api::EngineOptions engine;
  engine.float32 = options.float32;
  engine.check_finite = options.check_finite;
  if (std::string bad = executor_unavailable(options.executor); !bad.empty()) {
    err << "simit test: " << bad << "\n";
    return 2;
  }
  // With check, every section's runs are checked against the interpreter: a difference fails
  // the section.
  engine.executor = options.executor;
  InterpExecutor executor(engine, options.jit_stats);
  TestOptions run;
  run.verbose = options.verbose;
  run.executor = &executor;
  run.jit_stats = options.jit_stats;
  return run_tests(paths, run, out, err);
}

}  // namespace simit::tools
