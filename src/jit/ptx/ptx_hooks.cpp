// The NVIDIA GPU's hooks of LLVM emission (jit/ptx/ptx_hooks.h).
#include "jit/ptx/ptx_hooks.h"

#include <llvm/IR/CallingConv.h>
#include <llvm/IR/IntrinsicsNVPTX.h>

#include "jit/ptx/ptx_target.h"

namespace simit::jit::ptx {

llvm::Value* thread_index(llvm::IRBuilder<>& b) {
  auto sreg = [&](llvm::Intrinsic::ID id) {
    return b.CreateZExt(b.CreateIntrinsic(id, {}, {}), b.getInt64Ty());
  };
  return b.CreateAdd(b.CreateMul(sreg(llvm::Intrinsic::nvvm_read_ptx_sreg_ctaid_x),
                                 sreg(llvm::Intrinsic::nvvm_read_ptx_sreg_ntid_x)),
                     sreg(llvm::Intrinsic::nvvm_read_ptx_sreg_tid_x));
}

codegen::MapEntry PtxHooks::map_kernel(llvm::Module& m, const std::string& name) {
  llvm::LLVMContext& ctx = m.getContext();
  llvm::Type* ptr = llvm::PointerType::getUnqual(ctx);
  llvm::Type* i32 = llvm::Type::getInt32Ty(ctx);
  auto* ft =
      llvm::FunctionType::get(llvm::Type::getVoidTy(ctx), {ptr, ptr, ptr, i32, i32, ptr}, false);
  codegen::MapEntry e;
  e.fn = llvm::Function::Create(ft, llvm::Function::ExternalLinkage, name, m);
  // The calling convention makes it an `.entry` (LLVM 20 and later know kernels by it alone,
  // not by the older nvvm.annotations metadata).
  e.fn->setCallingConv(llvm::CallingConv::PTX_Kernel);
  auto arg = e.fn->arg_begin();
  e.arrays = &*arg++, e.scalars = &*arg++, e.endpoints = &*arg++;
  e.begin = &*arg++, e.end = &*arg++;
  failure_ = &*arg;
  for (int i = 0; i < 3; ++i) e.fn->addParamAttr(i, llvm::Attribute::NoAlias);
  return e;
}

// e = begin + the thread's index, and the element visited when e < end; then return.
void PtxHooks::elements(codegen::MapEmitter& k, const codegen::MapEntry& entry) {
  llvm::IRBuilder<>& b = k.builder();
  llvm::LLVMContext& ctx = b.getContext();
  llvm::Type* i64 = b.getInt64Ty();
  llvm::Value* e = b.CreateAdd(b.CreateSExt(entry.begin, i64), thread_index(b), "e");
  auto* visit = llvm::BasicBlock::Create(ctx, "element", entry.fn);
  auto* done = llvm::BasicBlock::Create(ctx, "done", entry.fn);
  b.CreateCondBr(b.CreateICmpSLT(e, b.CreateSExt(entry.end, i64)), visit, done);
  b.SetInsertPoint(visit);
  k.visit(b.CreateTrunc(e, b.getInt32Ty()));
  k.block(k.trace().body);
  b.CreateBr(done);
  b.SetInsertPoint(done);
  b.CreateRetVoid();
}

// The failure word keeps the lowest (element, error) any thread reported: an integer minimum,
// whose result does not depend on the threads' order, so the element reported is the one
// the CPU's executors report (the lowest). A system kernel (element null) reports element 0.
void PtxHooks::fail(llvm::IRBuilder<>& b, int error, llvm::Value* element) {
  if (failure_) {
    llvm::Type* i64 = b.getInt64Ty();
    llvm::Value* at = element ? b.CreateZExt(element, i64) : b.getInt64(0);
    llvm::Value* word = b.CreateOr(b.CreateShl(at, 32), b.getInt64(static_cast<uint32_t>(error)));
    b.CreateAtomicRMW(llvm::AtomicRMWInst::UMin, failure_, word, llvm::MaybeAlign(8),
                      llvm::AtomicOrdering::Monotonic);
  }
  b.CreateRetVoid();
}

// The runtime's functions run on the host only: the call is declared so that emission can
// finish, and the kernel is refused (PtxTarget reports refused()).
llvm::FunctionCallee PtxHooks::runtime_call(llvm::IRBuilder<>& b, const char* name,
                                            llvm::FunctionType* type) {
  if (refused_.empty())
    refused_ = std::string("calls the runtime's ") + name + ", which has no device version yet";
  return b.GetInsertBlock()->getModule()->getOrInsertFunction(name, type);
}

}  // namespace simit::jit::ptx
