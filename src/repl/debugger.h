// The step debugger: gdb's vocabulary over the interpreter's trap point (interp/hook.h).
// Breakpoints on lines and functions with conditions (`break tet_force if t == 17`),
// watchpoints on set fields, a NaN trap, stepping, frames with the map, element and
// endpoints a mapped call serves, and expressions over locals, fields and sets
// (frontend/debug_expr.h).
//
// A host (simit debug, the REPL) owns one Debugger and:
//   1. set_program() with the program it will run and the map of its lines to files;
//   2. passes trap() to the engine (api::EngineOptions::trap, or scene::SceneAccess::open);
//   3. feeds each command line typed outside a run to command(); on Outcome::Run it starts
//      the program between begin_run() and end_run() (run_args holds what followed `run`);
//   4. may wire SIGINT to trap().request_interrupt() (async-signal-safe).
// While a run is stopped the debugger reads its own commands from the line source. The hook
// is installed only while something needs it (a breakpoint, watchpoint, the NaN trap, a
// step), so a run without any costs the trap point's one branch per statement.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <ostream>
#include <string>
#include <unordered_map>
#include <vector>

#include "frontend/ast.h"
#include "interp/hook.h"
#include "interp/value.h"
#include "line_map.h"

namespace simit::interp {
class Interpreter;
}

namespace simit::repl {

// --- The structured interface: what a front end other than gdb's command loop uses ----------

// Why a run stopped.
struct StopInfo {
  enum class Reason { Breakpoint, FunctionBreakpoint, Step, Pause, Watch, Nan, Entry };
  Reason reason = Reason::Step;
  std::string text;    // what the terminal prints for it ("Breakpoint 1, ", the watch values)
  int breakpoint = 0;  // the breakpoint, watchpoint or NaN trap's number, 0 for none
};

// A breakpoint as a front end asks for it.
struct BreakpointRequest {
  enum class Kind { Line, Function, Watch, Nan };
  Kind kind = Kind::Line;
  int line = 0;               // Line: a line of the program's (first) file
  std::string function;       // Function
  std::string watch;          // Watch: SET.FIELD[i]
  std::string condition;      // the debugger's expression language; empty for none
  std::string hit_condition;  // "N" or "== N" (the Nth hit), ">= N", "> N", "% N" (every Nth)
};

struct BreakpointResult {
  bool verified = false;
  int number = 0;       // when verified
  int line = 0;         // the file line it stops at (Line, Function)
  std::string message;  // why not, when not verified
};

// One frame of a stop, innermost first.
struct FrameInfo {
  std::string function;
  std::string element;  // a mapped call's "element 17 of tets", else empty
  std::string map;      // "map tet_force to tets, element 17, endpoints verts[4 3 7 16] (...)"
  std::string file;     // as the program was loaded
  int line = 0;         // of the file
  int column = 0;
};

// A variable visible at a stop: its name, value (null while it has none) and declared type.
struct VariableInfo {
  std::string name;
  const interp::Value* value = nullptr;
  const frontend::Type* type = nullptr;
};

class Debugger : public interp::StatementHook {
 public:
  // Reads one command line; nullopt at the end of input (which quits). The prompt is for a
  // terminal; a pipe should not show it.
  using LineSource = std::function<std::optional<std::string>(const std::string& prompt)>;
  enum class Outcome { Done, Run, Quit };
  static constexpr const char* kPrompt = "(sdb) ";

  // Output (stops, values, listings) goes to `out`, error messages to `err` (`out` is flushed
  // first, so a terminal or a merged pipe shows them in order).
  Debugger(std::ostream& out, std::ostream& err, LineSource lines);
  ~Debugger() override;

  // The program that breakpoints are checked against and `list` shows, and how its lines map
  // to files (empty: its own source name, lines as they are). The program must stay alive
  // while it is set; the running program may be another compilation of the same text.
  void set_program(const frontend::ast::Program* program, std::vector<LineSegment> line_map = {});
  // The switch to pass to the interpreter; also the place for Ctrl-C.
  interp::Trap& trap() { return trap_; }

  // One command typed outside a run. Outcome::Run: start the program with `run_args`.
  Outcome command(const std::string& line, std::string& run_args);
  // Whether `word` names a debugger command (or an unambiguous prefix of one).
  static bool is_command(const std::string& word);

  // Around every run of the program: begin_run() arms the hook when something needs it and
  // clears a stale interrupt; end_run() disarms it and returns true when the debugger itself
  // ended the run (kill, quit, end of input), whose run-time error the host should not report.
  void begin_run();
  bool end_run();
  bool running() const { return running_; }
  // Stops the run at its next statement and reads commands there, as a breakpoint would
  // (Ctrl-C in `simit debug`). Async-signal-safe: it only stores atomics.
  void request_pause() {
    pause_requested_.store(true, std::memory_order_relaxed);
    trap_.install(this);
  }
  bool quit_requested() const { return quit_; }

  // --- The structured interface -------------------------------------------------------------
  // A front end that takes the stops itself: stopped() is called on the running thread at
  // each stop instead of the command loop; it inspects through the calls below and returns
  // after resume() or kill() (returning without either continues). service() is called at
  // the next statement after request_service(), for changes that must not race the run.
  class StopHandler {
   public:
    virtual ~StopHandler() = default;
    virtual void stopped(const StopInfo& stop) = 0;
    virtual void service() = 0;
  };
  void set_stop_handler(StopHandler* handler) { handler_ = handler; }
  // Async-signal-safe, as request_pause().
  void request_service() {
    service_requested_.store(true, std::memory_order_relaxed);
    trap_.install(this);
  }
  // Stop at the run's first statement (reason Entry); before begin_run().
  void stop_at_entry() { entry_pending_ = true; }

  BreakpointResult add_breakpoint(const BreakpointRequest& request);
  void delete_breakpoint(int number);
  bool stopped() const { return stopped_; }
  // While stopped: the frames, innermost first; the variables of frame `level`; the globals
  // (externs and constants); an expression's value text in frame `level`.
  std::vector<FrameInfo> frames() const;
  std::vector<VariableInfo> locals(int level) const;
  std::vector<VariableInfo> globals() const;
  // An expression's value in frame `level` and its text as `print` shows it (a front end
  // shows the parts of the value); nullopt with `why`.
  struct Evaluated {
    interp::Value value;
    std::string text;
  };
  std::optional<Evaluated> evaluate_value(const std::string& text, int level,
                                          std::string& why) const;
  std::optional<std::string> evaluate(const std::string& text, int level, std::string& why) const {
    std::optional<Evaluated> e = evaluate_value(text, level, why);
    return e ? std::optional<std::string>(std::move(e->text)) : std::nullopt;
  }
  enum class Resume { Continue, StepIn, StepOver, StepOut };
  // While stopped: how the run goes on once stopped() returns; false with `why` when it
  // cannot (StepOut from the outermost frame).
  bool resume(Resume how, int level, std::string& why);
  void kill() { killed_ = true; }

  void before_statement(const frontend::ast::Stmt& stmt, const frontend::ast::FuncDecl& func,
                        int depth, const interp::Interpreter& interpreter) override;
  void after_statement(const frontend::ast::Stmt& stmt, const frontend::ast::FuncDecl& func,
                       int depth, const interp::Interpreter& interpreter) override;

 private:
  struct Breakpoint;
  struct Display {
    int number = 0;
    std::string text;
  };
  // Where the run is stopped.
  struct Event {
    const frontend::ast::Stmt* stmt = nullptr;
    const frontend::ast::FuncDecl* func = nullptr;
    int depth = 0;
    bool after = false;  // after_statement: the statement has run
    const interp::Interpreter* in = nullptr;
  };
  enum class Action { None, Resume, Run, Quit };
  enum class Mode { Continue, Step, Next, Finish };

  // debugger.cpp: commands
  Action execute(const std::string& line, std::string& run_args);
  Action dispatch(const std::string& cmd, const std::string& arg, std::string& run_args);
  void cmd_break(const std::string& arg, bool temporary);
  void cmd_watch(const std::string& arg);
  void cmd_delete(const std::string& arg);
  void cmd_info(const std::string& arg);
  void cmd_list(const std::string& arg);
  void cmd_print(const std::string& arg);
  void cmd_display(const std::string& arg);
  void cmd_frame_move(int delta, const std::string& arg, bool absolute);
  Action cmd_resume(Mode mode, const std::string& arg);
  void help() const;
  bool need_stop(const char* what) const;
  void error(const std::string& message) const;

  // debugger_breaks.cpp: finding statements, resolving breakpoints against a program
  struct Location {
    const frontend::ast::Stmt* stmt = nullptr;
    const frontend::ast::FuncDecl* func = nullptr;
  };
  Location statement_at_line(const frontend::ast::Program& program, int compiled_line) const;
  bool resolve(Breakpoint& b, const frontend::ast::Program& program, std::string& why) const;
  bool resolve_watch(Breakpoint& b, const interp::Interpreter& in, std::string& why) const;
  void attach(const interp::Interpreter& in);
  std::optional<int> parse_line_spec(const std::string& spec, std::string& why) const;
  std::string where_text(int compiled_line) const;

  // debugger_stops.cpp: hook events, stepping, stop reports
  bool step_done(const Event& e);
  std::string breakpoint_hit(const Event& e);
  std::string watch_changes(const Event& e);
  std::string nan_written(const Event& e);
  void stop(const Event& e, const StopInfo& info);
  void resumed(const Event& e);  // after a stop: what the resumed run needs
  StopInfo::Reason hit_reason_ = StopInfo::Reason::Breakpoint;  // of breakpoint_hit's stop
  int hit_number_ = 0;
  void update_hook();
  void print_stop_location(const std::string& reason);
  std::string frame_line(int level, bool element_note) const;
  std::string map_line(int level) const;
  int frame_compiled_line(int level) const;
  uint32_t frame_offset(int level) const;
  void show_source_line(int compiled_line) const;
  const frontend::SourceFile* source() const;  // the text stops and listings show
  void show_displays();

  std::ostream& out_;
  std::ostream& err_;
  LineSource lines_;
  interp::Trap trap_;
  std::atomic<bool> pause_requested_{false};
  std::atomic<bool> service_requested_{false};
  StopHandler* handler_ = nullptr;
  bool entry_pending_ = false;
  const frontend::ast::Program* program_ = nullptr;
  LineMap map_;

  std::vector<std::unique_ptr<Breakpoint>> breakpoints_;
  int next_number_ = 1;
  std::vector<Display> displays_;
  int next_display_ = 1;
  std::string last_command_;  // an empty line repeats next, step and list

  // The run.
  bool running_ = false;
  bool killed_ = false;
  bool quit_ = false;
  const interp::Interpreter* attached_ = nullptr;  // breakpoints are resolved for it
  std::vector<int> warned_;                        // breakpoints this run ignores, reported once
  std::unordered_map<const frontend::ast::Stmt*, std::vector<Breakpoint*>> at_stmt_;
  Mode mode_ = Mode::Continue;
  int mode_depth_ = 0;
  uint64_t mode_activation_ = 0;
  int repeat_ = 0;  // `next 3`: stops still to skip

  // The stop.
  bool stopped_ = false;
  Event event_;
  int selected_ = 0;               // frame level chosen by up / down / frame
  uint64_t shown_activation_ = 0;  // of the frame the last stop reported
  int list_next_ = 0;  // compiled line a bare `list` continues from (0: around the stop)
};

}  // namespace simit::repl
