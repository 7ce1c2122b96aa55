// The code emitter shared by the CPU generator's files: loop IR to LLVM IR, one trace (a map
// or apply kernel) or one system trace (a solver loop) per function.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include <llvm/IR/IRBuilder.h>
#include <llvm/IR/LLVMContext.h>
#include <llvm/IR/MDBuilder.h>
#include <llvm/IR/Module.h>

#include "jit/target.h"
#include "jit/tunables.h"

namespace simit::jit::cpu {

using llvm::IRBuilder;
using llvm::Value;

// Whether a map kernel computes kLanes elements at once (jit/cpu/emit_lanes.cpp).
bool lanes_fit(const Trace& t);

// Emits one trace as a map kernel function, or a system trace as a system kernel function
// (their arguments: jit/target.h).
class Emitter {
 public:
  Emitter(const Trace& t, llvm::Module& m, const HostCalls& host)
      : t_(&t),
        slots_(t.arrays),
        local_types_(t.locals),
        m_(m),
        ctx_(m.getContext()),
        b_(ctx_),
        host_(host) {}
  Emitter(const SystemTrace& t, llvm::Module& m)
      : st_(&t), slots_(t.arrays), local_types_(t.locals), m_(m), ctx_(m.getContext()), b_(ctx_) {}

  llvm::Function* run(const std::string& name);
  llvm::Function* run_system(const std::string& name);

 private:
  llvm::Type* type(Ty t) {
    switch (t) {
      case Ty::F64: return b_.getDoubleTy();
      case Ty::I32: return b_.getInt32Ty();
      case Ty::Bool: return b_.getInt1Ty();
    }
    return nullptr;
  }
  llvm::Type* storage(const ArraySlot& a) {
    if (a.ty == Ty::F64) return a.single ? b_.getFloatTy() : b_.getDoubleTy();
    if (a.ty == Ty::I32) return b_.getInt32Ty();
    return b_.getInt8Ty();
  }
  // Address of component `comp` of element `index` of array `slot`.
  Value* address(int slot, Value* index, int comp) {
    return address(slot, index, b_.getInt64(comp));
  }
  Value* address(int slot, Value* index, Value* comp) {  // comp: an i64
    const ArraySlot& a = slots_[slot];
    // The visited element as the i64 it was computed from: LLVM then sees that a pass reads
    // the component a product has just stored (and keeps it in a register).
    Value* i =
        index == element_ && element_wide_ ? element_wide_ : b_.CreateSExt(index, b_.getInt64Ty());
    Value* at = b_.CreateAdd(b_.CreateMul(i, b_.getInt64(a.components)), comp);
    return b_.CreateInBoundsGEP(storage(a), arrays_[slot], at);
  }
  Value* math(const Expr& e, const std::vector<Value*>& args);
  llvm::Type* like(llvm::Type* scalar, Value* like);
  Value* int_divide(Value* x, Value* y, bool remainder);
  Value* combine(const Expr& e, const std::vector<Value*>& args);
  Value* expr(const Expr& e);
  Value* load(const Expr& e, Value* index);
  // Address of a component of a per-element scratch array (a tiled tensor).
  Value* scratch_at(int slot, const Expr& index);
  // Element e's index and its endpoints become the values Element and Endpoint read.
  void visit(Value* e);
  // Lanes (a map kernel computing kLanes elements at once; see lanes_fit).
  void run_lanes(Value* first, Value* end);
  Value* lanes(const Expr& e);
  Value* lanes_uncached(const Expr& e);
  void lanes_block(const std::vector<Stmt>& body);
  void allocate_roots();
  void count_roots(const std::vector<Stmt>& body);
  void spill(const Expr& e);
  Value* load_root(Ty t, int index);
  void flush_pending(int first);
  void block(const std::vector<Stmt>& body);
  void stmt(const Stmt& s);
  // for (i = begin; i < end; ++i) body(i), i an i32 (or i64 when wide).
  void loop(Value* begin, Value* end, const std::function<void(Value*)>& body);
  void vector_op(const VectorOp& op, const std::vector<Value*>& sizes);
  void guarded_op(const VectorOp& op, const std::vector<Value*>& sizes);
  // Unless `ok` (expected true), the kernel returns error + 1 with the element in *failed (a
  // map kernel).
  void fail_unless(Value* ok, int error, const char* what) {
    auto* fail = llvm::BasicBlock::Create(ctx_, std::string(what) + ".fail", fn_);
    auto* cont = llvm::BasicBlock::Create(ctx_, std::string(what) + ".ok", fn_);
    b_.CreateCondBr(ok, cont, fail, llvm::MDBuilder(ctx_).createLikelyBranchWeights());
    b_.SetInsertPoint(fail);
    if (failed_) b_.CreateStore(element_, failed_);  // a system trace has no element
    b_.CreateRet(b_.getInt32(error + 1));
    b_.SetInsertPoint(cont);
  }
  // The op's body for the `group` components of one run starting at `first` (an i64), its
  // sums taken over the run alone and then added to their totals.
  void run_of(const VectorOp& op, Value* first, int group);
  bool pass_in_lanes(const VectorOp& op) const;
  Value* pass_lanes(const Expr& e, Value* first);
  void runs_in_lanes(const VectorOp& op, Value* first);
  void load_arrays(Value* arrays);

  void decompose(const Stmt& s);
  Value* assemble_base(const Stmt& s);
  void mark(int marks, Value* pos);
  void assemble(const Stmt* s, int n);
  int assemble_run(const std::vector<Stmt>& body, size_t i);
  Value* root_address(int row);

  const Trace* t_ = nullptr;
  const SystemTrace* st_ = nullptr;
  const std::vector<ArraySlot>& slots_;
  const std::vector<Ty>& local_types_;
  llvm::Module& m_;
  llvm::LLVMContext& ctx_;
  IRBuilder<> b_;
  llvm::Function* fn_ = nullptr;
  std::vector<Value*> arrays_, scalars_, locals_, endpoints_;
  std::vector<Value*> ssa_;      // values of the locals set once
  std::vector<Value*> scratch_;  // the scratch arrays, in the function's entry block
  Value* element_ = nullptr;
  Value* element_wide_ = nullptr;  // element_ as an i64, where a pass computed it so
  Value* failed_ = nullptr;
  Value* endpoint_table_ = nullptr;
  // Lanes: each expression's value for every lane (memoised by node: traces share nodes),
  // the locals', and each lane's element and endpoints.
  std::unordered_map<const Expr*, Value*> vmemo_;
  std::vector<Value*> vlocal_, element_lane_;
  std::vector<std::vector<Value*>> endpoint_lane_;
  // The values the element-by-element statements read (conditions, written values), stored
  // per lane in one buffer per type: root -> its row.
  std::unordered_map<const Expr*, int> roots_;
  std::unordered_set<const Expr*> spilled_;
  int root_rows_[3] = {0, 0, 0};
  Value* root_buffer_[3] = {nullptr, nullptr, nullptr};
  Value* lane_ = nullptr;        // the lane whose statements are being emitted (i64), or null
  uint64_t root_stride_ = 0;     // float rows per lane in the buffer (a multiple of 4)
  std::vector<Value*> pending_;  // float roots computed, not yet stored
  HostCalls host_;
  // A map that writes only its results: result memory and everything it reads are disjoint,
  // and saying so lets LLVM keep table entries and field values in registers across the
  // result writes (alias.scope / noalias metadata; null when the trace writes fields).
  llvm::MDNode *inputs_ = nullptr, *results_ = nullptr;
  void tag(llvm::Instruction* i, int slot) {
    if (!inputs_) return;
    const ArraySlot::Kind k = slots_[static_cast<size_t>(slot)].kind;
    const bool result = k == ArraySlot::Kind::Result || k == ArraySlot::Kind::Marks;
    i->setMetadata(llvm::LLVMContext::MD_alias_scope, result ? results_ : inputs_);
    i->setMetadata(llvm::LLVMContext::MD_noalias, result ? inputs_ : results_);
  }
};

}  // namespace simit::jit::cpu
