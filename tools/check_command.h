// `simit check`: parse and type-check programs, print diagnostics and optional tree dumps.
#pragma once

#include <ostream>
#include <string>
#include <vector>

namespace simit::tools {

struct CheckOptions {
  std::vector<std::string> files;
  std::vector<std::string> dumps;  // "ast" and/or "typed", printed to `out` in that order
};

// Checks every file; diagnostics go to `err`. Returns 0 when all are clean, else 1.
int run_check(const CheckOptions& options, std::ostream& out, std::ostream& err);

}  // namespace simit::tools
