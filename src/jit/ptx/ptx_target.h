// The NVIDIA GPU target: a trace's map kernel in PTX, through the shared LLVM emission
// (jit/llvm/) with the GPU's hooks (jit/ptx/ptx_hooks.h) and LLVM's NVPTX back end. Compiling
// needs no GPU; running the kernels needs the CUDA driver and a device executor, which are
// not built yet, so a PtxKernel only carries its PTX (`--check-ptx`, `--dump=ptx`).
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "jit/loop_ir.h"
#include "jit/target.h"

namespace simit::jit::ptx {

// The GPU architecture kernels are compiled for unless told otherwise (the H200's).
inline constexpr const char* kDefaultGpuArch = "sm_90";
// The name of a map kernel's `.entry` (one per module).
inline constexpr const char* kMapEntry = "simit_map";
// A device program's step kernels: device_step_name(kStepEntry, i), each
// (int64_t* context, int64_t units) (jit/device_program.h).
inline constexpr const char* kStepEntry = "simit_step";

// A map kernel's failure word: a uint64_t in device memory, kNoFailure before the launch;
// after it, kNoFailure when no check failed, else the lowest (element, error) of the threads
// whose check failed: element in the high 32 bits, the failed check's index in Trace::errors
// in the low 32 bits.
inline constexpr uint64_t kNoFailure = ~uint64_t{0};
inline int32_t failed_element(uint64_t word) { return static_cast<int32_t>(word >> 32); }
inline int32_t failed_check(uint64_t word) { return static_cast<int32_t>(word & 0xffffffffu); }

// A kernel compiled for the GPU: its PTX text and the name of its entry. It cannot run here
// (run() throws std::logic_error): the device executor will load it through the driver.
class PtxKernel : public Kernel {
 public:
  std::string ptx;
  std::string entry;                 // a map kernel's
  std::vector<std::string> entries;  // a device program's, one per step
  int32_t run(const MapArgs& args, ElementRange range, int32_t* failed_element) const override;
  int32_t run(const SystemArgs& args) const override;
};

// Why a trace is not compiled for the GPU, or "" when it is: a trace that calls the runtime
// (a decomposition); a system trace not lowered as a device program, or one whose passes
// cannot run apart (device_refusal).
std::string gpu_refusal(const Trace& t);
std::string gpu_refusal(const SystemTrace& t);

// The target for `gpu_arch` (e.g. "sm_90"): compile() gives a PtxKernel, or null with the
// error (gpu_refusal's reason, or LLVM's). Null with `error` when this LLVM has no NVPTX back
// end or does not know the architecture.
std::unique_ptr<Target> make_ptx_target(const std::string& gpu_arch, std::string& error);

}  // namespace simit::jit::ptx
