// Loop IR statements to LLVM IR: locals, stores, branches, loops, checks, the decompositions'
// calls into the runtime and the assembly writes (jit/llvm/emitter.h).
#include <llvm/IR/MDBuilder.h>

#include "jit/llvm/emitter.h"

namespace simit::jit::codegen {

void Emitter::stmt(const Stmt& s) {
  switch (s.kind) {
    case StmtKind::SetLocal:
      if (pre_) return;  // its value is precomputed, and so are those it feeds
      if (!locals_[s.slot]) {
        ssa_[s.slot] = expr(*s.value);
        return;
      }
      b_.CreateStore(expr(*s.value), locals_[s.slot]);
      return;
    case StmtKind::Store: {
      const ArraySlot& a = slots_[s.slot];
      Value* v = expr(*s.value);
      if (a.ty == Ty::F64 && a.single) v = b_.CreateFPTrunc(v, b_.getFloatTy());
      if (a.ty == Ty::Bool) v = b_.CreateZExt(v, b_.getInt8Ty());
      b_.CreateStore(v, address(s.slot, expr(*s.index), s.comp));
      return;
    }
    case StmtKind::Assemble: return assemble(&s, 1);
    case StmtKind::If: {
      Value* c = expr(*s.value);
      auto* then_bb = llvm::BasicBlock::Create(ctx_, "then", fn_);
      auto* else_bb = llvm::BasicBlock::Create(ctx_, "else", fn_);
      auto* join = llvm::BasicBlock::Create(ctx_, "join", fn_);
      b_.CreateCondBr(c, then_bb, else_bb);
      b_.SetInsertPoint(then_bb);
      block(s.body);
      b_.CreateBr(join);
      b_.SetInsertPoint(else_bb);
      block(s.orelse);
      b_.CreateBr(join);
      b_.SetInsertPoint(join);
      return;
    }
    case StmtKind::Decompose: return decompose(s);
    case StmtKind::Check: return fail_unless(expr(*s.value), s.error, "check");
    case StmtKind::Put: b_.CreateStore(expr(*s.value), scratch_at(s.slot, *s.index)); return;
    case StmtKind::For:
      loop(b_.getInt32(0), b_.getInt32(static_cast<uint32_t>(s.n)), [&](Value* i) {
        ssa_[s.slot] = i;
        block(s.body);
      });
      return;
  }
}

void Emitter::block(const std::vector<Stmt>& body) {
  for (size_t i = 0; i < body.size();) {
    const int n = pre_ && body[i].kind == StmtKind::Assemble ? pre_->side_by_side(body, i) : 1;
    if (n > 1)
      assemble(&body[i], n);
    else
      stmt(body[i]);
    i += static_cast<size_t>(n);
  }
}

void Emitter::loop(Value* begin, Value* end, const std::function<void(Value*)>& body,
                   const LoopShape& shape) {
  llvm::BasicBlock* pre = b_.GetInsertBlock();
  auto* head = llvm::BasicBlock::Create(ctx_, shape.head, fn_);
  auto* inside = llvm::BasicBlock::Create(ctx_, shape.body, fn_);
  auto* done = llvm::BasicBlock::Create(ctx_, shape.done, fn_);
  b_.CreateBr(head);
  b_.SetInsertPoint(head);
  llvm::PHINode* i = b_.CreatePHI(begin->getType(), 2, shape.counter);
  i->addIncoming(begin, pre);
  b_.CreateCondBr(b_.CreateICmpSLT(i, end), inside, done);
  b_.SetInsertPoint(inside);
  body(i);
  i->addIncoming(b_.CreateAdd(i, llvm::ConstantInt::get(begin->getType(), shape.step)),
                 b_.GetInsertBlock());
  b_.CreateBr(head);
  b_.SetInsertPoint(done);
}

void Emitter::fail_unless(Value* ok, int error, const char* what) {
  auto* fail = llvm::BasicBlock::Create(ctx_, std::string(what) + ".fail", fn_);
  auto* cont = llvm::BasicBlock::Create(ctx_, std::string(what) + ".ok", fn_);
  b_.CreateCondBr(ok, cont, fail, llvm::MDBuilder(ctx_).createLikelyBranchWeights());
  b_.SetInsertPoint(fail);
  hooks_.fail(b_, error, per_element_ ? element_ : nullptr);
  b_.SetInsertPoint(cont);
}

// Where the element's block (or vector element) of an Assemble statement starts.
Value* Emitter::assemble_base(const Stmt& s, Value** in_place) {
  *in_place = nullptr;
  if (s.pair < 0 && s.member < 0) return address(s.slot, expr(*s.index), 0);
  // The block's position comes from a per-element table: a matrix's pattern table, or in a
  // deferred trace a vector's table of the members it writes (jit/defer_assembly.h).
  const int result = slots_[s.slot].index;
  int table = -1, marks = -1, deferred = -1;
  for (size_t i = 0; i < slots_.size(); ++i) {
    if (slots_[i].index != result) continue;
    if (slots_[i].kind == ArraySlot::Kind::Table) table = static_cast<int>(i);
    if (slots_[i].kind == ArraySlot::Kind::Marks) marks = static_cast<int>(i);
    if (slots_[i].kind == ArraySlot::Kind::Deferred) deferred = static_cast<int>(i);
  }
  llvm::LoadInst* pos =
      b_.CreateLoad(b_.getInt32Ty(), address(table, element_, s.pair >= 0 ? s.pair : s.member));
  tag(pos, table);
  if (marks >= 0) mark(marks, pos);
  Value* at = address(s.slot, pos, 0);
  if (deferred < 0) return at;
  // Entry -1 - k: the write goes to deferred block k (both addresses are computed, one kept).
  Value* k = b_.CreateSub(b_.getInt32(-1), pos);
  *in_place = b_.CreateICmpSGE(pos, b_.getInt32(0));
  return b_.CreateSelect(*in_place, at, address(deferred, k, 0));
}

// While the controller records the blocks a call writes (jit/write_guard.h), `marks` is an
// array of a byte per block and each write sets its block's; otherwise it is null.
void Emitter::mark(int marks, Value* pos) {
  auto* set = llvm::BasicBlock::Create(ctx_, "mark", fn_);
  auto* cont = llvm::BasicBlock::Create(ctx_, "marked", fn_);
  b_.CreateCondBr(b_.CreateIsNotNull(arrays_[marks]), set, cont);
  b_.SetInsertPoint(set);
  tag(b_.CreateStore(b_.getInt8(1), address(marks, pos, 0)), marks);
  b_.CreateBr(cont);
  b_.SetInsertPoint(cont);
}

// Statements s[0 .. n-1]: components s[0].comp, s[0].comp + 1, ... of one block, whose values
// lie side by side (Precomputed::side_by_side) when n > 1: one base address, and the writes
// up to four components at a time (lane by lane, the same additions).
void Emitter::assemble(const Stmt* s, int n) {
  Value* in_place;
  Value* base = assemble_base(s[0], &in_place);
  // --float32: a block's sum rounds at each addition; a deferred block holds one element's
  // contribution as it is (from -0.0), rounded when DeferredPlan::finish adds it to its block.
  Value* round32 = !float32_ ? nullptr : in_place ? in_place : b_.getTrue();
  llvm::Type* f64 = b_.getDoubleTy();
  for (int k = 0; k < n;) {
    const int width = n - k >= 4 ? 4 : n - k >= 2 ? 2 : 1;
    Value* at = b_.CreateConstInBoundsGEP1_64(f64, base, static_cast<uint64_t>(s[0].comp + k));
    Value* v = width == 1 ? expr(*s[k].value) : pre_->side_by_side_values(s[k], width);
    if (reduce_)
      hooks_.assemble(b_, at, v, alias(s[0].slot), round32);
    else
      tag(b_.CreateAlignedStore(v, at, llvm::Align(8)), s[0].slot);
    k += width;
  }
}

// The runtime's decomposition, called by name: the argument and the results pass through
// stack arrays; a non-zero return is the check that failed.
void Emitter::decompose(const Stmt& s) {
  llvm::Type* f64 = b_.getDoubleTy();
  llvm::Type* i32 = b_.getInt32Ty();
  llvm::IRBuilder<> entry(&fn_->getEntryBlock(), fn_->getEntryBlock().begin());
  Value* in = entry.CreateAlloca(f64, b_.getInt32(static_cast<uint32_t>(s.args.size())));
  Value* out = entry.CreateAlloca(f64, b_.getInt32(static_cast<uint32_t>(s.outs.size())));
  for (size_t i = 0; i < s.args.size(); ++i)
    b_.CreateStore(expr(*s.args[i]), b_.CreateConstInBoundsGEP1_64(f64, in, i));
  // int32_t simit_jit_decompose(int32_t fn, int32_t n, int32_t float32, const double* in,
  // double* out) (jit/decompose_call.h)
  auto* ft = llvm::FunctionType::get(i32, {i32, i32, i32, b_.getPtrTy(), b_.getPtrTy()}, false);
  llvm::FunctionCallee callee = hooks_.runtime_call(b_, "simit_jit_decompose", ft);
  Value* rc = b_.CreateCall(
      callee, {b_.getInt32(s.fn), b_.getInt32(s.n), b_.getInt32(float32_ ? 1 : 0), in, out});
  fail_unless(b_.CreateICmpEQ(rc, b_.getInt32(0)), s.error, "decompose");
  for (size_t i = 0; i < s.outs.size(); ++i) {
    Value* v = b_.CreateLoad(f64, b_.CreateConstInBoundsGEP1_64(f64, out, i));
    const int l = s.outs[i];
    if (locals_[l])
      b_.CreateStore(v, locals_[l]);
    else
      ssa_[l] = v;
  }
}

void Emitter::load_arrays(Value* arrays) {
  llvm::Type* ptr = b_.getPtrTy();
  for (size_t i = 0; i < slots_.size(); ++i)
    arrays_.push_back(
        b_.CreateLoad(ptr, b_.CreateConstInBoundsGEP1_64(ptr, arrays, i), slots_[i].name));
}

}  // namespace simit::jit::codegen
