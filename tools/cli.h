// The `simit` command line: subcommands and their options.
#pragma once

#include <ostream>

namespace simit::tools {

// Parses the arguments and runs a subcommand. Returns the process exit status: the
// subcommand's, 0 for --help and --version, 2 for a usage error.
int run_cli(int argc, const char* const* argv, std::ostream& out, std::ostream& err);

}  // namespace simit::tools
