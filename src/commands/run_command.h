// `simit run FILE --call` as `simit debug` runs it: under the debugger's trap point, over a
// program compiled once for many runs.
#pragma once

#include <memory>
#include <ostream>

#include "api/compiled_program.h"
#include "interp/hook.h"
#include "simit/commands.h"

namespace simit::tools {

struct RunHooks {
  interp::Trap* trap = nullptr;  // the interpreter's trap point switch
  // `options.file` already compiled; null: compile it here.
  std::shared_ptr<const api::CompiledProgram> program;
};

int run_function(const RunOptions& options, const RunHooks& hooks, std::ostream& out,
                 std::ostream& err);

}  // namespace simit::tools
