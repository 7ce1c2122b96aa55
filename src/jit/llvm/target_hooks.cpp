// The default hooks every target shares (jit/llvm/target_hooks.h): the project's math
// functions called by their C names, and assembly as a plain load, add and store.
#include "jit/llvm/target_hooks.h"

namespace simit::jit::codegen {

llvm::Value* TargetHooks::math(llvm::IRBuilder<>& b, MathFn f,
                               const std::vector<llvm::Value*>& args) {
  std::vector<llvm::Type*> params(args.size(), b.getDoubleTy());
  auto* ft = llvm::FunctionType::get(b.getDoubleTy(), params, false);
  const std::string name = std::string("simit_math_") + math_name(f);
  llvm::FunctionCallee callee = b.GetInsertBlock()->getModule()->getOrInsertFunction(name, ft);
  if (auto* fn = llvm::dyn_cast<llvm::Function>(callee.getCallee())) {
    fn->setDoesNotThrow();
    fn->setDoesNotAccessMemory();  // pure: no errno, no state
    fn->setWillReturn();
  }
  llvm::CallInst* c = b.CreateCall(callee, args);
  c->addFnAttr(llvm::Attribute::NoBuiltin);
  return c;
}

void TargetHooks::assemble(llvm::IRBuilder<>& b, llvm::Value* at, llvm::Value* value,
                           const llvm::AAMDNodes& aa, llvm::Value* round32) {
  llvm::LoadInst* old = b.CreateAlignedLoad(value->getType(), at, llvm::Align(8));
  old->setAAMetadata(aa);
  llvm::Value* sum = b.CreateFAdd(old, value);
  if (round32) {
    llvm::Value* rounded = b.CreateFPExt(
        b.CreateFPTrunc(sum, value->getType()->getWithNewType(b.getFloatTy())), value->getType());
    auto* always = llvm::dyn_cast<llvm::ConstantInt>(round32);
    sum = always && always->isOne() ? rounded : b.CreateSelect(round32, rounded, sum);
  }
  b.CreateAlignedStore(sum, at, llvm::Align(8))->setAAMetadata(aa);
}

}  // namespace simit::jit::codegen
