// The step debugger's commands (gdb's names, aliases and unique prefixes).
#include "debugger.h"

#include <algorithm>
#include <cctype>
#include <cstring>
#include <optional>
#include <sstream>

#include "debug_values.h"
#include "debugger_breakpoint.h"
#include "frontend/diagnostics.h"
#include "interp/interpreter.h"

namespace simit::repl {

namespace ast = frontend::ast;

namespace {

const char* const kCommands[] = {"backtrace", "break", "continue", "delete", "display", "down",
                                 "finish",    "frame", "help",     "info",   "kill",    "list",
                                 "next",      "print", "quit",     "run",    "step",    "tbreak",
                                 "undisplay", "up",    "watch"};

const std::pair<const char*, const char*> kAliases[] = {
    {"b", "break"},        {"br", "break"}, {"bt", "backtrace"}, {"c", "continue"},
    {"cont", "continue"},  {"d", "delete"}, {"f", "frame"},      {"h", "help"},
    {"i", "info"},         {"k", "kill"},   {"l", "list"},       {"n", "next"},
    {"p", "print"},        {"q", "quit"},   {"r", "run"},        {"s", "step"},
    {"where", "backtrace"}};

std::string trim(const std::string& s) {
  size_t b = s.find_first_not_of(" \t\r\n");
  if (b == std::string::npos) return "";
  return s.substr(b, s.find_last_not_of(" \t\r\n") - b + 1);
}

// The full name of a command word: an alias, a full name, or a unique prefix of one; "" when
// unknown, "?a b" (the candidates) when ambiguous.
std::string command_name(const std::string& word) {
  for (const auto& [alias, name] : kAliases)
    if (word == alias) return name;
  std::string found;
  for (const char* c : kCommands) {
    if (word == c) return c;
    if (!word.empty() && std::string(c).starts_with(word))
      found += (found.empty() ? "" : " ") + std::string(c);
  }
  if (found.find(' ') != std::string::npos) return "?" + found;
  return found;
}

// The commands' arguments are scanned by hand: they are user input of any length, and
// std::regex recurses once per character.
bool is_blank(char c) { return std::isspace(static_cast<unsigned char>(c)) != 0; }
bool is_word_char(char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; }

// `LOC if COND` (or `if COND`, at the stop) split into LOC and COND; nullopt without `if`.
std::optional<std::pair<std::string, std::string>> split_condition(const std::string& arg) {
  size_t loc_end = 0;
  if (!(arg.starts_with("if") && arg.size() > 2 && is_blank(arg[2]))) {
    loc_end = arg.find_first_of(" \t\r\n\v\f");
    if (loc_end == std::string::npos) return std::nullopt;
  }
  size_t i = arg.find_first_not_of(" \t\r\n\v\f", loc_end);
  if (i == std::string::npos || arg.compare(i, 2, "if") != 0) return std::nullopt;
  i += 2;
  if (i >= arg.size() || !is_blank(arg[i])) return std::nullopt;
  std::string condition = trim(arg.substr(i));
  if (condition.empty()) return std::nullopt;
  return std::make_pair(arg.substr(0, loc_end), condition);
}

struct WatchSpec {
  std::string set, field, index;
};

// SET.FIELD[i] (or SET.FIELD(i)), blanks allowed around the index.
std::optional<WatchSpec> parse_watch_spec(const std::string& arg) {
  size_t i = 0;
  auto word = [&](std::string& out) {
    size_t start = i;
    while (i < arg.size() && is_word_char(arg[i])) ++i;
    out = arg.substr(start, i - start);
    return !out.empty();
  };
  auto blanks = [&] {
    while (i < arg.size() && is_blank(arg[i])) ++i;
  };
  auto one_of = [&](const char* chars) {
    if (i >= arg.size() || arg[i] == '\0' || !std::strchr(chars, arg[i])) return false;
    ++i;
    return true;
  };
  WatchSpec w;
  if (!word(w.set) || !one_of(".") || !word(w.field)) return std::nullopt;
  blanks();
  if (!one_of("[(")) return std::nullopt;
  blanks();
  size_t start = i;
  while (i < arg.size() && std::isdigit(static_cast<unsigned char>(arg[i]))) ++i;
  w.index = arg.substr(start, i - start);
  blanks();
  if (w.index.empty() || !one_of("])") || i != arg.size()) return std::nullopt;
  return w;
}

bool positive_int(const std::string& s, int& n) {
  if (s.empty() || s.size() > 9 || !std::all_of(s.begin(), s.end(), [](char c) {
        return std::isdigit(static_cast<unsigned char>(c));
      }))
    return false;
  n = std::stoi(s);
  return true;
}

const char* kHelp =
    "Commands (gdb's names; unique prefixes and the usual one-letter aliases work):\n"
    "  run [ARGS]              start the program (simit debug: a scene takes FRAMES, a .sim\n"
    "                          file FUNC ARGS...)\n"
    "  break LOC [if COND]     stop before LOC: LINE, FILE:LINE or FUNC; COND is an expression\n"
    "                          over the locals there, in which an element compared with an int\n"
    "                          compares its index: break tet_force if t == 17\n"
    "  tbreak LOC [if COND]    the same, deleted when it stops the run\n"
    "  break on nan            stop after the first statement that writes a NaN or infinity\n"
    "  watch SET.FIELD[i]      stop after a statement that changes the field of element i\n"
    "  delete [N...]           delete breakpoints (all without N)\n"
    "  info breakpoints|locals|display\n"
    "  continue, next [N], step [N], finish, kill\n"
    "  print EXPR              an expression over locals, globals, sets and fields (det, norm\n"
    "                          and the other intrinsics; no calls of user functions); an int\n"
    "                          indexes a set: print verts.x(3)\n"
    "  display [EXPR], undisplay [N]   expressions shown at every stop\n"
    "  backtrace, up [N], down [N], frame [N]\n"
    "  list [LOC]              ten source lines (around the stop, or LOC)\n"
    "  quit\n";

}  // namespace

Debugger::Debugger(std::ostream& out, std::ostream& err, LineSource lines)
    : out_(out), err_(err), lines_(std::move(lines)) {}

Debugger::~Debugger() = default;

void Debugger::set_program(const ast::Program* program, std::vector<LineSegment> line_map) {
  program_ = program;
  if (line_map.empty()) {
    const frontend::SourceFile* file = source();
    line_map.push_back({1, file ? file->name() : "<program>", 1});
  }
  map_ = LineMap(std::move(line_map));
}

bool Debugger::is_command(const std::string& word) {
  std::string name = command_name(word);
  return !name.empty() && name[0] != '?';
}

Debugger::Outcome Debugger::command(const std::string& line, std::string& run_args) {
  switch (execute(line, run_args)) {
    case Action::Run: return Outcome::Run;
    case Action::Quit: return Outcome::Quit;
    default: return Outcome::Done;
  }
}

void Debugger::begin_run() {
  running_ = true;
  killed_ = false;
  attached_ = nullptr;
  mode_ = Mode::Continue;
  shown_activation_ = 0;
  warned_.clear();
  trap_.take_interrupt();
  pause_requested_.store(false, std::memory_order_relaxed);
  for (const auto& b : breakpoints_) {
    b->armed = true;
    b->set = nullptr;
    b->last.reset();
  }
  if (!interp::kStatementHook && !breakpoints_.empty())
    error("this build has no statement hook (SIMIT_STATEMENT_HOOK=OFF): breakpoints cannot stop");
  update_hook();
}

bool Debugger::end_run() {
  running_ = false;
  stopped_ = false;
  attached_ = nullptr;
  at_stmt_.clear();
  // The run's program and sets may be freed now; the next run resolves everything again.
  for (const auto& b : breakpoints_) {
    b->stmt = nullptr;
    b->func = nullptr;
    b->cond.reset();
    b->set = nullptr;
  }
  trap_.install(nullptr);
  bool killed = killed_;
  killed_ = false;
  return killed;
}

void Debugger::error(const std::string& message) const {
  out_.flush();
  err_ << message << "\n";
  err_.flush();
}

bool Debugger::need_stop(const char* what) const {
  if (stopped_) return true;
  error(std::string("No frame: ") + what +
        " needs a stopped program (the program is not running).");
  return false;
}

Debugger::Action Debugger::execute(const std::string& raw, std::string& run_args) {
  std::string line = trim(raw);
  if (line.starts_with("#")) return Action::None;  // a comment, as in gdb scripts
  if (line.empty()) {
    // An empty line repeats a command that moves on, as in gdb.
    if (last_command_ != "next" && last_command_ != "step" && last_command_ != "list")
      return Action::None;
    line = last_command_;
  }
  size_t sp = line.find_first_of(" \t");
  std::string word = line.substr(0, sp);
  std::string arg = sp == std::string::npos ? "" : trim(line.substr(sp));
  std::string cmd = command_name(word);
  if (cmd.empty()) {
    error("Undefined command: \"" + word + "\".  Try \"help\".");
    return Action::None;
  }
  if (cmd[0] == '?') {
    error("Ambiguous command \"" + word + "\": " + cmd.substr(1) + ".");
    return Action::None;
  }
  last_command_ = cmd == "list" ? "list" : cmd == "next" || cmd == "step" ? cmd : "";
  return dispatch(cmd, arg, run_args);
}

Debugger::Action Debugger::dispatch(const std::string& cmd, const std::string& arg,
                                    std::string& run_args) {
  if (cmd == "run") {
    if (running_) {
      error("The program is already running; 'kill' ends the run.");
      return Action::None;
    }
    run_args = arg;
    return Action::Run;
  }
  if (cmd == "quit") {
    quit_ = true;
    killed_ = running_;
    return Action::Quit;
  }
  if (cmd == "kill") {
    if (!running_) {
      error("The program is not being run.");
      return Action::None;
    }
    killed_ = true;
    return Action::Resume;
  }
  if (cmd == "continue") return cmd_resume(Mode::Continue, arg);
  if (cmd == "next") return cmd_resume(Mode::Next, arg);
  if (cmd == "step") return cmd_resume(Mode::Step, arg);
  if (cmd == "finish") return cmd_resume(Mode::Finish, arg);
  if (cmd == "break" || cmd == "tbreak")
    cmd_break(arg, cmd == "tbreak");
  else if (cmd == "watch")
    cmd_watch(arg);
  else if (cmd == "delete")
    cmd_delete(arg);
  else if (cmd == "info")
    cmd_info(arg);
  else if (cmd == "list")
    cmd_list(arg);
  else if (cmd == "print")
    cmd_print(arg);
  else if (cmd == "display")
    cmd_display(arg);
  else if (cmd == "undisplay") {
    int n = 0;
    if (arg.empty())
      displays_.clear();
    else if (!positive_int(arg, n) ||
             std::erase_if(displays_, [&](const Display& d) { return d.number == n; }) == 0)
      error("No display number " + arg + ".");
  } else if (cmd == "backtrace") {
    if (need_stop("backtrace")) {
      for (int level = 0; level < event_.in->frame_count(); ++level) {
        out_ << "#" << level << "  " << frame_line(level, false) << "\n";
        if (std::string m = map_line(level); !m.empty()) out_ << "    " << m << "\n";
      }
    }
  } else if (cmd == "up")
    cmd_frame_move(1, arg, false);
  else if (cmd == "down")
    cmd_frame_move(-1, arg, false);
  else if (cmd == "frame")
    cmd_frame_move(0, arg, true);
  else if (cmd == "help")
    help();
  return Action::None;
}

Debugger::Action Debugger::cmd_resume(Mode mode, const std::string& arg) {
  if (!running_ || !stopped_) {
    error("The program is not being run.");
    return Action::None;
  }
  int n = 1;
  if (!arg.empty() &&
      (mode == Mode::Continue || mode == Mode::Finish || !positive_int(arg, n) || n < 1)) {
    error("unexpected argument '" + arg + "'");
    return Action::None;
  }
  interp::FrameView v = event_.in->frame_view(selected_);
  if (mode == Mode::Finish) {
    if (selected_ + 1 >= event_.in->frame_count()) {
      error("\"finish\" not meaningful in the outermost frame.");
      return Action::None;
    }
    out_ << "Run till exit from #" << selected_ << "  " << frame_line(selected_, true) << "\n";
  }
  mode_ = mode;
  repeat_ = n - 1;
  mode_depth_ = v.depth;
  mode_activation_ = v.activation;
  return Action::Resume;
}

void Debugger::cmd_break(const std::string& arg, bool temporary) {
  auto b = std::make_unique<Breakpoint>();
  b->temporary = temporary;
  if (arg == "on nan") {
    for (const auto& x : breakpoints_)
      if (x->kind == Breakpoint::Kind::Nan) {
        x->armed = true;
        out_ << "NaN trap (breakpoint " << x->number << ") armed again.\n";
        return;
      }
    b->kind = Breakpoint::Kind::Nan;
    b->number = next_number_++;
    out_ << "Breakpoint " << b->number
         << ": stop after the first statement that writes a NaN or an infinity.\n";
    breakpoints_.push_back(std::move(b));
    update_hook();
    return;
  }
  if (!program_) {
    error("No program is loaded.");
    return;
  }
  std::string spec = arg;
  if (std::optional<std::pair<std::string, std::string>> split = split_condition(arg)) {
    spec = split->first;
    b->condition = split->second;
  }
  std::string why;
  if (spec.empty()) {
    if (!stopped_) {
      error("break needs a location: LINE, FILE:LINE or FUNC.");
      return;
    }
    b->line = frame_compiled_line(selected_);
  } else if (std::isdigit(static_cast<unsigned char>(spec[0])) ||
             spec.find(':') != std::string::npos) {
    std::optional<int> line = parse_line_spec(spec, why);
    if (!line) {
      error(why);
      return;
    }
    b->line = *line;
  } else {
    b->kind = Breakpoint::Kind::Function;
    b->func_name = spec;
  }
  // While stopped, the running program is the one the breakpoint will act in.
  const ast::Program& program = stopped_ ? event_.in->program() : *program_;
  if (!resolve(*b, program, why)) {
    error("Cannot set the breakpoint: " + why + ".");
    return;
  }
  b->number = next_number_++;
  out_ << (temporary ? "Temporary breakpoint " : "Breakpoint ") << b->number << " at "
       << b->func->name << ", " << where_text(b->stmt->span.start().line) << "\n";
  if (stopped_ && attached_) at_stmt_[b->stmt].push_back(b.get());
  breakpoints_.push_back(std::move(b));
  update_hook();
}

void Debugger::cmd_watch(const std::string& arg) {
  std::optional<WatchSpec> spec = parse_watch_spec(arg);
  if (!spec) {
    error("watch needs SET.FIELD[i], e.g. watch verts.x[3]");
    return;
  }
  if (spec->index.size() > 9) {
    error("watch: there is no element " + spec->index + " (the index is too large)");
    return;
  }
  if (!program_) {
    error("No program is loaded.");
    return;
  }
  auto b = std::make_unique<Breakpoint>();
  b->kind = Breakpoint::Kind::Watch;
  b->set_name = spec->set;
  b->field_name = spec->field;
  b->index = std::stoi(spec->index);
  std::string why;
  if (!resolve(*b, stopped_ ? event_.in->program() : *program_, why) ||
      (stopped_ && !resolve_watch(*b, *event_.in, why))) {
    error("Cannot watch " + arg + ": " + why + ".");
    return;
  }
  b->number = next_number_++;
  out_ << "Watchpoint " << b->number << ": " << b->set_name << "." << b->field_name << "["
       << b->index << "]\n";
  breakpoints_.push_back(std::move(b));
  update_hook();
}

void Debugger::cmd_delete(const std::string& arg) {
  std::vector<int> numbers;
  std::istringstream words(arg);
  for (std::string w; words >> w;) {
    int n = 0;
    if (!positive_int(w, n)) {
      error("expected breakpoint numbers but got '" + w + "'");
      return;
    }
    numbers.push_back(n);
  }
  auto gone = [&](const std::unique_ptr<Breakpoint>& b) {
    return numbers.empty() || std::find(numbers.begin(), numbers.end(), b->number) != numbers.end();
  };
  for (int n : numbers)
    if (std::none_of(breakpoints_.begin(), breakpoints_.end(),
                     [&](const auto& b) { return b->number == n; }))
      error("No breakpoint number " + std::to_string(n) + ".");
  for (auto& [stmt, list] : at_stmt_)
    std::erase_if(list, [&](Breakpoint* b) {
      return numbers.empty() ||
             std::find(numbers.begin(), numbers.end(), b->number) != numbers.end();
    });
  std::erase_if(at_stmt_, [](const auto& entry) { return entry.second.empty(); });
  std::erase_if(breakpoints_, gone);
  update_hook();
}

void Debugger::cmd_info(const std::string& arg) {
  std::string what;
  for (const char* topic : {"breakpoints", "watchpoints", "locals", "args", "display"})
    if (!arg.empty() && what.empty() && std::string(topic).starts_with(arg)) what = topic;
  if (what == "watchpoints") what = "breakpoints";
  if (what == "breakpoints") {
    if (breakpoints_.empty()) {
      out_ << "No breakpoints or watchpoints.\n";
      return;
    }
    out_ << "Num  Type        What\n";
    for (const auto& bp : breakpoints_) {
      const Breakpoint& b = *bp;
      std::string num = std::to_string(b.number);
      out_ << num << std::string(5 - std::min<size_t>(4, num.size()), ' ');
      switch (b.kind) {
        case Breakpoint::Kind::Line:
        case Breakpoint::Kind::Function:
          out_ << (b.temporary ? "tbreak      " : "breakpoint  ") << b.resolved_at << "\n";
          break;
        case Breakpoint::Kind::Watch:
          out_ << "watchpoint  " << b.set_name << "." << b.field_name << "[" << b.index << "]\n";
          break;
        case Breakpoint::Kind::Nan:
          out_ << "nan trap    the first statement that writes a NaN or an infinity"
               << (b.armed ? "" : " (fired; off until the next run)") << "\n";
          break;
      }
      if (!b.condition.empty()) out_ << "        stop only if " << b.condition << "\n";
      if (b.hits) out_ << "        hit " << b.hits << (b.hits == 1 ? " time" : " times") << "\n";
    }
  } else if (what == "locals" || what == "args") {
    if (!need_stop("info locals")) return;
    interp::FrameView v = event_.in->frame_view(selected_);
    std::vector<const ast::Variable*> vars =
        frontend::visible_variables(*v.func, frame_offset(selected_));
    // In declaration order; an outer variable that an inner one hides is not shown.
    bool any = false;
    for (size_t i = 0; i < vars.size(); ++i) {
      const ast::Variable& var = *vars[i];
      auto hides = [&](const ast::Variable* later) { return later->name == var.name; };
      if (std::any_of(vars.begin() + static_cast<long>(i) + 1, vars.end(), hides)) continue;
      if (var.kind == ast::Variable::Kind::Generic || var.kind == ast::Variable::Kind::IndexVar)
        continue;
      const interp::Value* value = event_.in->frame_value(selected_, var);
      out_ << var.name << " = " << (value ? value_text(*value, var.type.get()) : "<no value>")
           << "\n";
      any = true;
    }
    if (!any) out_ << "No locals.\n";
  } else if (what == "display") {
    if (displays_.empty()) out_ << "There are no auto-display expressions now.\n";
    for (const Display& d : displays_) out_ << d.number << ": " << d.text << "\n";
  } else {
    error("Undefined info command: \"" + arg +
          "\".  Try \"info breakpoints\", \"info locals\" or \"info display\".");
  }
}

void Debugger::cmd_list(const std::string& arg) {
  const frontend::SourceFile* file = source();
  if (!file) {
    error("No program is loaded.");
    return;
  }
  int first = 0;
  std::string why;
  if (arg.empty()) {
    if (list_next_ > 0)
      first = list_next_;
    else if (stopped_)
      first = frame_compiled_line(selected_) - 5;
    else
      first = 1;
  } else if (std::isdigit(static_cast<unsigned char>(arg[0])) ||
             arg.find(':') != std::string::npos) {
    std::optional<int> line = parse_line_spec(arg, why);
    if (!line) return error(why);
    first = *line - 5;
  } else {
    const ast::Program& program = stopped_ ? event_.in->program() : *program_;
    const ast::FuncDecl* f = program.find_func(arg);
    if (!f) return error("Function \"" + arg + "\" not defined.");
    first = f->span.start().line - 1;
  }
  first = std::max(1, first);
  if (first > file->line_count())
    return error("Line number " + std::to_string(map_.place(first).line) + " out of range.");
  int last = std::min(file->line_count(), first + 9);
  for (int l = first; l <= last; ++l)
    out_ << map_.place(l).line << "\t" << frontend::printable(file->line_text(l)) << "\n";
  list_next_ = last + 1;
}

void Debugger::cmd_print(const std::string& arg) {
  if (arg.empty()) return error("print needs an expression.");
  if (!need_stop("print")) return;
  std::string why;
  if (std::optional<std::string> text = evaluate(arg, selected_, why))
    out_ << arg << " = " << *text << "\n";
  else
    error(why);
}

void Debugger::cmd_display(const std::string& arg) {
  if (arg.empty()) {
    if (stopped_) show_displays();
    return;
  }
  Display d{next_display_++, arg};
  displays_.push_back(d);
  if (!stopped_) return;
  std::string why;
  if (std::optional<std::string> text = evaluate(arg, selected_, why))
    out_ << d.number << ": " << arg << " = " << *text << "\n";
  else
    error(why);
}

void Debugger::cmd_frame_move(int delta, const std::string& arg, bool absolute) {
  if (!need_stop(absolute ? "frame" : delta > 0 ? "up" : "down")) return;
  int n = 0;
  if (!arg.empty() && !positive_int(arg, n))
    return error("expected a number but got '" + arg + "'");
  if (arg.empty()) n = absolute ? selected_ : 1;
  int target = absolute ? n : selected_ + delta * n;
  const int count = event_.in->frame_count();
  if (absolute && target >= count) return error("No frame at level " + arg + ".");
  if (target >= count) {
    if (!absolute && selected_ == count - 1)
      return error("Initial frame selected; you cannot go up.");
    target = count - 1;
  }
  if (target < 0) {
    if (selected_ == 0) return error("Bottom (innermost) frame selected; you cannot go down.");
    target = 0;
  }
  selected_ = target;
  list_next_ = 0;
  out_ << "#" << selected_ << "  " << frame_line(selected_, true) << "\n";
  if (std::string m = map_line(selected_); !m.empty()) out_ << "    " << m << "\n";
  show_source_line(frame_compiled_line(selected_));
}

void Debugger::help() const { out_ << kHelp; }

}  // namespace simit::repl
