// `simit dap`: the step debugger behind the Debug Adapter Protocol, for editors (VS Code and
// others that speak DAP), over a pair of file descriptors (stdin and stdout).
#pragma once

#include <ostream>

namespace simit::tools {

// Serves one debugging session: reads the client's requests from `in_fd` and writes responses
// and events to `out_fd` until the client disconnects or its input ends. Problems of the
// protocol itself go to `log` (stderr) as well. Returns the process's exit status.
int run_dap(int in_fd, int out_fd, std::ostream& log);

}  // namespace simit::tools
