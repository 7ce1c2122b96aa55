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
// load, add and store: the arithmetic contract forbids floating-point atomics (their order,
// and so the sum's bits, change from run to run), and the GPU executor runs every map that
// adds into shared blocks with deferred writes (jit/defer_assembly.h), so that no two threads
// add into one block.
class PtxHooks : public codegen::TargetHooks {
 public:
  codegen::MapEntry map_kernel(llvm::Module& m, const std::string& name) override;
  void elements(codegen::MapEmitter& k, const codegen::MapEntry& entry) override;
  void fail(llvm::IRBuilder<>& b, int error, llvm::Value* element) override;
  llvm::FunctionCallee runtime_call(llvm::IRBuilder<>& b, const char* name,
                                    llvm::FunctionType* type) override;
  // One thread per element; a solver loop runs as a device program, one unit per thread
  // (jit/device_program.h), not through the pool's outlined passes.
  bool parallel_passes() const override { return false; }

  // Why the emitted kernel cannot run on the GPU (it called the runtime), or "".
  const std::string& refused() const { return refused_; }

 private:
  llvm::Value* failure_ = nullptr;  // the kernel's failure word
  std::string refused_;
};

// blockIdx.x * blockDim.x + threadIdx.x, computed in 64 bits (a grid larger than a range
// cannot wrap it): the thread's index in the launch.
llvm::Value* thread_index(llvm::IRBuilder<>& b);

}  // namespace simit::jit::ptx
