// `simit run FILE --call NAME [ARGS...]`: runs one exported function that needs no sets,
// with arguments written as literals, and prints its results.
#pragma once

#include <memory>
#include <ostream>
#include <string>
#include <vector>

namespace simit::interp {
class Trap;
}
namespace simit::api {
class CompiledProgram;
}

namespace simit::tools {

struct RunOptions {
  std::string file;
  std::string func;
  std::vector<std::string> args;  // one literal per parameter, e.g. `2.5`, `[1.0, 2.0]'`
  bool float32 = false;
  bool check_finite = false;
  interp::Trap* trap = nullptr;  // simit debug: the interpreter's trap point switch
  // `file` already compiled (simit debug runs it again and again); null: compile it here.
  std::shared_ptr<const api::CompiledProgram> program;
};

// Prints what the program prints, then one `name = literal` line per result, to `out`.
// Returns 0, or 1 (with diagnostics or the run-time error on `err`) when the file does not
// compile, the arguments do not fit, or the run stops with a run-time error.
int run_function(const RunOptions& options, std::ostream& out, std::ostream& err);

}  // namespace simit::tools
