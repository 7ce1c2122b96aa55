// The GPU probe (bench/gpu_probe): through the CUDA driver layer (cuda_driver.h), what the
// driver and the GPU are, then what launching a kernel and copying memory cost there, printed
// as Markdown tables. scripts/gpu_check.sh runs it first on a GPU machine. Without a driver or
// a device it prints why and returns kProbeNoGpu (77, the "skipped" status of test drivers).
#pragma once

#include <ostream>
#include <string>
#include <vector>

#include "jit/ptx/cuda_driver.h"

namespace simit::jit::cuda {

inline constexpr int kProbeOk = 0;
inline constexpr int kProbeFailed = 1;  // a driver call failed, or a kernel computed wrong
inline constexpr int kProbeUsage = 2;
inline constexpr int kProbeNoGpu = 77;

struct ProbeOptions {
  std::string driver = "libcuda.so.1";  // the library dlopen'd for the driver
  int device = 0;
  int launches = 2000;       // empty kernels timed one by one, and per back-to-back batch
  int graph_kernels = 1000;  // empty kernels in the graph
  int copy_mib = 256;        // each copy's and the fill kernel's buffer
  int reps = 7;              // timed repetitions of each batch, graph launch and copy
};

// The probe's kernels, PTX text written by hand (no toolkit needed to build the probe):
// simit_probe_empty() does nothing; simit_probe_fill(u32* out, u32 value, u32 n) writes
// value + i into out[i] for every i < n, one element per thread.
const std::string& probe_ptx();

// The probe as its command line runs it: `args` without the program's name. Prints the
// tables on `out`, progress and errors on `err`; returns the exit status (kProbe*). `get`,
// when not null, stands for the driver library's cuGetProcAddress (tests pass a fake one).
int run_probe(const std::vector<std::string>& args, std::ostream& out, std::ostream& err,
              const GetProcAddress* get = nullptr);

}  // namespace simit::jit::cuda
