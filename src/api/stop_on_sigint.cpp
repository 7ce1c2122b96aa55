// Ctrl-C stops the run at its next statement: see stop_on_sigint.h.
#include "api/stop_on_sigint.h"

#include <atomic>
#include <csignal>

namespace simit::api {
namespace {

// What the handler reaches: set before it is installed, cleared after it is removed.
std::atomic<interp::Trap*> g_trap{nullptr};
struct sigaction g_previous {};

extern "C" void simit_stop_run_on_sigint(int) {
  if (interp::Trap* trap = g_trap.load(std::memory_order_relaxed)) trap->request_interrupt();
  sigaction(SIGINT, &g_previous, nullptr);  // async-signal-safe; the next Ctrl-C acts as before
}

}  // namespace

StopOnSigint::StopOnSigint(interp::Trap& trap) {
  if (g_trap.load() != nullptr) return;
  struct sigaction current {};
  if (sigaction(SIGINT, nullptr, &current) != 0 || current.sa_handler == SIG_IGN) return;
  g_previous = current;
  g_trap.store(&trap);
  struct sigaction action {};
  action.sa_handler = simit_stop_run_on_sigint;
  sigemptyset(&action.sa_mask);
  action.sa_flags = SA_RESTART;  // a write to the output goes on
  installed_ = sigaction(SIGINT, &action, nullptr) == 0;
  if (!installed_) g_trap.store(nullptr);
}

StopOnSigint::~StopOnSigint() {
  if (!installed_) return;
  sigaction(SIGINT, &g_previous, nullptr);
  g_trap.store(nullptr);
}

}  // namespace simit::api
