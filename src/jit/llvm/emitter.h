// Loop IR to LLVM IR for every target: expressions and statements (Emitter), a map or apply
// kernel around one trace (MapEmitter), a solver loop around one system trace
// (SystemEmitter). What differs by target goes through its hooks (jit/llvm/target_hooks.h).
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <llvm/IR/IRBuilder.h>
#include <llvm/IR/LLVMContext.h>
#include <llvm/IR/Module.h>

#include "jit/device_program.h"
#include "jit/llvm/target_hooks.h"
#include "jit/loop_ir.h"

namespace simit::jit::codegen {

using llvm::IRBuilder;
using llvm::Value;

// Values an element's statements read that a target computed ahead of them (the CPU computes
// every value for several elements at once, then runs each element's statements): the
// statements read them back instead of computing them.
class Precomputed {
 public:
  virtual ~Precomputed() = default;
  // e's value for the element whose statements are emitted, or null: computed there.
  virtual Value* value(const Expr& e) = 0;
  // How many Assemble statements from body[i] on (body[i] one) write neighbouring components
  // of one block with values that lie side by side, and those values' first `width` from s.
  virtual int side_by_side(const std::vector<Stmt>& body, size_t i) = 0;
  virtual Value* side_by_side_values(const Stmt& s, int width) = 0;
};

// The names and step of a loop (the targets' element loops name their blocks their own way).
struct LoopShape {
  const char* head = "loop";
  const char* body = "loop.body";
  const char* done = "loop.done";
  const char* counter = "";
  int step = 1;
};

// Expressions and statements into the function being emitted: the part of a kernel every
// target emits alike. The function and the values it reads before its body (arrays, locals)
// are set up by MapEmitter or SystemEmitter.
// v's binary32 operand where v widens a binary32 value (an fpext from float, of a scalar or
// of lanes), or null.
Value* widened_binary32(Value* v);

class Emitter {
 public:
  // reduce: Assemble adds to the result (else it overwrites); float32: the decompositions'
  // tolerance; per_element: a failure reports the element.
  Emitter(llvm::Module& m, TargetHooks& hooks, const std::vector<ArraySlot>& slots,
          const std::vector<Ty>& local_types, bool reduce, bool float32, bool per_element)
      : slots_(slots),
        local_types_(local_types),
        m_(m),
        ctx_(m.getContext()),
        b_(ctx_),
        hooks_(hooks),
        reduce_(reduce),
        float32_(float32),
        per_element_(per_element) {}

  IRBuilder<>& builder() { return b_; }
  llvm::Function* function() const { return fn_; }

  Value* expr(const Expr& e);
  // Component e.comp (plus ops[1], a loop's counter, where given) of array e.slot at the
  // (scalar) element index.
  Value* load(const Expr& e, Value* index);
  // The operators on evaluated operands: scalars, or vectors of one element per lane.
  Value* combine(const Expr& e, const std::vector<Value*>& args);
  void block(const std::vector<Stmt>& body);
  // for (i = begin; i < end; i += step) body(i), i an i32 (or i64 when wide).
  void loop(Value* begin, Value* end, const std::function<void(Value*)>& body,
            const LoopShape& shape = {});
  // While set, the statements read the values `p` holds (and set no locals).
  void set_precomputed(Precomputed* p) { pre_ = p; }

 protected:
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
  // x (a binary64 operation) computed in binary32 where that gives its rounded value exactly.
  Value* in_binary32(Value* x);
  // x (binary64, a scalar or lanes) narrowed to binary32 and widened again: exactly x where x
  // holds a binary32 value, which in_binary32 then sees as one.
  Value* as_binary32(Value* x) {
    return b_.CreateFPExt(b_.CreateFPTrunc(x, like(b_.getFloatTy(), x)), x->getType());
  }
  llvm::Type* like(llvm::Type* scalar, Value* like);
  Value* int_divide(Value* x, Value* y, bool remainder);
  // Address of a component of a per-element scratch array (a tiled tensor).
  Value* scratch_at(int slot, const Expr& index);
  void stmt(const Stmt& s);
  // Unless `ok` (expected true), the kernel leaves with error `error` (TargetHooks::fail).
  void fail_unless(Value* ok, int error, const char* what);
  void decompose(const Stmt& s);
  // in_place: set to whether the write goes to the result's own block (null: it always does)
  // rather than to a deferred block.
  Value* assemble_base(const Stmt& s, Value** in_place);
  void mark(int marks, Value* pos);
  void assemble(const Stmt* s, int n);
  void load_arrays(Value* arrays);
  // A map that writes only its results: result memory and everything it reads are disjoint,
  // and saying so lets LLVM keep table entries and field values in registers across the
  // result writes (alias.scope / noalias metadata; null when the trace writes fields).
  void tag(llvm::Instruction* i, int slot) {
    if (inputs_) i->setAAMetadata(alias(slot));
  }
  llvm::AAMDNodes alias(int slot) const;

  const std::vector<ArraySlot>& slots_;
  const std::vector<Ty>& local_types_;
  llvm::Module& m_;
  llvm::LLVMContext& ctx_;
  IRBuilder<> b_;
  TargetHooks& hooks_;
  const bool reduce_, float32_, per_element_;
  llvm::Function* fn_ = nullptr;
  std::vector<Value*> arrays_, scalars_, locals_, endpoints_;
  std::vector<Value*> ssa_;      // values of the locals set once
  std::vector<Value*> scratch_;  // the scratch arrays, in the function's entry block
  Value* element_ = nullptr;
  Value* element_wide_ = nullptr;  // element_ as an i64, where a pass computed it so
  Precomputed* pre_ = nullptr;
  llvm::MDNode *inputs_ = nullptr, *results_ = nullptr;
  // The locals (stored in allocas) known to hold a binary32 value where the code being
  // emitted reads them (SystemEmitter::emit_ops); empty: none.
  std::vector<bool> binary32_locals_;
  bool binary32_local(int slot) const {
    return static_cast<size_t>(slot) < binary32_locals_.size() &&
           binary32_locals_[static_cast<size_t>(slot)];
  }
};

// A map or apply kernel: the trace's body once per element of the call's range.
class MapEmitter : public Emitter {
 public:
  MapEmitter(const Trace& t, llvm::Module& m, TargetHooks& hooks)
      : Emitter(m, hooks, t.arrays, t.locals, t.reduce, t.float32, true), t_(t) {}

  llvm::Function* run(const std::string& name);

  const Trace& trace() const { return t_; }
  // Element e's index and its endpoints become the values Element and Endpoint read.
  void visit(Value* e);
  Value* element() const { return element_; }
  const std::vector<Value*>& endpoints() const { return endpoints_; }

 private:
  const Trace& t_;
  Value* endpoint_table_ = nullptr;
};

// A system kernel: int32_t fn(void* const* arrays, double* scalars, const int64_t* sizes,
// const void* interrupt, void* pool, int64_t* iterations) (jit/target.h, SystemArgs), whose
// returns are the kernel's status. Where the target runs passes in parallel
// (TargetHooks::parallel_passes), each pass and product is outlined into a function over a range of
// its units, which the runtime's simit_jit_parallel_for runs on the pool
// (jit/llvm/emit_parallel.cpp).
class SystemEmitter : public Emitter {
 public:
  SystemEmitter(const SystemTrace& t, llvm::Module& m, TargetHooks& hooks)
      : Emitter(m, hooks, t.arrays, t.locals, false, false, false), st_(t) {}

  llvm::Function* run(const std::string& name);
  // A device program's steps (jit/device_program.h; emit_device_steps.cpp), each as
  //   void step(int64_t* context, int64_t first_unit, int64_t end_unit)
  // (internal functions: the target wraps each in its own entry), in DeviceProgram::all's
  // order, named device_step_name(prefix, i). Build the emitter with device_step_hooks.
  std::vector<llvm::Function*> device_steps(const DeviceProgram& p, const std::string& prefix);

 private:
  void vector_op(const VectorOp& op, const std::vector<Value*>& sizes);
  void spmv(const VectorOp& op, const std::vector<Value*>& sizes);
  void spmv_row(const VectorOp& op, Value* r, Value* lane);
  // Products over a copy in pairs of rows (emit_spmv_pairs.cpp; PrunedMatrix::pairs).
  bool products_in_pairs(const VectorOp& op) const;
  void spmv_pairs(const VectorOp& op, const std::vector<Value*>& sizes);
  void spmv_pair(const VectorOp& op, Value* r, Value* rows, Value* lane);
  llvm::Function* device_step(const DeviceStep& s, const std::string& name);
  void device_units(const DeviceStep& s, Value* first, Value* end,
                    const std::vector<Value*>& sizes);
  void combine_sums(const DeviceStep& s, const std::vector<Value*>& sizes);
  void guarded_op(const VectorOp& op, const std::vector<Value*>& sizes);
  // The ops of one list (before, the loop's body, after) in order, noting which locals each
  // leaves holding a binary32 value for the ops after it (binary32_locals_).
  void emit_ops(const std::vector<VectorOp>& ops, const std::vector<Value*>& sizes);
  bool holds_binary32(const Expr& e) const;
  // The op's body for the `group` components of one run starting at `first` (an i64); with
  // sums, each taken over the run alone and then added to lane `lane` (an i64) of its chunk.
  void run_of(const VectorOp& op, Value* first, int group, Value* lane);
  bool pass_in_lanes(const VectorOp& op) const;
  Value* pass_lanes(const Expr& e, Value* first);
  void runs_in_lanes(const VectorOp& op, Value* first, Value* lane);
  // An op with sums: its elements chunk by chunk (runtime/blocked_sum.h), work(begin, end)
  // emitting a chunk's elements [begin, end) (i64s).
  void chunked(const VectorOp& op, Value* elements,
               const std::function<void(Value*, Value*)>& work);
  Value* lane_of(Value* offset);
  Value* lane_at(size_t k, Value* lane);
  void write_scalars(Value* scalars);
  Value* iterations_ = nullptr;      // the loop's count of iterations run (an i64 alloca)
  Value* iterations_out_ = nullptr;  // where the kernel stores it (SystemArgs::iterations)
  void while_loop(const std::vector<Value*>& sizes, Value* scalars, Value* interrupt);
  std::vector<Value*> load_sizes(Value* sizes_in);
  // Component `k` (an i64) of a one-component vector array, as binary64 (a binary32 array's
  // widened); the store rounds to a binary32 array's storage.
  Value* load_component(int slot, Value* k);
  void store_component(int slot, Value* k, Value* v);

  // Parallel passes (emit_parallel.cpp). A unit is a chunk of runtime::kSumChunk elements for
  // an op with sums or a product's rows, pass_unit components for a pass without sums.
  void prepare_parallel(Value* arrays, Value* sizes_in, const std::vector<Value*>& sizes);
  void parallel_op(const VectorOp& op, const std::vector<Value*>& sizes);
  bool outlinable(const VectorOp& op) const;
  Value* units_of(const VectorOp& op, const std::vector<Value*>& sizes);
  int64_t pass_unit(const VectorOp& op) const;
  llvm::Function* outline(const VectorOp& op);
  // [0, n) (i64s), or inside an outlined op the part of it its units cover (`unit` per unit).
  std::pair<Value*, Value*> unit_range(Value* n, int64_t unit);

  const SystemTrace& st_;
  // The lane accumulators of the chunk being emitted: runtime::kSumLanes doubles per sum.
  Value* lanes_ = nullptr;
  // Inside an outlined op: its units [begin, end) and where its chunks' partials go.
  struct Outlined {
    Value *begin = nullptr, *end = nullptr, *partials = nullptr;
  };
  Outlined* outlined_ = nullptr;
  Value* pool_ = nullptr;      // the kernel's pool argument
  Value* context_ = nullptr;   // what an outlined op reads: arrays, sizes, partials, locals
  Value* partials_ = nullptr;  // per unit and sum, a chunk's partial
  int outlined_ops_ = 0;
};

// Hooks for a device program's steps: `target`'s, except that a failed check stores 1 + its
// index in the context's error word and leaves the step (emit_device_steps.cpp).
std::unique_ptr<TargetHooks> device_step_hooks(TargetHooks& target);

// Components of a pass without sums an outlined call runs per unit, when no sum or product of
// its loop gives one (SystemEmitter::pass_unit).
inline constexpr int64_t kPassUnit = 1024;

}  // namespace simit::jit::codegen
