// The step debugger at run time: the hook's events, stepping, watchpoints, the NaN trap, and
// what a stop reports (frames, the map element a mapped call serves, source lines).
#include <cstring>

#include "debug_values.h"
#include "debugger.h"
#include "debugger_breakpoint.h"
#include "frontend/diagnostics.h"
#include "interp/interpreter.h"

namespace simit::repl {

namespace ast = frontend::ast;
using Kind = interp::Value::Kind;

namespace {

bool same_bits(const runtime::Tensor& a, const runtime::Tensor& b) {
  if (a.kind() != b.kind() || a.shape() != b.shape()) return false;
  size_t bytes = 0;
  switch (a.kind()) {
    case runtime::ComponentKind::Int: bytes = sizeof(int32_t); break;
    case runtime::ComponentKind::Float: bytes = sizeof(double); break;
    case runtime::ComponentKind::Bool: bytes = sizeof(bool); break;
    case runtime::ComponentKind::Complex: bytes = sizeof(runtime::Complex); break;
    case runtime::ComponentKind::String: return a == b;
  }
  return std::memcmp(a.floats(), b.floats(), bytes * a.size()) == 0;
}

std::string tensor_text(const runtime::Tensor& t) {
  if (t.shape().is_scalar()) return value_text(interp::Value::component(t, 0), nullptr);
  return value_text(interp::Value::of_tensor(t), nullptr);
}

std::string source_of(const frontend::SourceSpan& s) {
  return s.valid() ? s.file->text().substr(s.begin, s.end - s.begin) : "?";
}

}  // namespace

void Debugger::before_statement(const ast::Stmt& stmt, const ast::FuncDecl& func, int depth,
                                const interp::Interpreter& in) {
  if (&in != attached_) attach(in);
  Event e{&stmt, &func, depth, false, &in};
  if (service_requested_.exchange(false, std::memory_order_relaxed)) {
    if (handler_) handler_->service();
    update_hook();
  }
  if (pause_requested_.exchange(false, std::memory_order_relaxed)) {
    stop(e, {StopInfo::Reason::Pause, "Interrupted (Ctrl-C).\n", 0});
    return;
  }
  if (entry_pending_) {
    entry_pending_ = false;
    stop(e, {StopInfo::Reason::Entry, "", 0});
    return;
  }
  std::string reason = breakpoint_hit(e);
  if (!reason.empty()) {
    stop(e, {hit_reason_, reason, hit_number_});
    return;
  }
  if (step_done(e)) stop(e, {StopInfo::Reason::Step, "", 0});
}

void Debugger::after_statement(const ast::Stmt& stmt, const ast::FuncDecl& func, int depth,
                               const interp::Interpreter& in) {
  if (&in != attached_) attach(in);
  Event e{&stmt, &func, depth, true, &in};
  hit_number_ = 0;
  std::string watch = watch_changes(e);
  const int watch_number = hit_number_;
  std::string nan = nan_written(e);
  if (!watch.empty() || !nan.empty()) {
    stop(e, {watch.empty() ? StopInfo::Reason::Nan : StopInfo::Reason::Watch, watch + nan,
             watch.empty() ? hit_number_ : watch_number});
    return;
  }
  if (step_done(e)) stop(e, {StopInfo::Reason::Step, "", 0});
}

// Whether a step, next or finish ends at this event. Depths are those of the frame that was
// selected when it was asked for: `next` stays in that activation (a mapped function's next
// element is another one) until it returns; `finish` waits for the return.
bool Debugger::step_done(const Event& e) {
  bool done = false;
  switch (mode_) {
    case Mode::Continue: return false;
    case Mode::Step: done = !e.after || e.depth < mode_depth_; break;
    case Mode::Next:
      done = e.depth < mode_depth_ || (!e.after && e.depth == mode_depth_ &&
                                       e.in->frame_view(0).activation == mode_activation_);
      break;
    case Mode::Finish: done = e.depth < mode_depth_; break;
  }
  if (!done || repeat_ == 0) return done;
  // `next 3`: this stop is skipped; the next one counts from here.
  --repeat_;
  mode_depth_ = e.depth;
  mode_activation_ = e.in->frame_view(0).activation;
  return false;
}

std::string Debugger::breakpoint_hit(const Event& e) {
  if (at_stmt_.empty()) return "";
  auto it = at_stmt_.find(e.stmt);
  if (it == at_stmt_.end()) return "";
  for (Breakpoint* b : it->second) {
    hit_reason_ = b->kind == Breakpoint::Kind::Function ? StopInfo::Reason::FunctionBreakpoint
                                                        : StopInfo::Reason::Breakpoint;
    hit_number_ = b->number;
    if (b->cond) {
      try {
        interp::Value v = e.in->evaluate(*b->cond->expr, 0);
        if (!v.as_bool()) continue;
      } catch (const interp::RuntimeError& err) {
        ++b->hits;
        return "Error in testing the condition of breakpoint " + std::to_string(b->number) + ": " +
               err.message() + "\n";
      } catch (const std::exception& err) {
        ++b->hits;
        return "Error in testing the condition of breakpoint " + std::to_string(b->number) + ": " +
               err.what() + "\n";
      }
    }
    ++b->hits;
    if (!b->hit_allows()) continue;
    return std::string(b->temporary ? "Temporary breakpoint " : "Breakpoint ") +
           std::to_string(b->number) + ", ";
  }
  return "";
}

std::string Debugger::watch_changes(const Event& e) {
  (void)e;
  std::string out;
  for (const auto& bp : breakpoints_) {
    Breakpoint& b = *bp;
    if (b.kind != Breakpoint::Kind::Watch || !b.set || !b.last) continue;
    runtime::Tensor now = b.set->get(b.field, b.index);
    if (same_bits(now, *b.last)) continue;
    ++b.hits;
    if (!hit_number_) hit_number_ = b.number;
    out += "Watchpoint " + std::to_string(b.number) + ": " + b.set_name + "." + b.field_name + "[" +
           std::to_string(b.index) + "]\nOld value = " + tensor_text(*b.last) +
           "\nNew value = " + tensor_text(now) + "\n";
    b.last = std::move(now);
  }
  return out;
}

// The NaN trap: the values the statement wrote, read back (a whole variable, or the part of
// a tensor, field or map result that an assignment target names).
std::string Debugger::nan_written(const Event& e) {
  Breakpoint* trap = nullptr;
  for (const auto& bp : breakpoints_)
    if (bp->kind == Breakpoint::Kind::Nan && bp->armed) trap = bp.get();
  if (!trap) return "";
  std::vector<std::pair<std::string, interp::Value>> written;
  auto add_var = [&](const ast::Variable* v) {
    if (const interp::Value* value = v ? e.in->frame_value(0, *v) : nullptr)
      written.emplace_back(v->name, *value);
  };
  if (const auto* d = e.stmt->as<ast::VarDecl>()) add_var(d->var);
  if (const auto* a = e.stmt->as<ast::Assign>()) {
    for (size_t i = 0; i < a->targets.size(); ++i) {
      if (i < a->declares.size() && a->declares[i]) {
        add_var(a->declares[i]);
        continue;
      }
      const ast::Expr* target = a->targets[i].get();
      // Index notation names its indices by index variables, bound only inside it.
      if (const auto* r = target->as<ast::TensorRead>(); r && r->index_notation)
        target = r->base.get();
      try {
        written.emplace_back(source_of(target->span), e.in->evaluate(*target, 0));
      } catch (const std::exception&) {
        // A part of a value that cannot be read back (a matrix block under assembly): skip it.
      }
    }
  }
  for (const auto& [name, value] : written) {
    if (all_finite(value)) continue;
    trap->armed = false;
    ++trap->hits;
    hit_number_ = trap->number;
    return "NaN trap (breakpoint " + std::to_string(trap->number) + "): " + name + " = " +
           value_text(value, nullptr) + "\n";
  }
  return "";
}

void Debugger::stop(const Event& e, const StopInfo& info) {
  const std::string& reason = info.text;
  stopped_ = true;
  event_ = e;
  selected_ = 0;
  list_next_ = 0;
  mode_ = Mode::Continue;
  repeat_ = 0;
  if (handler_) {
    handler_->stopped(info);
    return resumed(e);
  }
  print_stop_location(reason);
  // A temporary breakpoint goes once it has stopped the run.
  if (reason.starts_with("Temporary breakpoint ")) {
    int n = std::stoi(reason.substr(std::strlen("Temporary breakpoint ")));
    cmd_delete(std::to_string(n));
  }
  show_displays();
  std::string run_args;
  while (!killed_) {
    std::optional<std::string> line = lines_(kPrompt);
    if (!line) {
      killed_ = quit_ = true;
      break;
    }
    Action a = execute(*line, run_args);
    if (a == Action::Resume || a == Action::Quit) break;
  }
  resumed(e);
}

void Debugger::resumed(const Event& e) {
  stopped_ = false;
  // A Ctrl-C typed at the prompt neither ends nor pauses the resumed run.
  trap_.take_interrupt();
  pause_requested_.store(false, std::memory_order_relaxed);
  if (killed_) {
    trap_.install(nullptr);
    throw interp::Interrupted(e.stmt->span, "the debugger ended the run");
  }
  update_hook();
}

void Debugger::update_hook() {
  bool needed = running_ && (mode_ != Mode::Continue || entry_pending_ ||
                             service_requested_.load(std::memory_order_relaxed) ||
                             pause_requested_.load(std::memory_order_relaxed));
  for (const auto& b : breakpoints_) needed = needed || (running_ && b->armed);
  trap_.install(needed ? this : nullptr);
}

void Debugger::print_stop_location(const std::string& reason) {
  const uint64_t activation = event_.in->frame_view(0).activation;
  // "Breakpoint 1, " leads the frame's line; other reasons are lines of their own. A step
  // within one activation shows the source line alone, as gdb does.
  out_ << reason;
  if (!reason.empty() || event_.after || activation != shown_activation_)
    out_ << frame_line(0, true) << "\n";
  shown_activation_ = activation;
  show_source_line(frame_compiled_line(0));
}

std::string Debugger::frame_line(int level, bool element_note) const {
  interp::FrameView v = event_.in->frame_view(level);
  std::string s = v.func ? v.func->name : "?";
  if (element_note && v.map) {
    const std::string& set = v.map->assembly && v.map->assembly->target_set
                                 ? v.map->assembly->target_set->name
                                 : v.map->set->name();
    s += " (element " + std::to_string(v.map->element) + " of " + set + ")";
  }
  s += level == 0 && event_.after ? " just after " : " at ";
  return s + where_text(frame_compiled_line(level));
}

// `map tet_force to tets, element 17, endpoints verts[3 8 12 40] (fem.sim:143)`.
std::string Debugger::map_line(int level) const {
  interp::FrameView v = event_.in->frame_view(level);
  if (!v.map) return "";
  const interp::MapView& m = *v.map;
  std::string set =
      m.assembly && m.assembly->target_set ? m.assembly->target_set->name : m.set->name();
  std::string s = std::string(m.is_apply ? "apply " : "map ") + v.func->name + " to " + set +
                  ", element " + std::to_string(m.element);
  if (!m.endpoints.empty()) {
    s += ", endpoints";
    std::string open;
    for (const interp::MapView::Endpoint& ep : m.endpoints) {
      std::string name = ep.set_var ? ep.set_var->name : ep.set->name();
      if (name != open) {
        s += (open.empty() ? " " : "] ") + name + "[";
        open = name;
      } else {
        s += " ";
      }
      s += std::to_string(ep.index);
    }
    s += "]";
  }
  if (m.at.valid()) s += " (" + where_text(m.at.start().line) + ")";
  return s;
}

int Debugger::frame_compiled_line(int level) const {
  if (level == 0) return event_.stmt->span.start().line;
  interp::FrameView v = event_.in->frame_view(level);
  return v.position.valid() ? v.position.start().line : 0;
}

uint32_t Debugger::frame_offset(int level) const {
  if (level == 0) return event_.after ? event_.stmt->span.end : event_.stmt->span.begin;
  return event_.in->frame_view(level).position.begin;
}

void Debugger::show_source_line(int compiled_line) const {
  const frontend::SourceFile* file = source();
  if (!file || compiled_line < 1 || compiled_line > file->line_count()) return;
  out_ << map_.place(compiled_line).line << "\t"
       << frontend::printable(file->line_text(compiled_line)) << "\n";
}

const frontend::SourceFile* Debugger::source() const {
  if (stopped_ && event_.stmt) return event_.stmt->span.file;
  if (program_)
    for (const auto& d : program_->decls)
      if (d->span.valid()) return d->span.file;
  return nullptr;
}

void Debugger::show_displays() {
  for (const Display& d : displays_) {
    std::string why;
    // A display whose names are not visible here is skipped, as gdb does.
    if (std::optional<std::string> text = evaluate(d.text, selected_, why))
      out_ << d.number << ": " << d.text << " = " << *text << "\n";
  }
}

}  // namespace simit::repl
