// The project's math functions for the GPU: their device bitcode (src/jit/ptx/device_math.cmake,
// compiled by clang from the same sources as the host's, no contraction), linked into a PTX
// module so that it defines the `simit_math_*` functions its kernels call.
#pragma once

#include <string>

namespace llvm {
class Module;
}

namespace simit::jit::ptx {

// Whether this build carries the device bitcode (clang and llvm-link were found).
bool device_math_available();

// Links the math functions `m` calls (only those) into `m`, with `m`'s triple and data layout,
// internal to the module so that the optimiser inlines or drops them. Without the bitcode it
// does nothing: the calls stay external. False with `error` when the bitcode cannot be read or
// linked.
bool link_device_math(llvm::Module& m, std::string& error);

// The device bitcode compiled for this CPU instead (its own LLJIT, made once, no fma): the
// address of `name` (simit_math_exp, ...), a `double(double)` or, for pow and atan2,
// `double(double, double)`; null with `error` without the bitcode or the function. This is how
// the tests show that the device compile (clang, the std shim) computes the host's bits.
void* device_math_on_host(const std::string& name, std::string& error);

}  // namespace simit::jit::ptx
