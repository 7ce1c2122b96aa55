// Statement execution: one dispatch over the statement kinds, and the trap point.
#include <iostream>
#include <sstream>

#include "interp/frame.h"
#include "interp/hook.h"
#include "interp/interpreter.h"
#include "interp/printing.h"

namespace simit::interp {

namespace ast = frontend::ast;
using frontend::Type;

namespace {

// Whether a statement may be part of a run offered to the executor (exec_run).
bool joins_run(const ast::Stmt& s) { return s.system_level || s.scalar_level; }

}  // namespace

void Interpreter::exec_block(const ast::Block& b) {
  const size_t n = b.size();
  // Runs are offered to a compiled executor, not in a mapped function (whose element-wise
  // writes to its results are the map's business), nor in a distributed run (compiled system
  // statements would skip its reductions over ranks and ghost refreshes: maps only).
  const bool offer = options_.sites && !map_ && !options_.distribution;
  for (size_t i = 0; i < n; ++i) {
    const ast::Stmt& s = *b[i];
    // The first statement of a run: the run is offered whole.
    if (offer && joins_run(s) && i + 1 < n && joins_run(*b[i + 1]) &&
        (i == 0 || !joins_run(*b[i - 1]))) [[unlikely]]
      i += exec_run(b, i) - 1;
    else
      exec(s);
  }
}

// Offers the run that starts at b[first]: two or more consecutive statements that are
// system-level or assign scalars, the last of them system-level (a hook that checks a run
// compares when it is done: SiteHook::statement_done). Returns how many statements from
// `first` ran. What the executor declines runs interpreted one statement at a time, and the
// rest of the run (while it is still a run) is offered again: a run whose first statement
// cannot be compiled may compile from its second.
[[gnu::noinline]] size_t Interpreter::exec_run(const ast::Block& b, size_t first) {
  size_t end = first;
  while (end < b.size() && joins_run(*b[end])) ++end;
  while (end > first && !b[end - 1]->system_level) --end;
  size_t i = first;
  while (end >= i + 2) {
#if SIMIT_STATEMENT_HOOK
    if (trap_->armed()) break;
#endif
    if (const size_t ran = options_.sites->run_statements(b, i, end - i, *this))
      return i + ran - first;
    exec(*b[i++]);
  }
  if (i == first) exec(*b[i++]);  // no run after all: scalar statements alone, or one statement
  return i - first;
}

void Interpreter::exec(const ast::Stmt& s) {
#if SIMIT_STATEMENT_HOOK
  // The one trap point of the evaluation loop: a flag test and a branch when nothing is armed.
  if (trap_->armed()) [[unlikely]]
    return exec_trapped(s);
#endif
  if (s.system_level && options_.sites && !options_.distribution) [[unlikely]]
    return exec_offered(s);
  exec_node(s);
}

// Out of line: only programs run with a compiled executor get here. A statement alone is
// not offered in a mapped function (its writes to its results are the map's).
[[gnu::noinline]] void Interpreter::exec_offered(const ast::Stmt& s) {
  if ((!map_ || s.is<ast::While>()) && options_.sites->run_statement(s, *this)) return;
  exec_node(s);
  options_.sites->statement_done(s, *this);
}

Value& Interpreter::variable(const ast::Variable& v) { return var(v); }

void Interpreter::exec_interpreted(const ast::Stmt& s) { exec_node(s); }

#if SIMIT_STATEMENT_HOOK
// Out of line so that exec() stays small enough to inline into the block loop.
[[gnu::noinline]] void Interpreter::exec_trapped(const ast::Stmt& s) {
  if (trap_->take_interrupt()) throw Interrupted(s.span, "interrupted");
  const ast::FuncDecl& func = *frame().func;
  const int depth = depth_ - 1;
  if (StatementHook* h = trap_->hook()) h->before_statement(s, func, depth, *this);
  exec_node(s);
  // Read again: the hook may have removed itself, or been installed, meanwhile.
  if (StatementHook* h = trap_->hook()) h->after_statement(s, func, depth, *this);
}
#endif

void Interpreter::exec_node(const ast::Stmt& s) {
  switch (s.kind) {
    case ast::NodeKind::VarDecl: return exec_var_decl(static_cast<const ast::VarDecl&>(s));
    case ast::NodeKind::IvarDecl: return;
    case ast::NodeKind::Assign: {
      const auto& a = static_cast<const ast::Assign&>(s);
      return a.index_notation ? exec_index_assign(a) : exec_assign(a);
    }
    case ast::NodeKind::ExprStmt: {
      const ast::Expr& e = *static_cast<const ast::ExprStmt&>(s).expr;
      HoistScope hoisted(*this, e);
      if (e.type && e.type->kind == Type::Kind::Multi)
        eval_multi(e);
      else
        eval(e);
      return;
    }
    case ast::NodeKind::If: return exec_if(static_cast<const ast::If&>(s));
    case ast::NodeKind::While: {
      const auto& w = static_cast<const ast::While&>(s);
      while (condition(*w.condition)) exec_block(w.body);
      return;
    }
    case ast::NodeKind::DoWhile: {
      const auto& d = static_cast<const ast::DoWhile&>(s);
      do exec_block(d.body);
      while (condition(*d.condition));
      return;
    }
    case ast::NodeKind::ForRange: return exec_for_range(static_cast<const ast::ForRange&>(s));
    case ast::NodeKind::ForSet: return exec_for_set(static_cast<const ast::ForSet&>(s));
    case ast::NodeKind::Print: return exec_print(static_cast<const ast::Print&>(s));
    case ast::NodeKind::Apply: exec_apply(static_cast<const ast::Apply&>(s)); return;
    default: break;
  }
  fail(s.span, std::string("cannot execute a ") + ast::node_kind_name(s.kind) + " node");
}

// `var x : T = e;`, `const x = e;` and global constants. Every execution starts afresh
// (Q21): no value survives from an earlier execution of the declaration.
void Interpreter::exec_var_decl(const ast::VarDecl& d) {
  Value& slot = var(*d.var);
  const Type& t = *d.var->type;
  if (!d.init) {
    slot = zero_of(t, d.span);
    return;
  }
  Value v = eval_root(*d.init);
  if (t.kind != Type::Kind::Tensor || v.kind() == Value::Kind::Matrix) {
    slot = std::move(v);
    return;
  }
  Shape shape = shape_of(t, d.span);
  if (v.is_scalar()) {  // a scalar initialiser fills every component
    Value filled = Value::zero(v.component_kind(), shape);
    v.fill_into(filled.tensor(), 0, shape.size());
    slot = std::move(filled);
    return;
  }
  if (v.tensor().shape() != shape) {
    // `const m : tensor[1,3](float) = [1.0, 2.0, 3.0];` (§10.3): same components.
    if (v.tensor().size() != shape.size())
      fail(d.init->span, "initialiser of shape " + v.tensor().shape().str() +
                             " does not fit a variable of shape " + shape.str());
    v.tensor().reshape(shape);
  }
  slot = std::move(v);
}

// The right side is evaluated completely before any target is touched (§7.1).
void Interpreter::exec_assign(const ast::Assign& a) {
  if (a.targets.size() == 1 && !(a.value->type && a.value->type->kind == Type::Kind::Multi)) {
    store(a, 0, eval_root(*a.value));
    return;
  }
  std::vector<Value> values;
  {
    HoistScope hoisted(*this, *a.value);
    values = eval_multi(*a.value);
  }
  if (values.size() != a.targets.size())
    fail(a.span, "expected " + std::to_string(a.targets.size()) + " values but got " +
                     std::to_string(values.size()));
  for (size_t i = 0; i < values.size(); ++i) store(a, i, std::move(values[i]));
}

void Interpreter::store(const ast::Assign& a, size_t i, Value value) {
  if (i < a.declares.size() && a.declares[i]) {
    var(*a.declares[i]) = std::move(value);
    return;
  }
  const ast::Expr& target = *a.targets[i];
  HoistScope hoisted(*this, target);
  if (map_ && depth_ == map_depth_ && result_write(target, value)) return;
  write_place(resolve_place(target), std::move(value), target.span);
}

void Interpreter::exec_if(const ast::If& s) {
  for (size_t i = 0; i < s.conditions.size(); ++i) {
    if (condition(*s.conditions[i])) {
      exec_block(s.branches[i]);
      return;
    }
  }
  if (s.has_else) exec_block(s.else_branch);
}

bool Interpreter::condition(const ast::Expr& e) {
  Value v = eval_root(e);
  if (v.kind() != Value::Kind::Bool) fail(e.span, "condition is not a boolean");
  return v.as_bool();
}

// Bounds are evaluated once; the upper bound is exclusive (§7.5).
void Interpreter::exec_for_range(const ast::ForRange& s) {
  const int64_t lo = eval_root(*s.lo).as_int(), hi = eval_root(*s.hi).as_int();
  for (int64_t i = lo; i < hi; ++i) {
    var(*s.var) = Value::of_int(static_cast<int32_t>(i));
    exec_block(s.body);
  }
}

void Interpreter::exec_for_set(const ast::ForSet& s) {
  const ast::Variable* domain = s.domain_var;
  if (!domain) fail(s.span, "loop over an unresolved set");
  if (var(*domain).kind() == Value::Kind::Set) {
    SetBinding* b = var(*domain).binding();
    const int n = b->set->size();
    for (int32_t i = 0; i < n; ++i) {
      var(*s.var) = Value::of_element(b, i);
      exec_block(s.body);
    }
    return;
  }
  // A generic parameter bound to a size n: the loop runs over 0 .. n-1.
  const int32_t n = var(*domain).kind() == Value::Kind::Int ? var(*domain).as_int() : -1;
  if (n < 0) unsupported(s.span, "loops over sets");
  for (int32_t i = 0; i < n; ++i) {
    var(*s.var) = Value::of_int(i);
    exec_block(s.body);
  }
}

// An error statement builds its whole message first, so that an argument that fails to
// evaluate reports its own error and nothing is half-printed.
void Interpreter::exec_print(const ast::Print& p) {
  std::ostringstream message;
  std::ostream& out = p.is_error() ? message : options_.out ? *options_.out : std::cout;
  for (const auto& arg : p.args) {
    Value v = eval_root(*arg);
    const Type& t = *arg->type;
    print_value(out, v, t.kind == Type::Kind::Tensor && t.dims.size() == 1 && t.row);
  }
  if (p.is_error()) fail(p.span, message.str());
  if (p.newline()) out << "\n";
}

}  // namespace simit::interp
