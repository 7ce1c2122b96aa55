// The step debugger's structured interface (debugger.h): breakpoints asked for as data,
// frames, variables and values at a stop, and resuming, for front ends other than gdb's
// command loop (the Debug Adapter Protocol server). The terminal's commands share the same
// resolution, stepping and evaluation.
#include <algorithm>
#include <cctype>

#include "debug_values.h"
#include "debugger.h"
#include "debugger_breakpoint.h"
#include "frontend/debug_expr.h"
#include "interp/interpreter.h"

namespace simit::repl {

namespace ast = frontend::ast;

namespace {

// "N", "== N", "= N", ">= N", "> N", "% N" into the breakpoint's hit test.
bool parse_hit_condition(const std::string& text, char& hit_op, int& hit_n, std::string& why) {
  std::string t;
  for (char c : text)
    if (!std::isspace(static_cast<unsigned char>(c))) t += c;
  size_t digits = t.find_first_of("0123456789");
  const std::string op = t.substr(0, digits == std::string::npos ? t.size() : digits);
  const std::string number = digits == std::string::npos ? "" : t.substr(digits);
  const bool numeric = !number.empty() && number.size() <= 9 &&
                       std::all_of(number.begin(), number.end(), [](char c) {
                         return std::isdigit(static_cast<unsigned char>(c));
                       });
  if (!numeric || (op != "" && op != "==" && op != "=" && op != ">=" && op != ">" && op != "%")) {
    why = "the hit condition '" + text + "' is not N, == N, >= N, > N or % N";
    return false;
  }
  hit_n = std::stoi(number);
  hit_op = op == ">=" ? 'g' : op == ">" ? '>' : op == "%" ? '%' : '=';
  return true;
}

}  // namespace

BreakpointResult Debugger::add_breakpoint(const BreakpointRequest& r) {
  using Kind = BreakpointRequest::Kind;
  BreakpointResult out;
  auto b = std::make_unique<Breakpoint>();
  b->condition = r.condition;
  if (!r.hit_condition.empty() &&
      !parse_hit_condition(r.hit_condition, b->hit_op, b->hit_n, out.message))
    return out;
  if (r.kind == Kind::Nan) {
    b->kind = Breakpoint::Kind::Nan;
  } else if (!program_) {
    out.message = "no program is loaded";
    return out;
  } else if (r.kind == Kind::Watch) {
    // The terminal's parser and checks: `watch SET.FIELD[i]`.
    const size_t dot = r.watch.find('.'), open = r.watch.find('[');
    const size_t close = r.watch.find(']');
    if (dot == std::string::npos || open == std::string::npos || close != r.watch.size() - 1 ||
        open < dot || close - open - 1 == 0 || close - open - 1 > 9 ||
        !std::all_of(r.watch.begin() + static_cast<long>(open) + 1,
                     r.watch.begin() + static_cast<long>(close),
                     [](char c) { return std::isdigit(static_cast<unsigned char>(c)); })) {
      out.message = "a data breakpoint is SET.FIELD[i], e.g. verts.x[3], not '" + r.watch + "'";
      return out;
    }
    b->kind = Breakpoint::Kind::Watch;
    b->set_name = r.watch.substr(0, dot);
    b->field_name = r.watch.substr(dot + 1, open - dot - 1);
    b->index = std::stoi(r.watch.substr(open + 1, close - open - 1));
  } else if (r.kind == Kind::Function) {
    b->kind = Breakpoint::Kind::Function;
    b->func_name = r.function;
  } else {
    std::optional<int> compiled = map_.compiled_line(map_.default_file(), r.line);
    if (!compiled) {
      out.message = "no line " + std::to_string(r.line) + " in " + map_.default_file();
      return out;
    }
    b->line = *compiled;
  }
  const ast::Program& program = stopped_ ? event_.in->program() : *program_;
  if (!resolve(*b, program, out.message) || (b->kind == Breakpoint::Kind::Watch && stopped_ &&
                                             !resolve_watch(*b, *event_.in, out.message)))
    return out;
  b->number = next_number_++;
  out.verified = true;
  out.number = b->number;
  if (b->stmt) out.line = map_.place(b->stmt->span.start().line).line;
  if (b->stmt && (stopped_ || running_) && attached_) at_stmt_[b->stmt].push_back(b.get());
  breakpoints_.push_back(std::move(b));
  update_hook();
  return out;
}

void Debugger::delete_breakpoint(int number) {
  for (auto& [stmt, list] : at_stmt_)
    std::erase_if(list, [&](Breakpoint* b) { return b->number == number; });
  std::erase_if(at_stmt_, [](const auto& entry) { return entry.second.empty(); });
  std::erase_if(breakpoints_, [&](const auto& b) { return b->number == number; });
  update_hook();
}

std::vector<FrameInfo> Debugger::frames() const {
  std::vector<FrameInfo> out;
  if (!stopped_) return out;
  for (int level = 0; level < event_.in->frame_count(); ++level) {
    interp::FrameView v = event_.in->frame_view(level);
    FrameInfo f;
    f.function = v.func ? v.func->name : "?";
    if (v.map) {
      const std::string& set = v.map->assembly && v.map->assembly->target_set
                                   ? v.map->assembly->target_set->name
                                   : v.map->set->name();
      f.element = "element " + std::to_string(v.map->element) + " of " + set;
    }
    f.map = map_line(level);
    const int compiled = frame_compiled_line(level);
    const LineMap::Place place = map_.place(compiled);
    f.file = place.file;
    f.line = place.line;
    const frontend::SourceSpan span =
        level == 0 ? event_.stmt->span : event_.in->frame_view(level).position;
    f.column = span.valid() ? span.start().column : 1;
    out.push_back(std::move(f));
  }
  return out;
}

std::vector<VariableInfo> Debugger::locals(int level) const {
  std::vector<VariableInfo> out;
  if (!stopped_ || level < 0 || level >= event_.in->frame_count()) return out;
  interp::FrameView v = event_.in->frame_view(level);
  std::vector<const ast::Variable*> vars =
      frontend::visible_variables(*v.func, frame_offset(level));
  // As `info locals`: declaration order, an outer variable an inner one hides left out.
  for (size_t i = 0; i < vars.size(); ++i) {
    const ast::Variable& var = *vars[i];
    auto hides = [&](const ast::Variable* later) { return later->name == var.name; };
    if (std::any_of(vars.begin() + static_cast<long>(i) + 1, vars.end(), hides)) continue;
    if (var.kind == ast::Variable::Kind::Generic || var.kind == ast::Variable::Kind::IndexVar)
      continue;
    out.push_back({var.name, event_.in->frame_value(level, var), var.type.get()});
  }
  return out;
}

std::vector<VariableInfo> Debugger::globals() const {
  std::vector<VariableInfo> out;
  if (!stopped_) return out;
  for (const ast::Variable* g : event_.in->program().globals)
    if (g) out.push_back({g->name, event_.in->frame_value(0, *g), g->type.get()});
  return out;
}

std::optional<Debugger::Evaluated> Debugger::evaluate_value(const std::string& text, int level,
                                                            std::string& why) const {
  if (!stopped_) {
    why = "the program is not stopped";
    return std::nullopt;
  }
  const interp::Interpreter& in = *event_.in;
  interp::FrameView v = in.frame_view(level);
  try {
    frontend::DebugExpression e =
        frontend::check_debug_expression(in.program(), v.func, frame_offset(level), text);
    if (!e.ok()) {
      why = e.error;
      return std::nullopt;
    }
    interp::Value value = in.evaluate(*e.expr, level);
    std::string shown = value_text(value, e.expr->type.get());
    return Evaluated{std::move(value), std::move(shown)};
  } catch (const interp::RuntimeError& err) {
    why = err.message();
  } catch (const std::exception& err) {  // an internal failure must not end the paused run
    why = err.what();
  }
  return std::nullopt;
}

bool Debugger::resume(Resume how, int level, std::string& why) {
  if (!stopped_) {
    why = "the program is not stopped";
    return false;
  }
  const Mode mode = how == Resume::StepIn     ? Mode::Step
                    : how == Resume::StepOver ? Mode::Next
                    : how == Resume::StepOut  ? Mode::Finish
                                              : Mode::Continue;
  level = std::clamp(level, 0, event_.in->frame_count() - 1);
  if (mode == Mode::Finish && level + 1 >= event_.in->frame_count()) {
    why = "the outermost frame has no caller to step out to";
    return false;
  }
  interp::FrameView v = event_.in->frame_view(level);
  mode_ = mode;
  repeat_ = 0;
  mode_depth_ = v.depth;
  mode_activation_ = v.activation;
  return true;
}

}  // namespace simit::repl
