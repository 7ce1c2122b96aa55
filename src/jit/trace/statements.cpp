// The tracer's statements (jit/trace/tracer.h): declarations, assignments, error
// statements, unrolled loops, and ifs, with the variables their branches assign merged.
#include <functional>

#include "jit/trace/tracer.h"

namespace simit::jit::trace_detail {

void Tracer::exec_block(const ast::Block& b) {
  for (const auto& s : b) exec(*s);
}

void Tracer::exec(const ast::Stmt& s) {
  check_size();
  switch (s.kind) {
    case ast::NodeKind::VarDecl: {
      const auto& d = static_cast<const ast::VarDecl&>(s);
      Sym v = d.init ? as_declared(eval(*d.init), *d.var->type, d.span, true)
                     : zero_of(*d.var->type, d.span);
      return bind(*d.var, std::move(v), d.span);
    }
    case ast::NodeKind::Assign: {
      const auto& a = static_cast<const ast::Assign&>(s);
      if (a.index_notation) give_up(a.span, AbortReason::IndexNotation);
      if (a.targets.size() == 1) return assign(*a.targets[0], eval(*a.value), a.span);
      const auto* call = a.value->as<ast::Call>();
      if (!call) give_up(a.span, AbortReason::MultipleAssignmentNotCall);
      std::vector<Sym> values = call->func ? call_user(*call) : decompose(*call);
      if (values.size() != a.targets.size()) give_up(a.span, AbortReason::ResultCount);
      for (size_t i = 0; i < values.size(); ++i)
        assign(*a.targets[i], std::move(values[i]), a.span);
      return;
    }
    case ast::NodeKind::ExprStmt: {
      const auto& e = static_cast<const ast::ExprStmt&>(s);
      const auto* call = e.expr->as<ast::Call>();
      if (!call || !call->func) give_up(s.span, AbortReason::ExpressionStatement);
      call_user(*call);
      return;
    }
    case ast::NodeKind::If: return exec_if(static_cast<const ast::If&>(s));
    case ast::NodeKind::ForRange: return exec_for(static_cast<const ast::ForRange&>(s));
    case ast::NodeKind::Print:
      if (static_cast<const ast::Print&>(s).is_error()) return exec_error(s.span);
      break;
    default: break;
  }
  give_up(s.span, AbortReason::StatementKind, ast::node_kind_name(s.kind));
}

// An error statement is a check that always fails: the controller then runs the site again in
// the interpreter, which formats the message and reports it with its call stack. Its arguments
// are not traced, since compiled code never shows them.
void Tracer::exec_error(const SourceSpan& at) {
  if (!error_at_.valid()) error_at_ = at;
  emit_check(iconst(0, Ty::Bool), "an error statement (reported by the interpreter)", at);
}

void Tracer::exec_for(const ast::ForRange& s) {
  Sym lo = eval(*s.lo), hi = eval(*s.hi);
  if (!lo.scalar() || !hi.scalar() || !is_const(lo.c[0]) || !is_const(hi.c[0]))
    give_up(s.span, AbortReason::LoopBoundsNotConstant);
  for (int64_t i = lo.c[0]->i; i < hi.c[0]->i; ++i) {
    frame().vars[s.var] = scalar(Ty::I32, iconst(i));
    frame().bound_at[s.var] = static_cast<int>(blocks_.size());
    exec_block(s.body);
  }
}

// Variables assigned in a branch are given mutable locals before it, so that the value
// after the if is whichever branch ran.
void Tracer::merge(const ast::Variable& v, const SourceSpan& at) {
  Frame& f = frame();
  if (f.merged.count(&v)) return;
  auto it = f.vars.find(&v);
  if (it != f.vars.end() && it->second.kind != Sym::Kind::Tensor) return;  // elements, results
  Sym cur = it != f.vars.end() ? it->second : zero_of(*v.type, at);
  std::vector<int> locals;
  for (ExprRef& c : cur.c) {
    const int l = new_local(cur.ty, true);
    set_local(l, c, at);
    locals.push_back(l);
    c = read_local(l);
  }
  f.merged[&v] = std::move(locals);
  f.vars[&v] = std::move(cur);
}

void Tracer::merge_assigned(const ast::Block& b) {
  // Every variable a statement in `b` (at any depth) assigns or declares.
  std::vector<const ast::Variable*> found;
  std::function<void(const ast::Block&)> scan = [&](const ast::Block& blk) {
    for (const auto& st : blk) {
      if (const auto* d = st->as<ast::VarDecl>()) found.push_back(d->var);
      if (const auto* a = st->as<ast::Assign>()) {
        for (const auto& t : a->targets) {
          const ast::Expr* e = t.get();
          while (true) {
            if (const auto* r = e->as<ast::TensorRead>())
              e = r->base.get();
            else
              break;
          }
          if (const auto* v = e->as<ast::VarRef>()) found.push_back(v->var);
        }
      }
      if (const auto* i = st->as<ast::If>()) {
        for (const auto& br : i->branches) scan(br);
        scan(i->else_branch);
      }
      if (const auto* l = st->as<ast::ForRange>()) scan(l->body);
    }
  };
  scan(b);
  for (const ast::Variable* v : found)
    if (v && v->type &&
        (v->kind == ast::Variable::Kind::Local || v->kind == ast::Variable::Kind::Result ||
         v->kind == ast::Variable::Kind::Param)) {
      auto it = frame().vars.find(v);
      if (it != frame().vars.end() && it->second.kind == Sym::Kind::Result) continue;
      if (v->type->is_global()) continue;
      merge(*v, b.empty() ? SourceSpan{} : b.front()->span);
    }
}

void Tracer::exec_if(const ast::If& s) { exec_if_from(s, 0); }

// Conditions that fold choose their branch now; the first that does not becomes an If whose
// else part holds the rest of the chain (from condition `first` on).
void Tracer::exec_if_from(const ast::If& s, size_t first) {
  for (size_t i = first; i < s.conditions.size(); ++i) {
    Sym c = eval(*s.conditions[i]);
    if (!c.scalar() || c.ty != Ty::Bool) give_up(s.span, AbortReason::ConditionNotBoolean);
    if (is_const(c.c[0])) {
      if (c.c[0]->i) return exec_block(s.branches[i]);
      continue;
    }
    for (size_t j = i; j < s.branches.size(); ++j) merge_assigned(s.branches[j]);
    merge_assigned(s.else_branch);
    Stmt st;
    st.kind = StmtKind::If;
    st.value = c.c[0];
    st.span = s.conditions[i]->span;
    emit(std::move(st));
    std::vector<Stmt> then_body, else_body;
    auto run_in = [&](std::vector<Stmt>& body, auto fn) {
      std::vector<Stmt>* saved = out_;
      out_ = &body;
      blocks_.push_back(next_block_++);
      if (ZeroFold* z = build_.fold()) z->open();
      fn();
      if (ZeroFold* z = build_.fold())
        if (auto check = z->close(trace_.errors, s.span)) body.push_back(std::move(*check));
      blocks_.pop_back();
      out_ = saved;
    };
    run_in(then_body, [&] { exec_block(s.branches[i]); });
    run_in(else_body, [&] { exec_if_from(s, i + 1); });
    // The branches emitted into their own lists: the If is still the last statement here.
    out_->back().body = std::move(then_body);
    out_->back().orelse = std::move(else_body);
    return;
  }
  exec_block(s.else_branch);
}

}  // namespace simit::jit::trace_detail
