// gpu_probe: the CUDA driver's version and the GPU's properties, then what launching kernels
// and copying memory cost there, as Markdown (src/jit/ptx/gpu_probe.h; run by
// scripts/gpu_check.sh). Exits 77 with the reason where there is no driver or no GPU.
#include <iostream>
#include <string>
#include <vector>

#include "jit/ptx/gpu_probe.h"

int main(int argc, char** argv) {
  const std::vector<std::string> args(argv + 1, argv + argc);
  return simit::jit::cuda::run_probe(args, std::cout, std::cerr);
}
