// What a code generator offers the trace controller: a trace in, a native kernel out. The
// CPU generator (jit/cpu) is the only one that includes LLVM's headers.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "jit/loop_ir.h"

namespace simit::jit {

// A compiled trace runs the elements [begin, end) of its target set. `arrays` holds one
// pointer per ArraySlot, `scalars` one double per scalar argument (ints and booleans
// converted exactly), `endpoints` the target's endpoint table. Returns 0, or 1 + the index
// of the failed check in Trace::errors with the element in *failed_element.
using KernelFn = int32_t (*)(void* const* arrays, const double* scalars, const int32_t* endpoints,
                             int32_t begin, int32_t end, int32_t* failed_element);

// A compiled system trace: `scalars` holds the program's scalars (in, then out), `sizes` the
// lengths the trace names, `interrupt` the host's interrupt flag (a byte, nonzero while an
// interrupt is pending: interp::Trap::interrupt_flag), which its while loop reads at the top
// of every iteration. Returns 0; kSystemInterrupted when the loop stopped there for the flag
// (the scalars written back: everything as a whole number of iterations leaves it, the ops
// after the loop not run); or 1 + the index in SystemTrace::errors of the error statement it
// reached (the scalars and vectors are then partly updated).
using SystemFn = int32_t (*)(void* const* arrays, double* scalars, const int64_t* sizes,
                             const void* interrupt);
inline constexpr int32_t kSystemInterrupted = -1;

class Kernel {
 public:
  virtual ~Kernel() = default;
  KernelFn fn = nullptr;
  SystemFn system = nullptr;
  double compile_ms = 0.0;
  int lanes = 1;        // elements computed at once (a map kernel in SIMD lanes)
  std::string llvm_ir;  // the optimised module, when asked for (`--dump=llvm`)
};

class Backend {
 public:
  virtual ~Backend() = default;
  // Null with `error` set when the trace could not be compiled.
  virtual std::unique_ptr<Kernel> compile(const Trace& trace, bool keep_ir, std::string& error) = 0;
  virtual std::unique_ptr<Kernel> compile(const SystemTrace& trace, bool keep_ir,
                                          std::string& error) = 0;
};

// Functions of the host process compiled code calls (their addresses are built into it).
struct HostCalls {
  // int32_t (int32_t fn, int32_t n, int32_t float32, const double* in, double* out)
  void* decompose = nullptr;
};

// The host CPU through LLVM ORC; null with `error` set when LLVM cannot target this machine.
std::unique_ptr<Backend> make_cpu_backend(const HostCalls& host, std::string& error);

}  // namespace simit::jit
