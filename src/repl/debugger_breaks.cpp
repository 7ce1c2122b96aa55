// The step debugger: breakpoints resolved to statements of a program, watchpoints to the
// sets a run binds, and line specifications (`74`, `fem.sim:74`) through the line map.
#include <algorithm>
#include <cctype>

#include "debugger.h"
#include "debugger_breakpoint.h"
#include "interp/interpreter.h"
#include "interp/set_binding.h"

namespace simit::repl {

namespace ast = frontend::ast;

namespace {

int line_of(const frontend::SourceSpan& s) { return s.valid() ? s.start().line : 0; }
int end_line_of(const frontend::SourceSpan& s) {
  return s.valid() ? s.file->locate(s.end > s.begin ? s.end - 1 : s.begin).line : 0;
}

// Calls f(stmt) on every statement of `block`, outer statements before their bodies.
template <class F>
void each_statement(const ast::Block& block, F&& f) {
  for (const auto& sp : block) {
    const ast::Stmt& s = *sp;
    f(s);
    if (const auto* i = s.as<ast::If>()) {
      for (const ast::Block& b : i->branches) each_statement(b, f);
      each_statement(i->else_branch, f);
    } else if (const auto* w = s.as<ast::While>()) {
      each_statement(w->body, f);
    } else if (const auto* d = s.as<ast::DoWhile>()) {
      each_statement(d->body, f);
    } else if (const auto* r = s.as<ast::ForRange>()) {
      each_statement(r->body, f);
    } else if (const auto* e = s.as<ast::ForSet>()) {
      each_statement(e->body, f);
    }
  }
}

bool all_digits(const std::string& s) {
  if (s.empty()) return false;
  for (char c : s)
    if (!std::isdigit(static_cast<unsigned char>(c))) return false;
  return true;
}

const ast::Variable* extern_named(const ast::Program& program, const std::string& name) {
  for (const ast::Variable* g : program.globals)
    if (g && g->name == name && g->kind == ast::Variable::Kind::Extern) return g;
  return nullptr;
}

}  // namespace

// The first statement on `compiled_line`, or else the first after it, in the function whose
// text holds the line (gdb moves a breakpoint on a line without code to the next one).
Debugger::Location Debugger::statement_at_line(const ast::Program& program,
                                               int compiled_line) const {
  for (const auto& d : program.decls) {
    const auto* f = d->as<ast::FuncDecl>();
    if (!f || f->is_extern || line_of(f->span) > compiled_line ||
        end_line_of(f->span) < compiled_line)
      continue;
    Location best;
    int best_line = 0;
    each_statement(f->body, [&](const ast::Stmt& s) {
      int l = line_of(s.span);
      if (l >= compiled_line && (!best.stmt || l < best_line)) best = {&s, f}, best_line = l;
    });
    return best;
  }
  return {};
}

bool Debugger::resolve(Breakpoint& b, const ast::Program& program, std::string& why) const {
  using Kind = Breakpoint::Kind;
  if (b.kind == Kind::Nan) return true;
  if (b.kind == Kind::Watch) {
    const ast::Variable* set = extern_named(program, b.set_name);
    if (!set || !set->type || set->type->kind != frontend::Type::Kind::Set || !set->type->element) {
      why = "no set named '" + b.set_name + "' in the program";
      return false;
    }
    if (set->type->element->field_index(b.field_name) < 0) {
      why = "set '" + b.set_name + "' has no field '" + b.field_name + "'";
      return false;
    }
    return true;
  }
  b.stmt = nullptr;
  b.func = nullptr;
  b.cond.reset();
  Location loc;
  if (b.kind == Kind::Line) {
    loc = statement_at_line(program, b.line);
    if (!loc.stmt) {
      why = "no code at or after " + where_text(b.line);
      return false;
    }
  } else {
    const ast::FuncDecl* f = program.find_func(b.func_name);
    if (!f || f->is_extern) {
      why = "no function '" + b.func_name + "' in the program";
      return false;
    }
    if (f->body.empty()) {
      why = "function '" + b.func_name + "' has no statements";
      return false;
    }
    loc = {f->body.front().get(), f};
  }
  b.stmt = loc.stmt;
  b.func = loc.func;
  b.resolved_at = loc.func->name + " at " + where_text(loc.stmt->span.start().line);
  if (b.condition.empty()) return true;
  std::shared_ptr<frontend::DebugExpression> cond;
  try {
    cond = std::make_shared<frontend::DebugExpression>(
        frontend::check_debug_expression(program, loc.func, loc.stmt->span.begin, b.condition));
  } catch (const std::exception& e) {  // an internal failure: refuse the condition, go on
    why = std::string("in the condition: ") + e.what();
    return false;
  }
  if (!cond->ok()) {
    why = "in the condition: " + cond->error;
    return false;
  }
  const frontend::Type& t = *cond->expr->type;
  if (!t.is_scalar() || t.scalar != frontend::ScalarKind::Bool) {
    why = "the condition is of type " + frontend::to_string(t) + ", not bool";
    return false;
  }
  b.cond = std::move(cond);
  return true;
}

bool Debugger::resolve_watch(Breakpoint& b, const interp::Interpreter& in, std::string& why) const {
  const ast::Variable* var = extern_named(in.program(), b.set_name);
  const interp::Value* v = var ? in.frame_value(0, *var) : nullptr;
  if (!v || v->kind() != interp::Value::Kind::Set || !v->binding() || !v->binding()->set) {
    why = "set '" + b.set_name + "' is not bound in this run";
    return false;
  }
  const interp::SetBinding& binding = *v->binding();
  int field = binding.element ? binding.element->field_index(b.field_name) : -1;
  if (field < 0 || static_cast<size_t>(field) >= binding.fields.size()) {
    why = "set '" + b.set_name + "' has no field '" + b.field_name + "'";
    return false;
  }
  if (b.index < 0 || b.index >= binding.set->size()) {
    why = "set '" + b.set_name + "' has no element " + std::to_string(b.index) + " (it has " +
          std::to_string(binding.set->size()) + ")";
    return false;
  }
  if (b.set != binding.set || b.field != binding.fields[field]) {
    b.set = binding.set;
    b.field = binding.fields[field];
    b.last = b.set->get(b.field, b.index);
  }
  return true;
}

// Resolves every breakpoint for the program `in` runs: the first event of a run, and of each
// interpreter a run uses (a scene's init and step).
void Debugger::attach(const interp::Interpreter& in) {
  attached_ = &in;
  at_stmt_.clear();
  for (const auto& bp : breakpoints_) {
    Breakpoint& b = *bp;
    std::string why;
    bool ok = b.kind == Breakpoint::Kind::Watch ? resolve_watch(b, in, why)
                                                : resolve(b, in.program(), why);
    if (!ok) {
      if (std::find(warned_.begin(), warned_.end(), b.number) == warned_.end())
        error("breakpoint " + std::to_string(b.number) + " is ignored in this run: " + why);
      warned_.push_back(b.number);
      continue;
    }
    if (b.stmt) at_stmt_[b.stmt].push_back(&b);
  }
}

std::optional<int> Debugger::parse_line_spec(const std::string& spec, std::string& why) const {
  std::string file, number = spec;
  if (size_t colon = spec.rfind(':'); colon != std::string::npos) {
    file = spec.substr(0, colon);
    number = spec.substr(colon + 1);
  }
  if (!all_digits(number)) {
    why = "expected LINE or FILE:LINE but got '" + spec + "'";
    return std::nullopt;
  }
  if (file.empty()) {
    // The file of the selected frame, as gdb does; else the program's first file.
    file = stopped_ ? map_.place(frame_compiled_line(selected_)).file : map_.default_file();
  }
  if (number.size() > 9) {  // more lines than any file has
    why = "no line " + number + " in a file named '" + file + "' in the program";
    return std::nullopt;
  }
  int line = std::stoi(number);
  std::optional<int> compiled = map_.compiled_line(file, line);
  if (!compiled) why = "no line " + number + " in a file named '" + file + "' in the program";
  return compiled;
}

std::string Debugger::where_text(int compiled_line) const {
  LineMap::Place p = map_.place(compiled_line);
  return p.file + ":" + std::to_string(p.line);
}

}  // namespace simit::repl
