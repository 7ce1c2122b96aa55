// The REPL's `:` commands (unambiguous prefixes accepted) and tab completion.
#include <algorithm>
#include <chrono>
#include <optional>
#include <sstream>

#include "frontend/ast.h"
#include "frontend/intrinsics.h"
#include "input_text.h"
#include "session.h"

namespace simit::repl {
namespace {

namespace ast = frontend::ast;

struct CommandHelp {
  const char* name;
  const char* usage;
  const char* text;
};

const CommandHelp kCommands[] = {
    {"help", ":help [topic]", "this text, or help on one command"},
    {"load", ":load FILE.sim", "add the declarations of a file"},
    {"reload", ":reload", "read the loaded files (and the scene) again"},
    {"scene", ":scene FILE.toml", "load a scene's program and bind its sets and tensors"},
    {"type", ":type EXPR", "the type of an expression"},
    {"sets", ":sets", "the extern sets: sizes, element types, fields"},
    {"fields", ":fields SET", "each field of a set: type, min, max, NaN/Inf count"},
    {"print", ":print SET.FIELD[i]", "one element's field value (or a whole field)"},
    {"time", ":time STMT", "run a statement and print how long it took"},
    {"run", ":run FUNC [N]", "run a function without parameters N times (default 1)"},
    {"set", ":set [OPTION VALUE]",
     "float32 on|off, check_finite on|off, print_limit N, executor interpreter|jit|gpu, "
     "threads N|all; alone, the settings"},
    {"jit", ":jit", "what the JIT compiled for :run (executor jit): site, compile ms, calls, ms"},
    {"reset", ":reset", "forget every declaration, variable and scene"},
    {"quit", ":quit", "leave (Ctrl-D too)"},
};

// The intrinsics, from the frontend's own list, and the print and error statements.
const char* const kIntrinsics[] = {
#define SIMIT_INTRINSIC_NAME(id, name) name,
    SIMIT_INTRINSICS(SIMIT_INTRINSIC_NAME)
#undef SIMIT_INTRINSIC_NAME
        "print",
    "println", "error"};

const char* const kHelpIntro =
    "Enter declarations (element, extern, func, const) or statements; an expression without a\n"
    "trailing ';' prints its value and type. Variables assigned at the prompt persist.\n"
    "Ctrl-C stops a running computation; the session keeps its state.\n"
    "The debugger's commands work here with a ':' (:break FUNC|FILE:LINE [if COND],\n"
    ":tbreak, :watch SET.FIELD[i], :break on nan, :delete [N], :info breakpoints,\n"
    ":display EXPR, :list); a run that stops reads gdb commands (help lists them).\n"
    "Commands (unambiguous prefixes work):\n";

bool parse_switch(const std::string& v, bool& out) {
  if (v == "on" || v == "true" || v == "1") return out = true, true;
  if (v == "off" || v == "false" || v == "0") return out = false, true;
  return false;
}

}  // namespace

void Session::command(const std::string& line) {
  size_t sp = line.find_first_of(" \t");
  std::string word = line.substr(1, sp == std::string::npos ? std::string::npos : sp - 1);
  std::string arg = sp == std::string::npos ? "" : trim(line.substr(sp));
  std::vector<std::string> matches;
  for (const CommandHelp& c : kCommands) {
    if (word == c.name) {
      matches = {c.name};
      break;
    }
    if (!word.empty() && std::string(c.name).starts_with(word)) matches.push_back(c.name);
  }
  if (matches.empty() && Debugger::is_command(word)) {
    // :break, :watch, :delete, :info, :display, :list: the debugger's, set between runs.
    std::string run_args;
    Debugger::Outcome o = debugger_.command(line.substr(1), run_args);
    if (o == Debugger::Outcome::Run)
      err_ << "start a run with a statement or :run FUNC [N]\n";
    else if (o == Debugger::Outcome::Quit)
      quit_ = true;
    return;
  }
  if (matches.empty()) {
    err_ << "unknown command ':" << word << "' (:help lists the commands)\n";
    return;
  }
  if (matches.size() > 1) {
    err_ << "ambiguous command ':" << word << "': could be";
    for (const auto& m : matches) err_ << " :" << m;
    err_ << "\n";
    return;
  }
  const std::string& cmd = matches[0];
  if (cmd == "quit") {
    quit_ = true;
  } else if (cmd == "help") {
    help(arg);
  } else if (cmd == "reset") {
    files_.clear();
    file_texts_.clear();
    decls_.clear();
    vars_.clear();
    names_.clear();
    drop_run_engine();
    scene_.reset();
    refresh_program();
  } else if (cmd == "type") {
    if (arg.empty())
      err_ << ":type needs an expression\n";
    else
      statements(arg, true, true);
  } else if (cmd == "load" || cmd == "reload") {
    load_files(cmd, arg);
  } else if (cmd == "scene") {
    scene(arg);
  } else if (cmd == "sets") {
    list_sets();
  } else if (cmd == "fields") {
    list_fields(arg);
  } else if (cmd == "print") {
    print_field(arg);
  } else if (cmd == "time") {
    time_statement(arg);
  } else if (cmd == "run") {
    run_command(arg);
  } else if (cmd == "set") {
    set_option(arg);
  } else if (cmd == "jit") {
    jit_command();
  }
}

void Session::help(const std::string& topic) {
  auto line = [&](const CommandHelp& c) {
    std::string usage = c.usage;
    out_ << "  " << usage << std::string(usage.size() < 22 ? 22 - usage.size() : 1, ' ') << c.text
         << "\n";
  };
  if (topic.empty()) {
    out_ << kHelpIntro;
    for (const CommandHelp& c : kCommands) line(c);
    return;
  }
  std::string t = topic[0] == ':' ? topic.substr(1) : topic;
  for (const CommandHelp& c : kCommands)
    if (std::string(c.name).starts_with(t)) line(c);
  if (std::none_of(std::begin(kCommands), std::end(kCommands),
                   [&](const CommandHelp& c) { return std::string(c.name).starts_with(t); }))
    out_ << "no help on '" << topic << "'\n";
}

void Session::load_files(const std::string& cmd, const std::string& arg) {
  std::vector<std::string> files = files_;
  if (cmd == "load") {
    if (arg.empty()) {
      err_ << ":load needs a file name\n";
      return;
    }
    files.push_back(arg);
  }
  std::vector<std::string> texts;
  for (const auto& path : files) {
    std::string text;
    if (!load(path, text)) return;
    texts.push_back(text);
  }
  std::swap(files, files_);
  std::swap(texts, file_texts_);
  int offset = 0;
  auto c = compile("", "", "", offset);
  if (!c->ok()) {
    err_ << c->diagnostics.render_all();
    std::swap(files, files_);
    std::swap(texts, file_texts_);
    return;
  }
  declarations("");  // refreshes the names and the program
  if (cmd == "reload" && scene_) {
    std::string path = scene_->path;
    drop_run_engine();
    scene_.reset();
    scene(path);
  }
  out_ << (cmd == "load" ? "loaded " + arg
                         : "reloaded " + std::to_string(files_.size()) + " file(s)")
       << "\n";
}

// A scene brings its program (loaded once) and binds its sets and tensors to every run.
void Session::scene(const std::string& path) {
  if (path.empty()) {
    err_ << ":scene needs a scene file (.toml)\n";
    return;
  }
  if (!scene_loader_) {
    err_ << ":scene: this REPL cannot read scene files\n";
    return;
  }
  std::optional<SceneData> data = scene_loader_(path, options_.float32, err_);
  if (!data) return;
  if (std::find(files_.begin(), files_.end(), data->program_path) == files_.end()) {
    load_files("load", data->program_path);
    if (std::find(files_.begin(), files_.end(), data->program_path) == files_.end()) return;
  }
  drop_run_engine();
  scene_ = std::move(data);
  out_ << "scene " << path << ":";
  for (const auto& [name, set] : scene_->sets) out_ << " " << name << " (" << set->size() << ")";
  out_ << "\n";
  if (!scene_->init.empty())
    out_ << "  init is '" << scene_->init << "' (:run " << scene_->init << "), step is '"
         << scene_->step << "' (:run " << scene_->step << " N)\n";
}

void Session::set_option(const std::string& arg) {
  std::vector<std::string> w = split_blanks(arg);
  if (w.empty()) {  // the settings, as `:set` takes them
    out_ << "float32 " << (options_.float32 ? "on" : "off") << "\ncheck_finite "
         << (options_.check_finite ? "on" : "off") << "\nprint_limit " << options_.print_limit
         << "\nexecutor " << executor_name(options_.executor.kind) << "\nthreads "
         << options_.executor.threads << "\n";
    return;
  }
  if (w.size() != 2) {
    err_ << ":set needs an option and a value (float32 on|off, check_finite on|off, "
            "print_limit N, executor interpreter|jit|gpu, threads N|all)\n";
    return;
  }
  bool flag = false;
  if (w[0] == "float32" || w[0] == "check_finite") {
    if (!parse_switch(w[1], flag)) {
      err_ << ":set " << w[0] << ": expected on or off, not '" << w[1] << "'\n";
      return;
    }
    if (w[0] == "check_finite") {
      options_.check_finite = flag;
    } else if (options_.float32 != flag) {
      options_.float32 = flag;
      if (scene_) {
        out_ << "float32 " << (flag ? "on" : "off")
             << ": reloading the scene (fields start over)\n";
        std::string path = scene_->path;
        drop_run_engine();
        scene_.reset();
        scene(path);
      }
    }
  } else if (w[0] == "print_limit") {
    try {
      options_.print_limit = std::max(1, std::stoi(w[1]));
    } catch (const std::exception&) {
      err_ << ":set print_limit: expected a whole number, not '" << w[1] << "'\n";
    }
  } else if (w[0] == "executor" || w[0] == "backend") {  // backend: its former name
    // Parsed and checked here, once: a bad or unbuilt choice keeps the current one.
    std::string error;
    std::optional<ExecutorKind> kind = parse_executor_kind(w[1], error);
    ExecutorChoice choice = options_.executor;
    if (kind) choice.kind = *kind;
    if (kind) error = executor_unavailable(choice);
    if (!error.empty()) {
      err_ << ":set " << w[0] << ": " << error << "\n";
      return;
    }
    options_.executor = choice;
  } else if (w[0] == "threads") {
    // The JIT's threads; the interpreter runs serially whatever the count.
    std::string error;
    std::optional<int> n = parse_threads(w[1], error);
    if (!n) {
      err_ << ":set threads: " << error << "\n";
      return;
    }
    options_.executor.threads = *n;
  } else {
    err_ << ":set: no option '" << w[0]
         << "' (float32, check_finite, print_limit, executor, threads)\n";
    return;
  }
}

void Session::time_statement(const std::string& arg) {
  if (arg.empty()) {
    err_ << ":time needs a statement\n";
    return;
  }
  const auto t0 = std::chrono::steady_clock::now();
  handle(arg);
  const double ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  std::ostringstream s;
  s.precision(3);
  s << std::fixed << "time: " << ms << " ms\n";
  out_ << s.str();
}

void Session::run_command(const std::string& arg) {
  std::vector<std::string> w = split_blanks(arg);
  if (w.empty() || w.size() > 2) {
    err_ << ":run needs a function name and an optional count\n";
    return;
  }
  int times = 1;
  if (w.size() == 2) {
    try {
      times = std::stoi(w[1]);
    } catch (const std::exception&) {
      times = 0;
    }
    if (times < 1) {
      err_ << ":run: the count must be a whole number >= 1, not '" << w[1] << "'\n";
      return;
    }
  }
  int offset = 0;
  auto c = compile("", "", "", offset);
  if (!c->ok()) {
    report(*c, offset);
    return;
  }
  std::string key = c->source->text();
  key += std::string(1, '\0') + (options_.float32 ? " float32" : "") +
         (options_.check_finite ? " check_finite" : "") + " " +
         executor_name(options_.executor.kind) + " threads " +
         std::to_string(options_.executor.threads);
  if (key != run_.key || !run_.engine) run_ = RunEngine{std::move(key), std::move(c), nullptr};
  run_function(*run_.program, w[0], times);
}

void Session::jit_command() {
  if (!run_.engine || !compiles(options_.executor.kind)) {
    out_ << "no traces: :set executor jit, then :run a function\n";
    return;
  }
  run_.engine->print_jit_stats(out_);
}

std::vector<std::string> Session::completions(const std::string& prefix) const {
  std::vector<std::string> out;
  if (!prefix.empty() && prefix[0] == ':') {
    for (const CommandHelp& c : kCommands)
      if ((":" + std::string(c.name)).starts_with(prefix)) out.push_back(":" + std::string(c.name));
    return out;
  }
  auto add = [&](const std::string& n) {
    if (n.starts_with(prefix) && !n.starts_with("__")) out.push_back(n);
  };
  size_t dot = prefix.rfind('.');
  if (dot != std::string::npos) {
    // `verts.x`: the fields of a bound set.
    if (const runtime::Set* s = bound_set(prefix.substr(0, dot)))
      for (int f = 0; f < s->field_count(); ++f)
        add(prefix.substr(0, dot + 1) + s->field(f).name());
    return out;
  }
  for (const auto& n : names_) add(n);
  for (const auto& [n, v] : vars_) add(n);
  for (const auto& n : set_names()) add(n);
  for (const char* n : kIntrinsics) add(n);
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

}  // namespace simit::repl
