// What LLVM's vectorisers did with a kernel's loops: the loops numbered and described before
// the module is optimised, and the loop and SLP vectorisers' optimisation remarks collected
// while it is, into the kernel's SimdReport (jit/target.h; docs/jit.md, "What vectorises").
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <llvm/IR/DiagnosticHandler.h>
#include <llvm/IR/DiagnosticInfo.h>
#include <llvm/IR/Module.h>

#include "jit/target.h"

namespace simit::jit::cpu {

class SimdRemarks {
 public:
  // Numbers the loops of `m` (emitted, not yet optimised) in the order they were emitted,
  // function by function, describes each from its shape (`lanes`: a map kernel in SIMD
  // lanes), and tags it with loop metadata ("simit.loop", its number) that the optimiser
  // carries along, so that a remark names its loop.
  SimdRemarks(llvm::Module& m, bool lanes);

  // The remarks handler for the module's context while it is optimised: it keeps the loop
  // and SLP vectorisers' remarks and hands every other diagnostic to LLVM's default.
  std::unique_ptr<llvm::DiagnosticHandler> handler();

  // The innermost loops the loop vectoriser reported on, and the SLP vectoriser's groups.
  void fill(SimdReport& report) const;

  // One loop's line for the optimised module's text (--dump=llvm), e.g. "loop 2 (vector
  // pass): vectorised, width 4, interleave 2".
  static std::string describe(const SimdLoop& loop);

  // Called by the handler with each loop or SLP vectoriser remark.
  void remark(const llvm::DiagnosticInfoOptimizationBase& r);

 private:
  struct Loop {
    std::string what;
    bool reported = false;  // the loop vectoriser said something of it
    int width = 1, interleave = 1;
    std::vector<std::string> why_not;
  };

  std::vector<Loop> loops_;  // by number - 1
  // Reasons given for a loop not yet known: the loop vectoriser names a loop's block that is
  // not its header in some analysis remarks, and then names the loop itself.
  std::vector<std::string> pending_;
  int slp_groups_ = 0;
};

// LLVM's reason for not vectorising a loop (an analysis remark's name and message) in short
// words: "reduction in the contract's order" for a floating-point reduction LLVM may not
// reorder (docs/arithmetic.md forbids it), LLVM's own words for reasons without a short form.
std::string short_reason(const std::string& remark_name, const std::string& message);

}  // namespace simit::jit::cpu
