// `simit test`: runs test files in the inline test format (TESTFORMAT.md) through the
// reference interpreter and reports each section.
#pragma once

#include <ostream>
#include <string>
#include <vector>

#include "simit/executor.h"

namespace simit::tools {

struct TestCommandOptions {
  bool verbose = false;       // list every section, not only failures
  bool float32 = false;       // run programs with 32-bit floats
  bool check_finite = false;  // stop a run at the first NaN or infinity
  // What runs the sections. No kernel cache unless one is asked for (`--jit-cache DIR`): a
  // test run writes nothing into the user's cache folder.
  ExecutorChoice executor = ExecutorChoice{.jit_cache = "off"};
  // jit: the traces of each section listed (failures; all with `verbose`) and a summary
  bool jit_stats = false;
};

// Runs every test file under `paths` (folders are searched for *.sim), prints failures (every
// section with `verbose`) and the summary line `N passed, N failed[, N skipped]` to `out`;
// returns 0, or 1 when anything failed.
int run_test_command(const std::vector<std::string>& paths, const TestCommandOptions& options,
                     std::ostream& out, std::ostream& err);

}  // namespace simit::tools
