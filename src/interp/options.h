// Settings of one interpreter run, passed down explicitly (there is no global state).
#pragma once

#include <ostream>

namespace simit::interp {

class StatementHook;

struct Options {
  // Round every float to binary32 when it is produced (the program's float type is float32).
  bool float32 = false;
  // Stop with a run-time error at the first operation that produces a NaN or an infinity.
  bool check_finite = false;
  // Where `print` and `println` write; null means standard output.
  std::ostream* out = nullptr;
  // Called before every statement (the step debugger, hot counters); null when unused.
  StatementHook* hook = nullptr;
};

}  // namespace simit::interp
