// Entry point of the `simit` command.
#include <exception>
#include <iostream>

#include "cli.h"
#include "frontend/diagnostics.h"

int main(int argc, char** argv) {
  // User mistakes are diagnostics with exit status 1; reaching here means simit itself is
  // wrong, which must be reported as such, never as a crash or as the user's error.
  try {
    return simit::tools::run_cli(argc, argv, std::cout, std::cerr);
  } catch (const simit::frontend::InternalError& e) {
    std::cerr << "simit: " << e.what() << "\nsimit: this is a bug in simit; please report it\n";
  } catch (const std::exception& e) {
    std::cerr << "simit: internal error: " << e.what()
              << "\nsimit: this is a bug in simit; please report it\n";
  }
  return 3;
}
