// The REPL behind a terminal: a session fed line by line (declarations, statements, `:`
// commands, and the step debugger's commands while a run is stopped). The front end (repl/)
// owns the terminal, the prompt and Ctrl-C; everything it says goes through this.
#pragma once

#include <functional>
#include <memory>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

namespace simit::repl {

class Session;

class ReplSession {
 public:
  // Reads the next line with a prompt while a run is stopped at a breakpoint; nullopt at the
  // end of input.
  using LineSource = std::function<std::optional<std::string>(const std::string& prompt)>;

  // Results and values go to `out`; diagnostics and run-time errors to `err`. `:scene` reads
  // scene files with the scene library (simit/scene.h).
  ReplSession(std::ostream& out, std::ostream& err);
  ~ReplSession();
  ReplSession(const ReplSession&) = delete;
  ReplSession& operator=(const ReplSession&) = delete;

  // Feeds one line. An incomplete input (an open block or bracket) is kept until a later
  // line completes it. Returns false once the session has been asked to quit.
  bool feed_line(const std::string& line);
  // True while a multi-line input is waiting for more lines (the prompt changes).
  bool pending() const;
  // Drops a multi-line input being typed (Ctrl-C at the prompt).
  void cancel_pending();
  // Candidates for tab completion of `prefix` (commands, names, intrinsics, `set.field`).
  std::vector<std::string> completions(const std::string& prefix) const;
  // Where the debugger reads its commands while a run is stopped; without one, a stop ends
  // the run.
  void set_line_source(LineSource source);
  // Stops the computation running now at its next statement (async-signal-safe: Ctrl-C).
  void interrupt();

 private:
  std::unique_ptr<Session> session_;
};

}  // namespace simit::repl
