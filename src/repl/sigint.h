// A SIGINT handler installed for the lifetime of a scope (Ctrl-C in the REPL and in
// `simit debug`), restored after. SA_RESTART: a blocking read goes on; select() still
// returns EINTR, which the REPL's prompt uses.
#pragma once

#include <csignal>

namespace simit::repl {

class SigintScope {
 public:
  explicit SigintScope(void (*handler)(int)) {
    struct sigaction sa {};
    sa.sa_handler = handler;
    sa.sa_flags = SA_RESTART;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, &previous_);
  }
  ~SigintScope() { sigaction(SIGINT, &previous_, nullptr); }
  SigintScope(const SigintScope&) = delete;
  SigintScope& operator=(const SigintScope&) = delete;

 private:
  struct sigaction previous_ {};
};

}  // namespace simit::repl
