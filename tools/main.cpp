// Entry point of the `simit` command.
#include <iostream>

#include "cli.h"

int main(int argc, char** argv) { return simit::tools::run_cli(argc, argv, std::cout, std::cerr); }
