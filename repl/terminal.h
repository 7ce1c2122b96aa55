// The REPL's front end: readline on a terminal (history in ~/.simit_history, tab
// completion), plain lines from stdin otherwise (no prompt, for scripts).
#pragma once

#include <string>

namespace simit::repl {

// Runs the REPL on stdin/stdout/stderr, loading `file` first when it is not empty (a
// `.toml` file is loaded as a scene). Ctrl-C stops a running computation and returns to the
// prompt. Returns the exit status (0).
int run_repl(const std::string& file);

}  // namespace simit::repl
