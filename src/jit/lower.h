// The lowering driver: one flat pipeline from a traced site or run of statements to a kernel,
// the same for both. The trace is verified, each pass of the list runs with a verify after it
// (and the IR printed after it with `--dump=passes`), and the target compiles the result.
//
//   map site:           trace -> verify -> compile
//   map site, parallel: trace -> verify -> defer-assembly -> verify -> compile
//   system statements:  trace -> verify -> fuse-passes -> verify -> compile
#pragma once

#include <memory>
#include <ostream>
#include <string>

#include "jit/loop_ir.h"
#include "jit/target.h"

namespace simit::jit {

struct LowerOptions {
  std::ostream* dump = nullptr;  // where the dumps below print; null prints nothing
  bool dump_loop_ir = false;     // the IR as it is compiled
  bool dump_passes = false;      // the IR as traced and after each pass, named
  bool dump_llvm = false;        // the target's optimised LLVM module
  // Chunks of a map's elements run apart (jit/executor.h, Executor::parallel): a map that
  // adds into shared blocks defers the later chunks' additions (jit/defer_assembly.h).
  bool defer_assembly = false;
};

struct Lowered {
  std::unique_ptr<Kernel> kernel;  // null when something failed
  std::string failure;             // why there is no kernel
  bool verify_failed = false;      // the IR was wrong (not worth another try)
  int loops_fused = 0;             // fuse-passes: loops removed
  size_t ir_nodes = 0;
};

Lowered lower(Trace& trace, Target& target, const LowerOptions& options);
Lowered lower(SystemTrace& trace, Target& target, const LowerOptions& options);

}  // namespace simit::jit
