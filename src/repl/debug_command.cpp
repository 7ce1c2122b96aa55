// `simit debug`: a command loop around repl::Debugger that runs scenes and functions.
#include "simit/debug.h"

#include <unistd.h>

#include <csignal>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <sstream>
#include <vector>

#include "api/compiled_program.h"
#include "commands/run_command.h"
#include "debugger.h"
#include "scene/scene_sets.h"
#include "sigint.h"
#include "simit/scene.h"

namespace simit::tools {

namespace {

namespace fs = std::filesystem;

repl::Debugger* g_debugger = nullptr;  // what SIGINT pauses while a run goes on

extern "C" void interrupt_run(int) {
  if (g_debugger) g_debugger->request_pause();
}

// Ctrl-C during a run pauses it at its next statement, where the debugger reads commands
// (`continue` goes on, `kill` ends the run), as gdb does.
class InterruptScope {
 public:
  explicit InterruptScope(repl::Debugger& debugger)
      : handler_((g_debugger = &debugger, interrupt_run)) {}
  ~InterruptScope() { g_debugger = nullptr; }
  InterruptScope(const InterruptScope&) = delete;
  InterruptScope& operator=(const InterruptScope&) = delete;

 private:
  repl::SigintScope handler_;
};

constexpr int kNotStarted = -1;  // `run` with arguments that do not fit: nothing ran

bool is_scene(const std::string& file) { return file.ends_with(".toml"); }

// `FUNC ARGS...` with arguments that may hold spaces inside brackets or quotes.
std::vector<std::string> split_args(const std::string& text) {
  std::vector<std::string> out;
  std::string cur;
  int depth = 0;
  bool quoted = false;
  for (char c : text) {
    if (c == '"') quoted = !quoted;
    if (!quoted && (c == '[' || c == '(' || c == '<')) ++depth;
    if (!quoted && (c == ']' || c == ')' || c == '>')) --depth;
    if (!quoted && depth <= 0 && (c == ' ' || c == '\t')) {
      if (!cur.empty()) out.push_back(cur);
      cur.clear();
      continue;
    }
    cur += c;
  }
  if (!cur.empty()) out.push_back(cur);
  return out;
}

class DebugSession {
 public:
  DebugSession(const DebugOptions& options, std::istream& in, std::ostream& out, std::ostream& err)
      : options_(options),
        in_(in),
        out_(out),
        err_(err),
        tty_(&in == &std::cin && isatty(fileno(stdin))),
        debugger_(out, err, [this](const std::string& prompt) { return read(prompt); }) {}

  int run();

 private:
  std::optional<std::string> read(const std::string& prompt) {
    if (tty_) out_ << prompt << std::flush;
    std::string line;
    if (!std::getline(in_, line)) {
      if (tty_) out_ << "\n";
      return std::nullopt;
    }
    if (options_.echo && !tty_) out_ << prompt << line << "\n";
    return line;
  }
  // Reads the scene or compiles the program, once for every run; false after reporting why.
  bool open();
  void start(const std::string& args);
  int run_scene_frames(const std::string& args, std::ostream& errors);
  int run_call(const std::string& args, std::ostream& errors);

  const DebugOptions& options_;
  std::istream& in_;
  std::ostream& out_;
  std::ostream& err_;
  bool tty_;
  repl::Debugger debugger_;
  scene::SceneOptions scene_options_;
  std::unique_ptr<scene::Scene> scene_;                  // a .toml file
  std::shared_ptr<const api::CompiledProgram> program_;  // a .sim file
};

bool DebugSession::open() {
  if (is_scene(options_.file)) {
    scene_options_.file = options_.file;
    scene_options_.float32 = options_.float32;
    scene_options_.quiet = true;
    scene_options_.finite_check = false;  // `break on nan` is the debugger's way to find one
    scene_ = scene::SceneAccess::open(scene_options_, &debugger_.trap(), err_);
    if (!scene_) return false;
    debugger_.set_program(&scene::SceneAccess::program(*scene_),
                          {{1, fs::path(scene_->program_path()).filename().string(), 1}});
    return true;
  }
  program_ = api::CompiledProgram::from_file(options_.file);
  if (!program_->ok()) {
    err_ << program_->compilation()->diagnostics.render_all();
    return false;
  }
  debugger_.set_program(&program_->program(),
                        {{1, fs::path(options_.file).filename().string(), 1}});
  return true;
}

int DebugSession::run() {
  if (!open()) return 1;
  if (tty_)
    out_ << "Debugging " << options_.file << ". 'help' lists the commands, 'run' starts "
         << (is_scene(options_.file) ? "the scene ('run FRAMES')"
                                     : "a function ('run FUNC ARGS...')")
         << ".\n";
  std::string args;
  while (!debugger_.quit_requested()) {
    std::optional<std::string> line = read(repl::Debugger::kPrompt);
    if (!line) break;
    repl::Debugger::Outcome outcome = debugger_.command(*line, args);
    if (outcome == repl::Debugger::Outcome::Quit) break;
    if (outcome == repl::Debugger::Outcome::Run) start(args);
  }
  return 0;
}

void DebugSession::start(const std::string& args) {
  std::ostringstream errors;  // a run the debugger ended reports no error
  int rc = 0;
  {
    InterruptScope interrupts(debugger_);
    debugger_.begin_run();
    rc = is_scene(options_.file) ? run_scene_frames(args, errors) : run_call(args, errors);
  }
  if (debugger_.end_run()) {
    out_ << "[run ended by the debugger]\n";
    return;
  }
  out_.flush();
  err_ << errors.str() << std::flush;
  if (rc == kNotStarted) return;
  out_ << (rc == 0 ? "[program exited normally]\n" : "[program stopped with an error]\n");
}

int DebugSession::run_scene_frames(const std::string& args, std::ostream& errors) {
  int frames = -1;  // the scene's
  if (!args.empty()) {
    std::vector<std::string> words = split_args(args);
    char* end = nullptr;
    long count = words.size() == 1 ? std::strtol(words[0].c_str(), &end, 10) : -1;
    if (count < 0 || !end || *end) {
      errors << "run: a scene takes the number of frames to run, e.g. 'run 2'\n";
      return kNotStarted;
    }
    frames = static_cast<int>(count);
  }
  return scene_->run(out_, errors, frames);
}

int DebugSession::run_call(const std::string& args, std::ostream& errors) {
  std::vector<std::string> words = split_args(args);
  if (words.empty()) {
    errors << "run: a .sim file needs the function to call: run FUNC ARGS...\n";
    return kNotStarted;
  }
  RunOptions ro;
  ro.file = options_.file;
  ro.func = words[0];
  ro.args.assign(words.begin() + 1, words.end());
  ro.float32 = options_.float32;
  return run_function(ro, RunHooks{&debugger_.trap(), program_}, out_, errors);
}

}  // namespace

int run_debug(const DebugOptions& options, std::istream& in, std::ostream& out, std::ostream& err) {
  DebugSession session(options, in, out, err);
  return session.run();
}

}  // namespace simit::tools
