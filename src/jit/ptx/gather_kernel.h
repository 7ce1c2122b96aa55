// The gather kernel: a deferred assembly's deferred blocks added to their blocks in device
// memory (DeferredPlan::finish's additions, jit/deferred_plan.h), one thread per block that
// has deferred blocks, as PTX text; and the same computation on the host, which the emulated
// GPU executor runs over its "device" memory in place of the launch.
#pragma once

#include <cstdint>
#include <string>

namespace simit::jit::ptx {

// The name of the gather kernel's `.entry`.
inline constexpr const char* kGatherEntry = "simit_gather";
// The PTX ISA version the module declares unless told otherwise: the lowest that knows sm_90
// (what LLVM's NVPTX back end writes for the map kernels of sm_90).
inline constexpr const char* kDefaultPtxVersion = "7.8";

// The kernel's parameters, in order (device addresses, or host ones for gather_on_host):
// thread i adds, for each component c < components, deferred[k[j] * components + c] into
// values[block[i] * components + c] for j = start[i], ..., start[i + 1] - 1 in turn;
// threads i >= blocks do nothing.
struct GatherArgs {
  double* values = nullptr;
  const double* deferred = nullptr;
  const int32_t* block = nullptr;
  const int32_t* start = nullptr;
  const int32_t* k = nullptr;
  uint32_t blocks = 0;
  uint32_t components = 1;
  uint32_t round32 = 0;  // non-zero (--float32): each addition's sum rounded to binary32
};

// The gather kernel's module: `.version version`, `.target arch` (e.g. "sm_90"). Empty
// arguments take the defaults (kDefaultPtxVersion, ptx::kDefaultGpuArch).
std::string gather_ptx(const std::string& arch = "", const std::string& version = "");

// A module of hand-written PTX (the gather kernel's, the fused-sum kernel's): a comment
// naming `what`, the directives for `arch` and `version` (defaults as above), then `body`.
std::string hand_written_module(const std::string& what, const std::string& arch,
                                const std::string& version, const char* body);

// Threads [first, end) of the gather kernel over `a`, on the calling thread.
void gather_on_host(const GatherArgs& a, uint32_t first, uint32_t end);

// The operand of a PTX module's `directive` line (".version", ".target"), e.g. "sm_90", or ""
// when the text has none: the gather module is written for the map kernels' architecture.
std::string ptx_directive(const std::string& ptx, const std::string& directive);

}  // namespace simit::jit::ptx
