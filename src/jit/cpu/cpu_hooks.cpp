// The host CPU's hooks of LLVM emission (jit/cpu/cpu_hooks.h), and the function through which
// the emulated GPU calls a device program's steps (jit/cpu/emitter.h).
#include "jit/cpu/cpu_hooks.h"

#include <memory>
#include <vector>

#include "jit/cpu/emitter.h"
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
  const codegen::LoopShape shape{"element", "body", "done", "e",
                                 in_lanes ? lanes_of(k.trace()) : 1};
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

// atan2 and log of four lanes (or eight, a --float32 kernel's) by one call of the runtime's
// simit_math_atan2_x4 and simit_math_log_x4 (_x8: two groups of four; their lanes have the
// bits of simit_math_atan2 and simit_math_log), through arrays on the kernel's stack: four
// elements at once take about a third of four calls' time (docs/math.md), and they are the
// bend force's and the Neo-Hookean force's.
llvm::Value* CpuHooks::math_lanes(llvm::IRBuilder<>& b, MathFn f,
                                  const std::vector<llvm::Value*>& args) {
  auto* lanes = llvm::dyn_cast<llvm::FixedVectorType>(args[0]->getType());
  if ((f != MathFn::Atan2 && f != MathFn::Log) || !lanes) return nullptr;
  const unsigned count = lanes->getNumElements();
  if (count != 4 && count != 8) return nullptr;
  llvm::Function* fn = b.GetInsertBlock()->getParent();
  llvm::IRBuilder<> entry(&fn->getEntryBlock(), fn->getEntryBlock().begin());
  std::vector<llvm::Value*> at;  // the arguments' arrays, then the result's
  for (size_t i = 0; i <= args.size(); ++i) {
    llvm::AllocaInst* a = entry.CreateAlloca(lanes);
    a->setAlignment(llvm::Align(32));
    at.push_back(a);
  }
  for (size_t i = 0; i < args.size(); ++i) b.CreateAlignedStore(args[i], at[i], llvm::Align(32));
  auto* ft = llvm::FunctionType::get(b.getVoidTy(),
                                     std::vector<llvm::Type*>(at.size(), b.getPtrTy()), false);
  llvm::FunctionCallee callee =
      runtime_call(b,
                   f == MathFn::Atan2 ? (count == 8 ? "simit_math_atan2_x8" : "simit_math_atan2_x4")
                                      : (count == 8 ? "simit_math_log_x8" : "simit_math_log_x4"),
                   ft);
  if (auto* callee_fn = llvm::dyn_cast<llvm::Function>(callee.getCallee())) {
    callee_fn->setDoesNotThrow();
    callee_fn->setWillReturn();
    callee_fn->setOnlyAccessesArgMemory();
  }
  llvm::CallInst* c = b.CreateCall(callee, at);
  c->addFnAttr(llvm::Attribute::NoBuiltin);
  return b.CreateAlignedLoad(lanes, at.back(), llvm::Align(32));
}

// The steps as internal functions, and one external function that calls step `step` (a
// switch over their indices; an index out of range does nothing).
llvm::Function* Emitter::run_device_steps(const std::string& name) {
  const SystemTrace& t = *std::get<const SystemTrace*>(trace_);
  CpuHooks hooks;
  std::unique_ptr<codegen::TargetHooks> step_hooks = codegen::device_step_hooks(hooks);
  const std::vector<llvm::Function*> steps =
      codegen::SystemEmitter(t, m_, *step_hooks).device_steps(plan_device_program(t), name);
  llvm::LLVMContext& ctx = m_.getContext();
  llvm::IRBuilder<> b(ctx);
  llvm::Type* ptr = b.getPtrTy();
  llvm::Type* i64 = b.getInt64Ty();
  auto* ft = llvm::FunctionType::get(b.getVoidTy(), {b.getInt32Ty(), ptr, i64, i64}, false);
  auto* fn = llvm::Function::Create(ft, llvm::Function::ExternalLinkage, name, m_);
  auto* entry = llvm::BasicBlock::Create(ctx, "entry", fn);
  auto* done = llvm::BasicBlock::Create(ctx, "done", fn);
  b.SetInsertPoint(done);
  b.CreateRetVoid();
  b.SetInsertPoint(entry);
  llvm::SwitchInst* sw = b.CreateSwitch(fn->getArg(0), done, static_cast<unsigned>(steps.size()));
  for (size_t i = 0; i < steps.size(); ++i) {
    auto* call = llvm::BasicBlock::Create(ctx, "step", fn);
    sw->addCase(b.getInt32(static_cast<uint32_t>(i)), call);
    b.SetInsertPoint(call);
    b.CreateCall(steps[i], {fn->getArg(1), fn->getArg(2), fn->getArg(3)});
    b.CreateBr(done);
  }
  return fn;
}

}  // namespace simit::jit::cpu
