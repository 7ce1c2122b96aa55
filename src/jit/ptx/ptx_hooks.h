// The NVIDIA GPU's choices in LLVM emission (jit/llvm/target_hooks.h): the map kernel is a
// `ptx_kernel` entry that visits one element per thread, calls the project's math functions
// by their C names (external: their device versions are not built yet), adds into the
// results with plain loads and stores, and reports a failure through a device word.
#pragma once

#include <string>

#include "jit/llvm/emitter.h"
#include "jit/llvm/target_hooks.h"

namespace simit::jit::ptx {

// A map kernel is
//   ptx_kernel void fn(void* const* arrays, const double* scalars, const int32_t* endpoints,
//                      int32_t begin, int32_t end, uint64_t* failure)
// (jit/ptx/ptx_target.h: the failure word's encoding). Thread t of the grid visits element
// begin + t when it lies below end.
// The math functions are TargetHooks' calls by C name, defined by their device bitcode (the
// same sources compiled for the GPU, linked into the module: jit/ptx/device_math.h; a build
// without it leaves them external and its PTX relocatable). Assembly is TargetHooks' plain
// load, add and store, which races where a GPU's elements share a block: the arithmetic
// contract forbids floating-point atomics (their order, and so the sum's bits, change from
// run to run), and what will make it correct is the deferred assembly still to be built
// (contributions into a scratch array, then one thread per block summing them in element
// order). Until then these kernels are only compiled and assembled (`--check-ptx`).
class PtxHooks : public codegen::TargetHooks {
 public:
  codegen::MapEntry map_kernel(llvm::Module& m, const std::string& name) override;
  void elements(codegen::MapEmitter& k, const codegen::MapEntry& entry) override;
  void fail(llvm::IRBuilder<>& b, int error, llvm::Value* element) override;
  llvm::FunctionCallee runtime_call(llvm::IRBuilder<>& b, const char* name,
                                    llvm::FunctionType* type) override;
  // One thread per element (a solver loop's passes are not compiled for the GPU yet).
  bool parallel_passes() const override { return false; }

  // Why the emitted kernel cannot run on the GPU (it called the runtime), or "".
  const std::string& refused() const { return refused_; }

 private:
  llvm::Value* failure_ = nullptr;  // the kernel's failure word
  std::string refused_;
};

}  // namespace simit::jit::ptx
