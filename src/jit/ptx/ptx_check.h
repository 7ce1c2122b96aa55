// `--check-ptx` and `--dump=ptx`: each trace the JIT compiles for the CPU is compiled for the
// GPU as well (jit/ptx/ptx_target.h) and its PTX printed and/or assembled by ptxas, the CUDA
// toolkit's assembler, which needs no GPU. The process keeps one tally of what was assembled
// and what was not compiled for the GPU (and why), which the command line prints at the end.
#pragma once

#include <ostream>
#include <string>

#include "jit/loop_ir.h"

namespace simit::jit::ptx {

// The ptxas to run: $SIMIT_PTXAS when set, else `ptxas` on PATH, else
// /usr/local/cuda/bin/ptxas. "" with `why` when there is none (or $SIMIT_PTXAS is not an
// executable file).
std::string find_ptxas(std::string& why);

// Assembles `ptx` with `ptxas --gpu-name ARCH -c` into relocatable code (its calls of the
// project's math functions stay external). True when ptxas accepts it; otherwise false with
// `message`: what ptxas printed, or why it could not be run.
bool assemble(const std::string& ptxas, const std::string& ptx, const std::string& gpu_arch,
              std::string& message);

struct CheckOptions {
  bool assemble = false;         // --check-ptx: assemble the PTX with ptxas
  std::ostream* dump = nullptr;  // --dump=ptx: print the PTX (or why there is none) here
  std::string gpu_arch;          // empty: kDefaultGpuArch
};

// Compiles the trace of `site` (as --jit-stats names it) for the GPU, prints and assembles its
// PTX as `o` says, and counts it in the tally. "" or the message the run stops with: ptxas
// rejected the PTX, ptxas is missing, or LLVM failed to compile a trace the GPU target takes.
std::string check_trace(const Trace& t, const std::string& site, const CheckOptions& o);
std::string check_trace(const SystemTrace& t, const std::string& site, const CheckOptions& o);

// "check-ptx: N traces assembled by ptxas, M not compiled for the GPU (K: reason; ...)", and
// ", R rejected by ptxas" when ptxas rejected any.
std::string tally_summary();
// Zeroes the tally (for tests that run several programs in one process).
void reset_tally();

}  // namespace simit::jit::ptx
