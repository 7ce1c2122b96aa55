// The system tracer's run (jit/trace/system_tracer.h): the statements of a run and its while
// loop traced section by section, the variables they use classified and bound to arrays,
// sizes and scalar locals; and the entry points of jit/system_trace.h.
#include "jit/trace/system_tracer.h"

#include <functional>
#include <utility>

#include "interp/set_binding.h"
#include "runtime/system_ops.h"

namespace simit::jit::trace_detail {

TracedSystem SystemTracer::run() {
  TracedSystem out;
  try {
    collect();
    const ast::While* loop = nullptr;
    for (at_ = 0; at_ < run_.size(); ++at_) {
      const ast::Stmt& s = *run_[at_];
      if (const auto* w = s.as<ast::While>()) {
        if (loop) give_up(s.span, AbortReason::SecondWhileLoop);
        loop = w;
        end_section();
        trace_loop(*w);
      } else {
        stmt(s);
      }
    }
    end_section();
    // A loop's products read a copy of each matrix without its zero blocks (PrunedMatrix),
    // made once per call for all iterations; a run without a loop multiplies once and reads
    // the matrix where it is, as the interpreter does.
    t_.matrices_in_place = !loop;
    t_.float32 = float32_;
    // Under float32 that copy is binary32 (PrunedMatrix::values32): every value of a
    // program's matrix is a binary32 value then (docs/arithmetic.md).
    if (loop && float32_) {
      for (const auto& [var, mat] : matrix_)
        t_.arrays[static_cast<size_t>(mat.values)].single = true;
      mark_binary32_vectors();
    }
    // A kernel that reaches an error statement puts the variables back for the interpreter
    // to run the statements again; it could not put a field back.
    if (!t_.errors.empty() && first_field_write_ < run_.size()) {
      at_ = first_field_write_;
      give_up(run_[at_]->span, AbortReason::FieldWriteBeforeError);
    }
    name(loop);
    t_.scalars = static_cast<int>(b_.scalars.size());
  } catch (const GiveUp& g) {
    out.reason = g.reason;
    out.failed_at = at_;
    return out;
  }
  out.trace = std::move(t_);
  out.binding = std::move(b_);
  return out;
}

// "while:LINE" for a loop alone, else "statements:FIRST-LAST".
void SystemTracer::name(const ast::While* loop) {
  if (run_.size() == 1 && loop) {
    t_.name = "while";
    if (loop->span.valid()) t_.name += ":" + std::to_string(loop->span.start().line);
    return;
  }
  t_.name = "statements:" + run_lines(run_);
}

void SystemTracer::trace_loop(const ast::While& loop) {
  ops_ = &t_.body;
  t_.condition = scalar(*loop.condition);
  if (!t_.body.empty()) give_up(loop.condition->span, AbortReason::VectorLoopCondition);
  for (const auto& s : loop.body) stmt(*s);
  end_section();
  ops_ = &t_.after;
}

// Every sum of the section just traced starts at +0.0 first in it, so that no scalar op
// stands between a start and its pass: fuse_passes may move the pass up to another loop.
void SystemTracer::end_section() {
  if (starts_.empty()) return;
  VectorOp first;
  first.body = std::move(starts_);
  starts_.clear();
  ops_->insert(ops_->begin(), std::move(first));
}

// Every variable the run reads or writes, classified by its type.
void SystemTracer::collect() {
  std::function<void(const ast::Expr&)> expr = [&](const ast::Expr& e) {
    if (const auto* f = e.as<ast::FieldRead>(); f && f->of_set) return note_field(*f);
    if (const auto* r = e.as<ast::VarRef>()) note(*r->var, r->span);
    ast::for_each_child(e, [&](const ast::Expr& c) { expr(c); });
  };
  for (at_ = 0; at_ < run_.size(); ++at_) {
    if (const auto* w = run_[at_]->as<ast::While>()) {
      expr(*w->condition);
      collect_block(w->body, expr);
    } else {
      collect_stmt(*run_[at_], expr);
    }
  }
  at_ = 0;
  // Vectors first assigned in the run borrow the shape of a vector, or a field of a set, of
  // the same type.
  for (auto& [v, slot] : vector_slot_) {
    const Value& val = in_.variable(*v);
    if (!val.empty()) continue;
    SystemBinding::Created c{v};
    for (auto& [w, s2] : vector_slot_)
      if (!in_.variable(*w).empty() && frontend::types_equal(*w->type, *v->type)) c.like = w;
    if (c.like) {
      size_of_[v] = size_of_[c.like];
      if (block_of_.count(c.like)) block_of_[v] = block_of_.at(c.like);
    } else {
      for (const auto& [key, type] : field_type_)
        if (!c.like && frontend::types_equal(*type, *v->type)) {
          c.like = key.first;
          c.like_field = key.second;
          size_of_[v] = field_size_.at(key);
          block_of_[v] = field_block_.at(key);
        }
    }
    if (!c.like) give_up(v->span, AbortReason::VectorWithoutShape, v->name);
    b_.created.push_back(c);
  }
}

void SystemTracer::collect_block(const ast::Block& body,
                                 const std::function<void(const ast::Expr&)>& expr) {
  for (const auto& s : body) collect_stmt(*s, expr);
}

void SystemTracer::collect_stmt(const ast::Stmt& s,
                                const std::function<void(const ast::Expr&)>& expr) {
  if (const auto* d = s.as<ast::VarDecl>()) {
    note(*d->var, d->span);
    if (d->init) expr(*d->init);
  } else if (const auto* a = s.as<ast::Assign>()) {
    for (const auto& t : a->targets) expr(*t);
    expr(*a->value);
  } else if (const auto* i = s.as<ast::If>()) {
    for (const auto& c : i->conditions) expr(*c);
    for (const auto& b : i->branches) collect_block(b, expr);
    collect_block(i->else_branch, expr);
  } else if (const auto* p = s.as<ast::Print>(); p && p->is_error()) {
    // Its arguments are only formatted by the interpreter, which runs the loop again.
  } else {
    give_up(s.span, AbortReason::StatementKindInLoop, ast::node_kind_name(s.kind));
  }
}

namespace {

void visit_stores(const std::vector<Stmt>& body, const std::function<void(const Stmt&)>& f) {
  for (const Stmt& s : body) {
    if (s.kind == StmtKind::Store) f(s);
    visit_stores(s.body, f);
    visit_stores(s.orelse, f);
  }
}

}  // namespace

// Under float32, the vectors the run writes (the program's, copied in and out around the
// call, and the trace's scratch vectors) that only ever hold binary32 values are binary32 in
// the kernel,
// half the bytes. A stored value is one when it is an operator's (rounded), a binary32
// constant, or a read of a binary32 array; not a copy of a binary64 field or of a scalar the
// host bound, which the interpreter does not round. A product's rows are stored as they are
// rounded. Vectors copied in hold binary32 values or the call is left to the interpreter
// (loop_kernel.cpp).
void SystemTracer::mark_binary32_vectors() {
  using Part = SystemBinding::Array::Part;
  std::vector<bool> ok(t_.arrays.size(), false);
  // A vector the run only reads holds whatever the caller passed: binary32 values (an
  // operator's), or wider ones (a binary64 field read as it is, `cg(A, points.b, ...)`),
  // which a binary32 copy could not hold. Its value now decides; a later call whose values
  // are wider runs interpreted (loop_kernel.cpp).
  auto binary32_now = [&](const ast::Variable* v) {
    const Value& val = in_.variable(*v);
    if (val.empty() || !val.is_tensor() || val.tensor().kind() != runtime::ComponentKind::Float)
      return false;
    return runtime::is_binary32(std::span(val.tensor().floats(), val.tensor().size()));
  };
  for (size_t i = 0; i < b_.arrays.size(); ++i)
    ok[i] = b_.arrays[i].part == Part::Scratch ||
            (b_.arrays[i].part == Part::Vector &&
             (t_.arrays[i].written || binary32_now(b_.arrays[i].var)));
  std::function<bool(const Expr&)> binary32 = [&](const Expr& e) {
    switch (e.kind) {
      case ExprKind::Const: return runtime::is_binary32(e.f);
      case ExprKind::Load:
        return t_.arrays[static_cast<size_t>(e.slot)].single || ok[static_cast<size_t>(e.slot)];
      case ExprKind::Unary: return static_cast<UnOp>(e.op) == UnOp::Round32;
      default: return false;
    }
  };
  // A vector stays binary32 while every store into it is; one that is not can make the
  // vectors copied from it wide in turn, so repeat until nothing changes.
  for (bool changed = true; changed;) {
    changed = false;
    for (const auto* ops : {&t_.before, &t_.body, &t_.after})
      for (const VectorOp& op : *ops)
        visit_stores(op.body, [&](const Stmt& s) {
          if (ok[static_cast<size_t>(s.slot)] && !binary32(*s.value)) {
            ok[static_cast<size_t>(s.slot)] = false;
            changed = true;
          }
        });
  }
  for (size_t i = 0; i < ok.size(); ++i)
    if (ok[i]) t_.arrays[i].single = true;
}

void SystemTracer::note(const ast::Variable& v, const SourceSpan& at) {
  if (scalar_local_.count(&v) || vector_slot_.count(&v) || matrix_.count(&v)) return;
  if (v.kind == ast::Variable::Kind::GlobalConst) return;
  if (!v.type) give_up(at, AbortReason::VariableWithoutType, v.name);
  const Type& t = *v.type;
  if (t.kind == Type::Kind::Scalar) {
    Ty ty = t.scalar == frontend::ScalarKind::Float ? Ty::F64
            : t.scalar == frontend::ScalarKind::Int ? Ty::I32
            : t.scalar == frontend::ScalarKind::Bool
                ? Ty::Bool
                : (give_up(at, AbortReason::ScalarType), Ty::F64);
    scalar_local_[&v] = static_cast<int>(t_.locals.size());
    t_.locals.push_back(ty);
    b_.scalars.push_back(&v);
    b_.scalar_types.push_back(ty);
    return;
  }
  if (is_vector(t)) {
    if (t.component() != frontend::ScalarKind::Float) give_up(at, AbortReason::VectorTypeNotFloat);
    vector_slot_[&v] = array(&v, SystemBinding::Array::Part::Vector, Ty::F64, v.name);
    const Value& val = in_.variable(v);
    if (!val.empty()) {
      if (!val.is_tensor() || val.tensor().kind() != runtime::ComponentKind::Float)
        give_up(at, AbortReason::VectorNotFloat, v.name);
      size_of_[&v] = size(&v, false, static_cast<int64_t>(val.tensor().size()));
      block_of_[&v] = static_cast<int>(val.tensor().shape().block_size());
    }
    return;
  }
  if (is_matrix(t)) {
    const Value& val = in_.variable(v);
    if (val.kind() != Value::Kind::Matrix || !val.matrix() || !val.matrix()->is_float())
      give_up(at, AbortReason::MatrixWithoutValue, v.name);
    const runtime::SystemMatrix& m = *val.matrix();
    if (m.block_rows() != m.block_cols()) give_up(at, AbortReason::NonSquareBlocks);
    Mat mat;
    mat.row_ptr = array(&v, SystemBinding::Array::Part::RowPtr, Ty::I32, v.name + ".row_ptr");
    mat.cols = array(&v, SystemBinding::Array::Part::Cols, Ty::I32, v.name + ".cols");
    mat.values = array(&v, SystemBinding::Array::Part::Values, Ty::F64, v.name + ".values");
    mat.rows = size(&v, true, m.rows());
    mat.block = m.block_rows();
    mat.length = static_cast<int64_t>(m.rows()) * m.block_rows();
    matrix_[&v] = mat;
    return;
  }
  give_up(at, AbortReason::VariableTypeInLoop, v.name, frontend::to_string(t));
}

// `S.f`, a field of a set as a vector: its array, read or written in place (a binary32
// field widened at each read and rounded at each write, as the interpreter converts it).
void SystemTracer::note_field(const ast::FieldRead& f) {
  const auto* set = f.base->as<ast::VarRef>();
  if (!set) give_up(f.span, AbortReason::FieldOfSetExpression);
  const FieldKey key{set->var, f.field_index};
  if (field_slot_.count(key)) return;
  const Value& sv = in_.variable(*set->var);
  if (sv.kind() != Value::Kind::Set || !sv.binding() || !sv.binding()->set)
    give_up(f.span, AbortReason::SetNotBound, set->var->name);
  const interp::SetBinding& b = *sv.binding();
  const runtime::Field& field = std::as_const(*b.set).field(b.fields[f.field_index]);
  if (field.type().kind != runtime::ComponentKind::Float)
    give_up(f.span, AbortReason::FieldNotFloat, f.field);
  const bool single = field.type().single;
  const int slot =
      array(set->var, SystemBinding::Array::Part::Field, Ty::F64, set->var->name + "." + f.field);
  t_.arrays[static_cast<size_t>(slot)].single = single;
  b_.arrays.back().field = f.field_index;
  field_slot_[key] = slot;
  const int64_t n = static_cast<int64_t>(b.set->size()) * field.components();
  field_size_[key] = size(set->var, false, n, f.field_index);
  field_block_[key] = static_cast<int>(field.components());
  field_type_[key] = f.type.get();
}

std::pair<const ast::Variable*, int> SystemTracer::field_key(const ast::FieldRead& f) {
  return {f.base->as<ast::VarRef>()->var, f.field_index};
}

int SystemTracer::array(const ast::Variable* v, SystemBinding::Array::Part part, Ty ty,
                        std::string name) {
  ArraySlot a;
  a.kind = ArraySlot::Kind::Vector;
  a.ty = ty;
  a.components = 1;
  a.name = std::move(name);
  t_.arrays.push_back(a);
  b_.arrays.push_back({v, part});
  return static_cast<int>(t_.arrays.size() - 1);
}

// Sizes are shared by value: passes over vectors of equal length may fuse. The controller
// keys kernels by every length, so a length that changes gets a new trace.
int SystemTracer::size(const ast::Variable* v, bool rows, int64_t n, int field) {
  const std::pair<bool, int64_t> key{rows, n};
  if (auto it = sizes_.find(key); it != sizes_.end()) return it->second;
  t_.sizes.push_back((rows ? "block rows of " : "components of ") + v->name + " (" +
                     std::to_string(n) + ")");
  b_.sizes.push_back({v, rows, field});
  size_value_.push_back(n);
  return sizes_[key] = static_cast<int>(t_.sizes.size() - 1);
}

}  // namespace simit::jit::trace_detail

namespace simit::jit {

namespace ast = frontend::ast;
using frontend::SourceSpan;
using trace_detail::is_matrix;
using trace_detail::SystemTracer;

bool matrix_statement(const ast::Stmt& s) {
  bool found = false;
  std::function<void(const ast::Expr&)> scan = [&](const ast::Expr& e) {
    if (const auto* b = e.as<ast::Binary>(); b && b->op == ast::Binary::Op::LeftDiv) found = true;
    if (const auto* c = e.as<ast::Call>()) {
      if (c->type && is_matrix(*c->type)) found = true;
      for (const auto& a : c->args)
        if (a->type && is_matrix(*a->type)) found = true;
    }
    if (!found) ast::for_each_child(e, scan);
  };
  if (const auto* d = s.as<ast::VarDecl>()) {
    if (d->var && d->var->type && is_matrix(*d->var->type)) return true;
    if (d->init) scan(*d->init);
  } else if (const auto* a = s.as<ast::Assign>()) {
    for (const auto& t : a->targets)
      if (t->type && is_matrix(*t->type)) return true;
    scan(*a->value);
  }
  return found;
}

std::string run_lines(const std::vector<const ast::Stmt*>& run) {
  const SourceSpan &a = run.front()->span, &b = run.back()->span;
  if (!a.valid() || !b.valid()) return "?";
  return std::to_string(a.start().line) + "-" +
         std::to_string(b.file->locate(b.end > b.begin ? b.end - 1 : b.begin).line);
}

TracedSystem trace_system(const std::vector<const ast::Stmt*>& run, interp::ExecState& in,
                          bool float32) {
  return SystemTracer(run, in, float32).run();
}

}  // namespace simit::jit
