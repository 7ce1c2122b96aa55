// `simit test`: runs test files in the inline test format (TESTFORMAT.md) through the
// reference interpreter and reports each section.
#pragma once

#include <ostream>
#include <string>
#include <vector>

namespace simit::tools {

struct TestCommandOptions {
  bool verbose = false;                 // list every section, not only failures
  bool float32 = false;                 // run programs with 32-bit floats
  bool check_finite = false;            // stop a run at the first NaN or infinity
  std::string backend = "interpreter";  // or "jit": sections' runs through the JIT
  long jit_threshold = -1;              // jit: executions before a site is compiled
  bool check_jit = false;               // jit: each compiled call also run interpreted and compared
  // jit: the traces of each section listed (failures; all with `verbose`) and a summary
  bool jit_stats = false;
};

// Runs every test file under `paths` (folders are searched for *.sim), prints failures (every
// section with `verbose`) and the summary line `N passed, N failed[, N skipped]` to `out`;
// returns 0, or 1 when anything failed.
int run_test_command(const std::vector<std::string>& paths, const TestCommandOptions& options,
                     std::ostream& out, std::ostream& err);

}  // namespace simit::tools
