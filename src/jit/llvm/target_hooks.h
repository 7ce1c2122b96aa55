// What LLVM emission asks of a target: the few choices that differ between the host CPU and
// a GPU (the map kernel's function and its loop over the elements, library calls, the
// assembly's additions, the failure report, calls into the runtime). Everything else a
// kernel computes is emitted the same way for every target (jit/llvm/emitter.h).
#pragma once

#include <string>
#include <vector>

#include <llvm/IR/IRBuilder.h>
#include <llvm/IR/Metadata.h>
#include <llvm/IR/Module.h>

#include "jit/loop_ir.h"

namespace simit::jit::codegen {

class MapEmitter;

// A map kernel's function as a target declares it, and the arguments its body reads (their
// meaning: jit/target.h, MapArgs and ElementRange).
struct MapEntry {
  llvm::Function* fn = nullptr;
  llvm::Value* arrays = nullptr;     // void* const*: one pointer per ArraySlot
  llvm::Value* scalars = nullptr;    // const double*: the call's scalar arguments
  llvm::Value* endpoints = nullptr;  // const int32_t*: the target set's endpoint table
  llvm::Value* begin = nullptr;      // i32: the call's elements are [begin, end)
  llvm::Value* end = nullptr;
};

// One object per kernel emitted: a target may keep what its function declared (the failure
// report's destination) between calls.
class TargetHooks {
 public:
  virtual ~TargetHooks() = default;

  // Declares the map kernel `name` in `m`.
  virtual MapEntry map_kernel(llvm::Module& m, const std::string& name) = 0;
  // With the builder at the end of the kernel's entry block (everything invariant over the
  // elements loaded), emits the visit of each element of the call's range (k.visit, then
  // k.block of the trace's body, or the target's own strategy over them) and the kernel's
  // successful return.
  virtual void elements(MapEmitter& k, const MapEntry& entry) = 0;
  // C library function `f` of scalar binary64 arguments (the ones computed exactly, sqrt,
  // fabs, fmax and fmin, are emitted inline for every target). By default a call of the
  // project's own function (runtime/math/math_functions.h, the interpreter's bits) by its C
  // name, simit_math_sin and so on, which each target defines for its code (the CPU links
  // this process's, the GPU links their device bitcode). LLVM knows nothing of these names,
  // so it folds no call.
  virtual llvm::Value* math(llvm::IRBuilder<>& b, MathFn f, const std::vector<llvm::Value*>& args);
  // `f` of vectors of lanes (a map kernel's elements at once) by one call, or null where the
  // target has none for `f` and that many lanes: each lane then calls math().
  virtual llvm::Value* math_lanes(llvm::IRBuilder<>& /*b*/, MathFn /*f*/,
                                  const std::vector<llvm::Value*>& /*args*/) {
    return nullptr;
  }
  // *at += value (a double, or a vector of doubles at 8-byte alignment): an assembly write
  // with `reduce +`; round32 (an i1, or null for never; --float32): where it holds, the sum
  // rounded to binary32. `aa`: the alias metadata of the accesses to the result. By default a
  // plain load, add and store: right where one thread writes each block at a time.
  virtual void assemble(llvm::IRBuilder<>& b, llvm::Value* at, llvm::Value* value,
                        const llvm::AAMDNodes& aa, llvm::Value* round32);
  // Leaves the kernel reporting the failure of Trace::errors[error] (or SystemTrace's), at
  // `element` (an i32; null in a system kernel). Ends the current block.
  virtual void fail(llvm::IRBuilder<>& b, int error, llvm::Value* element) = 0;
  // The runtime's function `name` (extern "C", e.g. simit_jit_decompose), called by name so
  // that the code holds no address of this process.
  virtual llvm::FunctionCallee runtime_call(llvm::IRBuilder<>& b, const char* name,
                                            llvm::FunctionType* type) = 0;
  // Whether a solver loop's passes and products run their units on the kernel's pool
  // (outlined, through the runtime's simit_jit_parallel_for), or inline in element order.
  virtual bool parallel_passes() const { return false; }
};

}  // namespace simit::jit::codegen
