// Ctrl-C as a stop of the run rather than the end of the process, for command-line runs that
// still have something to print when a run ends early (`simit run --jit-stats`).
#pragma once

#include "interp/hook.h"

namespace simit::api {

// While it lives, the first SIGINT asks `trap` to stop the run at its next statement (the
// interpreter checks it per statement, compiled maps between chunks of elements) with an
// interp::Interrupted error, which the command reports like any run-time error before it
// prints the rest. The handler then puts the previous one back, so that a second Ctrl-C does
// what it did before (ends the process), also while a compiled loop never reaches a check.
// An ignored SIGINT (a background job) stays ignored; only one scope is active at a time (an
// inner one does nothing).
class StopOnSigint {
 public:
  explicit StopOnSigint(interp::Trap& trap);
  ~StopOnSigint();
  StopOnSigint(const StopOnSigint&) = delete;
  StopOnSigint& operator=(const StopOnSigint&) = delete;

 private:
  bool installed_ = false;
};

}  // namespace simit::api
