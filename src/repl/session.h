// The REPL's state, with no terminal code: accumulated declarations (as source text),
// variables kept as values between inputs, a bound scene, and the `:` commands. The
// terminal front end (repl/, through simit/repl.h) feeds it lines; tests feed it strings.
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "api/engine.h"
#include "debugger.h"
#include "frontend/frontend.h"
#include "interp/value.h"
#include "line_map.h"
#include "scene_data.h"

namespace simit::repl {

// Settings changed with `:set NAME VALUE`.
struct SessionOptions {
  bool float32 = false;       // round every float to binary32 (scenes are reloaded)
  bool check_finite = false;  // stop at the first NaN or infinity
  int print_limit = 20;       // elements `:print SET.FIELD` lists before summarising
  // What runs the inputs (`:set executor interpreter|jit`). Each input runs once: the JIT
  // compiles a site at its first execution (threshold 0), not eagerly by set size.
  ExecutorChoice executor = ExecutorChoice{.threshold = 0, .eager = false};
};

class Session {
 public:
  // Results and values go to `out`; diagnostics and run-time errors to `err`.
  Session(std::ostream& out, std::ostream& err);
  ~Session();

  // Feeds one line. An incomplete input (an open block or bracket) is kept until a later
  // line completes it. Returns false once the session has been asked to quit.
  bool feed_line(const std::string& line);
  // True while a multi-line input is waiting for more lines (the prompt changes).
  bool pending() const { return !buffer_.empty(); }
  bool quit_requested() const { return quit_; }

  // Candidates for tab completion of `prefix`: commands (when it starts with ':'),
  // declared names, persistent variables, intrinsics, and `set.field` after a set name.
  std::vector<std::string> completions(const std::string& prefix) const;

  // Whether `text` is a complete input: blocks closed by `end`, brackets closed.
  static bool is_complete(const std::string& text);

  // `:scene` reads scene files through this loader (ReplSession supplies load_scene).
  void set_scene_loader(SceneLoader loader) { scene_loader_ = std::move(loader); }
  // Where the debugger reads its commands while a run is stopped (the terminal or stdin);
  // without one, a stop ends the run.
  void set_line_source(Debugger::LineSource source) { line_source_ = std::move(source); }
  const SessionOptions& options() const { return options_; }
  // Stops the computation running now at its next statement (async-signal-safe: Ctrl-C).
  void interrupt() { debugger_.trap().request_interrupt(); }
  // Drops a multi-line input being typed (Ctrl-C at the prompt).
  void cancel_pending() { buffer_.clear(); }

 private:
  struct Var {
    std::string type;  // as the checker prints it
    interp::Value value;
  };

  // session.cpp: inputs, compilation, runs
  void handle(const std::string& input);
  void declarations(const std::string& input);
  void statements(const std::string& input, bool expression, bool type_only);
  bool load(const std::string& path, std::string& text);
  std::string program_text() const;
  std::unique_ptr<frontend::Compilation> compile(const std::string& prefix,
                                                 const std::string& input,
                                                 const std::string& suffix, int& input_offset);
  void report(const frontend::Compilation& c, int input_offset);
  void report_runtime(const interp::RuntimeError& e, int input_offset);
  std::string location(const frontend::SourceSpan& span, int input_offset) const;
  std::vector<LineSegment> segments(const frontend::SourceFile& file, int input_offset) const;
  api::EngineOptions run_options();
  // Runs `body` (which runs `c`) under the debugger; reports its run-time error. False when
  // the run did not complete.
  bool debug_run(const frontend::Compilation& c, int input_offset,
                 const std::function<void()>& body);
  // The program alone (files and declarations), for breakpoints set between runs: compiled
  // again when declarations change, and given back to the debugger after each run.
  void refresh_program();
  void restore_program();
  void bind_scene(api::Engine& engine, const frontend::ast::Program& program);
  void bind_scene_tensors(api::Engine& engine, const frontend::ast::Program& program);
  void keep_scene_tensors(const api::Engine& engine, const frontend::ast::Program& program);
  // Runs `func` (no parameters) of `c` `times` times on the shared `:run` engine; prints its
  // results after each run.
  void run_function(const frontend::Compilation& c, const std::string& name, int times);

  // commands.cpp: the `:` commands
  void command(const std::string& line);
  void help(const std::string& topic);
  void load_files(const std::string& cmd, const std::string& arg);
  void scene(const std::string& path);
  void set_option(const std::string& arg);
  void time_statement(const std::string& arg);
  void run_command(const std::string& arg);
  void jit_command();

  // inspect.cpp: :sets, :fields, :print over the bound scene
  void list_sets();
  void list_fields(const std::string& set_name);
  void print_field(const std::string& arg);
  const runtime::Set* bound_set(const std::string& name) const;
  std::string field_type(const std::string& set_name, const runtime::Field& f);
  std::vector<std::string> set_names() const;

  std::ostream& out_;
  std::ostream& err_;
  std::string buffer_;              // lines of an incomplete input
  std::vector<std::string> files_;  // loaded with :load, in order
  std::vector<std::string> file_texts_;
  std::string decls_;                // declarations entered at the prompt
  std::map<std::string, Var> vars_;  // persistent variables
  std::vector<std::string> names_;   // declared names (for completion)
  bool quit_ = false;
  int counter_ = 0;
  SessionOptions options_;
  SceneLoader scene_loader_;
  std::optional<SceneData> scene_;
  Debugger::LineSource line_source_;
  Debugger debugger_;
  std::unique_ptr<frontend::Compilation> program_;  // see refresh_program
  // The engine `:run` commands share while the program text, the scene and the options stay
  // the same: what the JIT compiled and the matrix patterns carry over from one `:run` to
  // the next. A run that fails drops it.
  struct RunEngine {
    std::string key;
    std::unique_ptr<frontend::Compilation> program;
    std::unique_ptr<api::Engine> engine;
  };
  RunEngine run_;
  // Before the scene changes: the engine holds the scene's sets.
  void drop_run_engine() { run_ = RunEngine{}; }
};

}  // namespace simit::repl
