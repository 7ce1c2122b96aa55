// The host CPU's choices in LLVM emission (jit/llvm/target_hooks.h): the map kernel is a C
// function that loops over its elements (kLanes at a time where the trace allows), calls the
// C library by name, adds into the results without atomics (a call's elements run in
// order on one thread) and returns its status.
#pragma once

#include <string>

#include "jit/llvm/emitter.h"
#include "jit/llvm/target_hooks.h"

namespace simit::jit::cpu {

// Whether a map kernel computes kLanes elements at once (jit/cpu/emit_lanes.cpp); when not,
// *why_not (where given) says why in short words ("a local assigned in a branch").
bool lanes_fit(const Trace& t, std::string* why_not = nullptr);
// How many elements at once a kernel that lanes_fit computes: kLanes32 under --float32, else
// kLanes.
int lanes_of(const Trace& t);
// Elements first .. first + lanes_of - 1 of a kernel that lanes_fit, not past `end` (i32s).
void run_lanes(codegen::MapEmitter& k, llvm::Value* first, llvm::Value* end);

// A map kernel is int32_t fn(void* const* arrays, const double* scalars, const int32_t*
// endpoints, int32_t begin, int32_t end, int32_t* failed_element) (jit/target.h): 0, or 1 +
// the failed check's index with the element in *failed_element. A system kernel returns
// 1 + the error's index.
class CpuHooks : public codegen::TargetHooks {
 public:
  codegen::MapEntry map_kernel(llvm::Module& m, const std::string& name) override;
  void elements(codegen::MapEmitter& k, const codegen::MapEntry& entry) override;
  void fail(llvm::IRBuilder<>& b, int error, llvm::Value* element) override;
  llvm::FunctionCallee runtime_call(llvm::IRBuilder<>& b, const char* name,
                                    llvm::FunctionType* type) override;
  bool parallel_passes() const override { return true; }
  llvm::Value* math_lanes(llvm::IRBuilder<>& b, MathFn f,
                          const std::vector<llvm::Value*>& args) override;

 private:
  llvm::Value* failed_ = nullptr;  // the map kernel's failed_element (none in a system kernel)
};

}  // namespace simit::jit::cpu
