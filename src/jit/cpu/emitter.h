// The CPU's kernel emission as the ORC back end (jit/cpu/llvm_backend.cpp) calls it: the
// target-neutral emitter (jit/llvm/emitter.h) with the host CPU's hooks (jit/cpu/cpu_hooks.h).
#pragma once

#include <string>
#include <variant>

#include <llvm/IR/IRBuilder.h>
#include <llvm/IR/LLVMContext.h>
#include <llvm/IR/MDBuilder.h>
#include <llvm/IR/Module.h>

#include "jit/cpu/cpu_hooks.h"
#include "jit/llvm/emitter.h"
#include "jit/target.h"
#include "jit/tunables.h"

namespace simit::jit::cpu {

// Emits one trace as a map kernel function, or a system trace as a system kernel function
// (their arguments: jit/target.h).
class Emitter {
 public:
  // Compiled code calls the runtime by name (TargetHooks::runtime_call), so `host` is not
  // built into it: the ORC session resolves those names.
  Emitter(const Trace& t, llvm::Module& m, const HostCalls& host) : trace_(&t), m_(m) {
    (void)host;
  }
  Emitter(const SystemTrace& t, llvm::Module& m) : trace_(&t), m_(m) {}

  llvm::Function* run(const std::string& name) {
    CpuHooks hooks;
    return codegen::MapEmitter(*std::get<const Trace*>(trace_), m_, hooks).run(name);
  }
  llvm::Function* run_system(const std::string& name) {
    CpuHooks hooks;
    return codegen::SystemEmitter(*std::get<const SystemTrace*>(trace_), m_, hooks).run(name);
  }
  // A device program's steps (jit/device_program.h) behind one function, which the emulated
  // GPU calls: void name(int32_t step, int64_t* context, int64_t first, int64_t end).
  llvm::Function* run_device_steps(const std::string& name);

 private:
  std::variant<const Trace*, const SystemTrace*> trace_;
  llvm::Module& m_;
};

}  // namespace simit::jit::cpu
