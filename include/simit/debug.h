// `simit debug SCENE.toml|FILE.sim`: the step debugger (src/repl/debugger.h) on a scene or a
// program, with gdb's commands read from a stream (stdin).
#pragma once

#include <istream>
#include <ostream>
#include <string>

namespace simit::tools {

struct DebugOptions {
  std::string file;   // a scene (.toml) or a Simit source file (.sim)
  bool echo = false;  // print each command after the prompt (transcripts, tests)
  bool float32 = false;
};

// Reads commands from `in` until `quit` or its end. `run [FRAMES]` runs a scene's init and
// FRAMES frames (default: the scene's) without writing its output; `run FUNC ARGS...` calls an
// exported function of a .sim file with literal arguments, as `simit run FILE --call`.
// Returns 0, or 1 when the file cannot be compiled (diagnostics on `err`).
int run_debug(const DebugOptions& options, std::istream& in, std::ostream& out, std::ostream& err);

}  // namespace simit::tools
