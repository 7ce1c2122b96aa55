// `simit dap`: a Debug Adapter Protocol server for the step debugger. A reader thread takes
// the client's messages off the input; everything that touches the debugger or the program
// runs on the main thread: before and after the run in the main loop, during it at the
// debugger's stops (StopHandler::stopped) and, for requests that come while the program
// runs, at its next statement (StopHandler::service). Replies and events are written whole,
// one at a time.
#pragma once

#include <atomic>
#include <condition_variable>
#include <deque>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <ostream>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "dap/variables.h"
#include "repl/debugger.h"
#include "simit/scene.h"

namespace simit::api {
class CompiledProgram;
}

namespace simit::dap {

using json = nlohmann::json;

class Server : public repl::Debugger::StopHandler {
 public:
  Server(int in_fd, int out_fd, std::ostream& log);
  ~Server() override;
  // Serves until the client disconnects or its input ends; the process's exit status.
  int run();

  // The protocol's output: one message at a time, from any thread.
  void send(json message);
  void event(const std::string& name, json body = json::object());

 private:
  // repl::Debugger::StopHandler
  void stopped(const repl::StopInfo& stop) override;
  void service() override;

  // The reader thread and the queue of requests it fills.
  void read_loop();
  void incoming(const std::string& body);
  std::optional<json> take(bool wait);
  bool input_ended();

  // One request, on the main thread (requests.cpp).
  void handle(const json& request);
  void respond(const json& request, json body = json::object());
  void fail(const json& request, const std::string& message);
  void on_launch(const json& request);
  void on_set_breakpoints(const json& request);
  void on_set_function_breakpoints(const json& request);
  void on_set_exception_breakpoints(const json& request);
  void on_data_breakpoint_info(const json& request);
  void on_set_data_breakpoints(const json& request);
  void on_stack_trace(const json& request);
  void on_error_stop(const json& request);
  void on_scopes(const json& request);
  void on_variables(const json& request);
  void on_evaluate(const json& request);
  void on_resume(const json& request, repl::Debugger::Resume how);
  // Replaces the breakpoints in `numbers` with those `requests` make; the protocol's list.
  json replace_breakpoints(std::vector<int>& numbers,
                           const std::vector<repl::BreakpointRequest>& requests);

  // Ends the run: at once when stopped, else at its next statement.
  void end_run();

  // The run (launch.cpp).
  bool open_program(const json& args, std::string& why);
  void run_program();
  void stop_on_error(const std::string& message);
  // After a run-time error, until the client goes on: where it happened.
  struct ErrorStop {
    std::string message, function;
    int line = 0, column = 0;
  };
  std::optional<ErrorStop> error_stop_;

  int in_fd_, out_fd_;
  std::ostream& log_;
  std::mutex write_mutex_;
  int seq_ = 1;

  std::mutex queue_mutex_;
  std::condition_variable queue_cv_;
  std::deque<json> queue_;
  bool input_closed_ = false;
  std::thread reader_;
  int wake_[2] = {-1, -1};  // a pipe: written when the session ends before the input does

  std::unique_ptr<std::ostream> program_out_;  // print and progress, as output events
  repl::Debugger debugger_;
  VariableStore variables_;

  // The session's state.
  bool initialised_ = false, launched_ = false, configured_ = false;
  std::atomic<bool> running_{false};  // the run is on (read by the reader thread too)
  bool resume_ = false;               // at a stop: a resume request came
  bool disconnect_ = false;           // the client asked to end the session
  bool end_run_ = false;              // the run is to end at its next statement
  bool ran_ = false;                  // the run has ended
  std::string program_file_;          // launch's `program`, absolute
  std::string source_path_;           // the .sim file breakpoints are set in, absolute
  std::string function_;              // a .sim: the function to call, with its arguments
  std::vector<std::string> args_;
  int frames_ = -1;
  bool float32_ = false;
  std::unique_ptr<scene::Scene> scene_;
  std::shared_ptr<const api::CompiledProgram> compiled_;
  std::vector<int> line_breakpoints_, function_breakpoints_, data_breakpoints_;
  std::optional<int> nan_breakpoint_;
};

}  // namespace simit::dap
