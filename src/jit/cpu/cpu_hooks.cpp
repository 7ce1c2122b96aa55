// The host CPU's hooks of LLVM emission (jit/cpu/cpu_hooks.h).
#include "jit/cpu/cpu_hooks.h"

#include "jit/tunables.h"

#include <string>

namespace simit::jit::cpu {

codegen::MapEntry CpuHooks::map_kernel(llvm::Module& m, const std::string& name) {
  llvm::LLVMContext& ctx = m.getContext();
  llvm::Type* ptr = llvm::PointerType::getUnqual(ctx);
  llvm::Type* i32 = llvm::Type::getInt32Ty(ctx);
  auto* ft = llvm::FunctionType::get(i32, {ptr, ptr, ptr, i32, i32, ptr}, false);
  codegen::MapEntry e;
  e.fn = llvm::Function::Create(ft, llvm::Function::ExternalLinkage, name, m);
  auto arg = e.fn->arg_begin();
  e.arrays = &*arg++, e.scalars = &*arg++, e.endpoints = &*arg++;
  e.begin = &*arg++, e.end = &*arg++;
  failed_ = &*arg;
  for (int i = 0; i < 3; ++i) e.fn->addParamAttr(i, llvm::Attribute::NoAlias);
  return e;
}

// for (e = begin; e < end; e += step) the element(s) at e; then return 0.
void CpuHooks::elements(codegen::MapEmitter& k, const codegen::MapEntry& entry) {
  const bool in_lanes = lanes_fit(k.trace());
  const codegen::LoopShape shape{"element", "body", "done", "e", in_lanes ? kLanes : 1};
  k.loop(
      entry.begin, entry.end,
      [&](llvm::Value* e) {
        if (in_lanes) return run_lanes(k, e, entry.end);
        k.visit(e);
        k.block(k.trace().body);
      },
      shape);
  llvm::IRBuilder<>& b = k.builder();
  b.CreateRet(b.getInt32(0));
}

void CpuHooks::fail(llvm::IRBuilder<>& b, int error, llvm::Value* element) {
  if (failed_ && element) b.CreateStore(element, failed_);
  b.CreateRet(b.getInt32(static_cast<uint32_t>(error + 1)));
}

// Declared by name; the ORC session resolves it to this process's function when it links
// the kernel (jit/cpu/llvm_backend.cpp).
llvm::FunctionCallee CpuHooks::runtime_call(llvm::IRBuilder<>& b, const char* name,
                                            llvm::FunctionType* type) {
  return b.GetInsertBlock()->getModule()->getOrInsertFunction(name, type);
}

}  // namespace simit::jit::cpu
