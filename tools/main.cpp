// Entry point of the `simit` command.
#include <iostream>

#include "cli.h"
#include "simit/commands.h"

int main(int argc, char** argv) {
  return simit::tools::run_guarded(
      [&] { return simit::tools::run_cli(argc, argv, std::cout, std::cerr); }, std::cerr);
}
