// Entry point of the `simit` command.
#include <malloc.h>

#include <iostream>

#include "cli.h"
#include "simit/commands.h"

int main(int argc, char** argv) {
#ifdef M_MMAP_THRESHOLD
  // A frame allocates and frees vectors and matrices of megabytes (a matrix expression's
  // result, a CG temporary). By default glibc maps each from the kernel and returns it on
  // free, so every frame pays page faults on fresh pages; kept in the heap, they are reused.
  mallopt(M_MMAP_THRESHOLD, 32 << 20);
  mallopt(M_TRIM_THRESHOLD, 256 << 20);
#endif
  return simit::tools::run_guarded(
      [&] { return simit::tools::run_cli(argc, argv, std::cout, std::cerr); }, std::cerr);
}
