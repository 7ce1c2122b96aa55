// The system tracer's statements (jit/trace/system_tracer.h): assignments to scalars, vectors
// and fields (passes and sparse products), ifs of scalar statements or of guarded vector
// operations, and checks.
#include "jit/trace/system_tracer.h"

#include <algorithm>

namespace simit::jit::trace_detail {

// Ops: consecutive scalar statements share one Scalar op.
void SystemTracer::scalar_stmt(Stmt s) {
  if (sink_) return sink_->push_back(std::move(s));
  if (ops_->empty() || ops_->back().kind != VectorOp::Kind::Scalar ||
      ops_->back().guard != guard_) {
    ops_->emplace_back();
    ops_->back().guard = guard_;
  }
  ops_->back().body.push_back(std::move(s));
}

// A loop over vectors, under the guard of the branch being traced.
void SystemTracer::push_op(VectorOp op, const SourceSpan& at) {
  if (sink_) give_up(at, AbortReason::VectorOpInScalarIf);
  op.guard = guard_;
  ops_->push_back(std::move(op));
}

void SystemTracer::set_local(int l, ExprRef v, const SourceSpan& at) {
  scalar_stmt(jit::set_local(l, std::move(v), at));
}

int SystemTracer::temp(Ty ty) {
  t_.locals.push_back(ty);
  return static_cast<int>(t_.locals.size() - 1);
}

void SystemTracer::assign(const ast::Variable& target, const ast::Expr& value,
                          const SourceSpan& at) {
  if (auto it = scalar_local_.find(&target); it != scalar_local_.end()) {
    ExprRef v = scalar(value);
    if (v->ty != t_.locals[it->second]) give_up(at, AbortReason::AssignmentType);
    return set_local(it->second, v, at);
  }
  auto vt = vector_slot_.find(&target);
  if (vt == vector_slot_.end()) give_up(at, AbortReason::AssignmentTo, target.name);
  // The controller makes such a vector before the loop runs, where the interpreter would
  // leave it without a value when the branch does not run (unless the run assigned it
  // before, outside any if).
  if (guard_ >= 0 && !assigned_.count(&target))
    for (const SystemBinding::Created& c : b_.created)
      if (c.var == &target) give_up(at, AbortReason::VectorFirstAssignedInIf);
  // `x = K * x`: the product goes to a scratch vector first, then into x, since its rows
  // read every component of x.
  const auto* x = is_product(value) ? value.as<ast::Binary>()->rhs->as<ast::VarRef>() : nullptr;
  if (x && x->var == &target)
    store_own_product(vt->second, size_of_.at(&target), value, at);
  else
    store_vector(vt->second, size_of_.at(&target), value, at);
  if (guard_ < 0) assigned_.insert(&target);
}

// A vector without a value when the run starts (one the controller makes) may be read only
// after the run has assigned it: the interpreter stops at an earlier read (an unbound
// extern, a variable not yet set).
void SystemTracer::check_has_value(const ast::Variable& v, const SourceSpan& at) const {
  if (assigned_.count(&v)) return;
  for (const SystemBinding::Created& c : b_.created)
    if (c.var == &v) give_up(at, AbortReason::ReadBeforeSet, v.name);
}

// `S.f = v`: the field's array, written in place.
void SystemTracer::assign_field(const ast::FieldRead& target, const ast::Expr& value,
                                const SourceSpan& at) {
  const auto key = field_key(target);
  first_field_write_ = std::min(first_field_write_, at_);
  if (is_product(value))
    if (const auto* x = value.as<ast::Binary>()->rhs->as<ast::FieldRead>();
        x && x->of_set && field_key(*x) == key)
      return store_own_product(field_slot_.at(key), field_size_.at(key), value, at);
  store_vector(field_slot_.at(key), field_size_.at(key), value, at);
}

// A product written into its own operand (`x = K * x`, `S.f = K * S.f`): computed into a
// scratch vector, which a pass then copies into the target.
void SystemTracer::store_own_product(int slot, int n, const ast::Expr& value,
                                     const SourceSpan& at) {
  t_.arrays[slot].written = true;
  store_pass(slot, n, product(*value.as<ast::Binary>(), at), at);
}

// `A * x` with A a matrix variable of the run.
bool SystemTracer::is_product(const ast::Expr& value) const {
  const auto* b = value.as<ast::Binary>();
  if (!b || b->op != ast::Binary::Op::Mul) return false;
  const auto* a = b->lhs->as<ast::VarRef>();
  return a && matrix_.count(a->var);
}

// Array `slot` (of `n` components) = value: a sparse product `A * x`, or a pass.
void SystemTracer::store_vector(int slot, int n, const ast::Expr& value, const SourceSpan& at) {
  t_.arrays[slot].written = true;
  if (is_product(value)) {
    const auto& b = *value.as<ast::Binary>();
    if (!single(slot)) return spmv(matrix_.at(b.lhs->as<ast::VarRef>()->var), *b.rhs, slot, n, at);
    // A product writes binary64 rows: a binary32 field takes them through a scratch vector.
    return store_pass(slot, n, product(b, at), at);
  }
  if (value.type && is_vector(*value.type) && length_of(value) != n)
    give_up(at, AbortReason::AssignmentLength);
  store_pass(slot, n, component(value), at);
}

// A pass over `n` components storing `value` (the visited component's) into array `slot`.
void SystemTracer::store_pass(int slot, int n, ExprRef value, const SourceSpan& at) {
  VectorOp pass;
  pass.kind = VectorOp::Kind::Pass;
  pass.length = n;
  Stmt s;
  s.kind = StmtKind::Store;
  s.slot = slot;
  s.index = element();
  s.value = std::move(value);
  s.span = at;
  pass.body.push_back(std::move(s));
  push_op(std::move(pass), at);
}

// arrays[y] = m * x, x a vector expression (computed into a scratch vector first unless it
// is a vector variable), y an array of `length` components.
void SystemTracer::spmv(const Mat& m, const ast::Expr& x, int y, int length, const SourceSpan& at) {
  if (!x.type || !is_vector(*x.type)) give_up(at, AbortReason::MatrixTimesNonVector);
  const int n = length_of(x);
  if (size_value_[static_cast<size_t>(n)] != m.length ||
      size_value_[static_cast<size_t>(length)] != m.length)
    give_up(at, AbortReason::ProductLengths);
  if (group_of(x) != m.block) give_up(at, AbortReason::ProductBlocks);
  VectorOp op;
  op.kind = VectorOp::Kind::SpMV;
  op.row_ptr = m.row_ptr;
  op.cols = m.cols;
  op.values = m.values;
  op.rows = m.rows;
  op.block = m.block;
  op.group = m.block;
  op.x = vector_operand(x, n, at);
  op.y = y;
  op.length = length;
  if (float32_) {
    // The product's value is rounded, component by component, before anything reads it.
    Stmt s;
    s.kind = StmtKind::Store;
    s.slot = y;
    s.index = element();
    s.value = rounded(load(y, at), at);
    s.span = at;
    op.body.push_back(std::move(s));
  }
  push_op(std::move(op), at);
}

// A product inside a vector expression (`b - A * x`): into a scratch vector, read back
// component by component.
ExprRef SystemTracer::product(const ast::Binary& b, const SourceSpan& at) {
  const auto* a = b.lhs->as<ast::VarRef>();
  if (!a || !matrix_.count(a->var)) give_up(at, AbortReason::MatrixExpressionProduct);
  const Mat& m = matrix_.at(a->var);
  const int n = length_of(*b.rhs);
  const int y = scratch(n);
  spmv(m, *b.rhs, y, n, at);
  return load(y, at);
}

// The array slot that holds a vector expression: a vector variable's own, or a scratch
// vector a pass fills.
int SystemTracer::vector_operand(const ast::Expr& x, int n, const SourceSpan& at) {
  if (const auto* r = x.as<ast::VarRef>())
    if (auto it = vector_slot_.find(r->var); it != vector_slot_.end()) {
      check_has_value(*r->var, x.span);
      return it->second;
    }
  if (const auto* f = x.as<ast::FieldRead>(); f && f->of_set) {
    const int field = field_slot_.at(field_key(*f));
    if (!single(field)) return field;  // a product reads binary64 operands
  }
  const int slot = scratch(n);
  store_pass(slot, n, component(x), at);
  return slot;
}

int SystemTracer::scratch(int n) {
  ArraySlot a;
  a.kind = ArraySlot::Kind::Vector;
  a.ty = Ty::F64;
  a.components = 1;
  a.written = true;
  a.name = "scratch" + std::to_string(scratch_count_++);
  t_.arrays.push_back(a);
  SystemBinding::Array b;
  b.part = SystemBinding::Array::Part::Scratch;
  b.size = n;
  b_.arrays.push_back(b);
  return static_cast<int>(t_.arrays.size() - 1);
}

void SystemTracer::stmt(const ast::Stmt& s) {
  if (const auto* i = s.as<ast::If>()) return has_vectors(*i) ? guarded_if(*i) : if_stmt(*i, 0);
  if (s.is<ast::Print>()) return error_stmt(s.span);
  if (const auto* d = s.as<ast::VarDecl>()) {
    if (!d->init) give_up(s.span, AbortReason::DeclarationWithoutValue);
    return assign(*d->var, *d->init, s.span);
  }
  const auto& a = *s.as<ast::Assign>();
  if (a.index_notation || a.targets.size() != 1) give_up(s.span, AbortReason::InLoop, "assignment");
  if (const auto* f = a.targets[0]->as<ast::FieldRead>(); f && f->of_set)
    return assign_field(*f, *a.value, s.span);
  const auto* target = a.targets[0]->as<ast::VarRef>();
  if (!target) give_up(s.span, AbortReason::PartAssignment);
  assign(*target->var, *a.value, s.span);
}

// Branch `from` of an if (and the elifs after it, nested in its else) as one If statement
// of scalar statements. The conditions are traced where the interpreter evaluates them.
void SystemTracer::if_stmt(const ast::If& i, size_t from) {
  Stmt s;
  s.kind = StmtKind::If;
  s.span = i.conditions[from]->span;
  s.value = scalar(*i.conditions[from]);
  if (s.value->ty != Ty::Bool) give_up(s.span, AbortReason::ConditionNotBoolean);
  std::vector<Stmt>* outer = sink_;
  sink_ = &s.body;
  for (const auto& b : i.branches[from]) stmt(*b);
  sink_ = &s.orelse;
  if (from + 1 < i.conditions.size())
    if_stmt(i, from + 1);
  else
    for (const auto& b : i.else_branch) stmt(*b);
  sink_ = outer;
  scalar_stmt(std::move(s));
}

// Whether an if's branches (or its elif conditions) compute on vectors: then it is traced
// as guarded ops, else as one If statement of scalar statements.
bool SystemTracer::mentions_vector(const ast::Expr& e) {
  if (e.type && has_set_dim(*e.type)) return true;
  bool found = false;
  ast::for_each_child(e, [&](const ast::Expr& c) { found = found || mentions_vector(c); });
  return found;
}

bool SystemTracer::has_vectors(const ast::If& i) {
  for (size_t k = 1; k < i.conditions.size(); ++k)
    if (mentions_vector(*i.conditions[k])) return true;
  auto block = [](const ast::Block& b) {
    for (const auto& s : b) {
      if (const auto* d = s->as<ast::VarDecl>(); d && d->init && mentions_vector(*d->init))
        return true;
      if (const auto* a = s->as<ast::Assign>()) {
        if (mentions_vector(*a->value)) return true;
        for (const auto& t : a->targets)
          if (mentions_vector(*t)) return true;
      }
      if (const auto* n = s->as<ast::If>();
          n && (mentions_vector(*n->conditions[0]) || has_vectors(*n)))
        return true;
    }
    return false;
  };
  for (const auto& b : i.branches)
    if (block(b)) return true;
  return block(i.else_branch);
}

// An if with vector operations: each branch's ops run under a guard, a Bool local set on
// every iteration to "the enclosing guard holds, the earlier conditions do not, and this
// one does". Each condition is evaluated before its branch, as the interpreter does (when
// an earlier branch ran, its value does not matter).
void SystemTracer::guarded_if(const ast::If& i) {
  if (sink_) give_up(i.span, AbortReason::VectorOpsInNestedIf);
  const int outer = guard_;
  const SourceSpan at = i.span;
  auto both = [&](ExprRef a, ExprRef b) {
    return a ? node(ExprKind::Binary, Ty::Bool, static_cast<uint8_t>(BinOp::And), {a, b}, at) : b;
  };
  ExprRef rest = outer >= 0 ? local(outer, Ty::Bool) : nullptr;
  for (size_t k = 0; k < i.conditions.size(); ++k) {
    guard_ = -1;
    ExprRef c = scalar(*i.conditions[k]);
    if (c->ty != Ty::Bool) give_up(i.conditions[k]->span, AbortReason::ConditionNotBoolean);
    const int g = temp(Ty::Bool), r = temp(Ty::Bool);
    set_local(g, both(rest, c), i.conditions[k]->span);
    set_local(r,
              both(rest, node(ExprKind::Unary, Ty::Bool, static_cast<uint8_t>(UnOp::Not), {c},
                              i.conditions[k]->span)),
              i.conditions[k]->span);
    guard_ = g;
    for (const auto& b : i.branches[k]) stmt(*b);
    rest = local(r, Ty::Bool);
  }
  guard_ = rest->slot;
  for (const auto& b : i.else_branch) stmt(*b);
  guard_ = outer;
}

// An integer division's or mod's divisor: a check that it is not zero, which hands the loop
// back to the interpreter (as an error statement does) to report the error in its words.
void SystemTracer::check_divisor(const ExprRef& d, const char* message, const SourceSpan& at) {
  if (d->kind == ExprKind::Const && d->i != 0) return;
  check(node(ExprKind::Compare, Ty::Bool, static_cast<uint8_t>(CmpOp::Ne), {d, iconst(0, Ty::I32)},
             at),
        message, at);
}

// A check that `ok` holds; a kernel where it does not hands the loop back.
void SystemTracer::check(ExprRef ok, const char* message, const SourceSpan& at) {
  Stmt s;
  s.kind = StmtKind::Check;
  s.value = std::move(ok);
  s.error = static_cast<int>(t_.errors.size());
  s.span = at;
  t_.errors.push_back({at, message});
  scalar_stmt(std::move(s));
}

}  // namespace simit::jit::trace_detail
