// simit::tools::run_dap (simit/dap.h): one session of the DAP server.
#include "dap/server.h"
#include "simit/dap.h"

namespace simit::tools {

int run_dap(int in_fd, int out_fd, std::ostream& log) {
  dap::Server server(in_fd, out_fd, log);
  return server.run();
}

}  // namespace simit::tools
