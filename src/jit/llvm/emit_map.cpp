// Map and apply kernels: the function the target declares, everything invariant over the
// elements read once in its entry block, then the target's loop over the elements
// (jit/llvm/emitter.h).
#include <llvm/IR/MDBuilder.h>

#include "jit/llvm/emitter.h"

namespace simit::jit::codegen {

llvm::Function* MapEmitter::run(const std::string& name) {
  const MapEntry entry = hooks_.map_kernel(m_, name);
  fn_ = entry.fn;
  b_.SetInsertPoint(llvm::BasicBlock::Create(ctx_, "entry", fn_));
  if (!t_.writes_fields) {
    llvm::MDBuilder md(ctx_);
    llvm::MDNode* domain = md.createAnonymousAliasScopeDomain("arrays");
    inputs_ = llvm::MDNode::get(ctx_, {md.createAnonymousAliasScope(domain, "inputs")});
    results_ = llvm::MDNode::get(ctx_, {md.createAnonymousAliasScope(domain, "results")});
  }
  load_arrays(entry.arrays);
  for (size_t i = 0; i < t_.scalars.size(); ++i)
    scalars_.push_back(b_.CreateLoad(
        b_.getDoubleTy(), b_.CreateConstInBoundsGEP1_64(b_.getDoubleTy(), entry.scalars, i)));
  // Locals set once are SSA values; the others (assigned in branches) live in stack slots.
  ssa_.assign(local_types_.size(), nullptr);
  for (size_t i = 0; i < local_types_.size(); ++i) {
    const bool slot = i >= t_.local_mutable.size() || t_.local_mutable[i];
    locals_.push_back(slot ? b_.CreateAlloca(type(local_types_[i])) : nullptr);
  }
  for (int n : t_.scratch) {
    llvm::AllocaInst* a = b_.CreateAlloca(b_.getDoubleTy(), b_.getInt32(static_cast<uint32_t>(n)));
    a->setAlignment(llvm::Align(32));
    scratch_.push_back(a);
  }
  endpoint_table_ = entry.endpoints;
  hooks_.elements(*this, entry);
  return fn_;
}

void MapEmitter::visit(Value* e) {
  element_ = e;
  endpoints_.clear();
  if (t_.arity == 0) return;
  Value* base = b_.CreateMul(b_.CreateSExt(e, b_.getInt64Ty()), b_.getInt64(t_.arity));
  for (int k = 0; k < t_.arity; ++k)
    endpoints_.push_back(
        b_.CreateLoad(b_.getInt32Ty(), b_.CreateInBoundsGEP(b_.getInt32Ty(), endpoint_table_,
                                                            b_.CreateAdd(base, b_.getInt64(k)))));
}

}  // namespace simit::jit::codegen
