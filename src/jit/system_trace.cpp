// The system tracer (jit/system_trace.h): a run of statements over global vectors and
// system matrices (at most one while loop), lowered statement by statement into vector ops.
#include "jit/system_trace.h"

#include <algorithm>
#include <cstdint>
#include <functional>
#include <map>
#include <set>
#include <utility>

#include "frontend/ast_walk.h"
#include "interp/set_binding.h"
#include "jit/ir_build.h"

namespace simit::jit {

namespace ast = frontend::ast;
using frontend::IndexSet;
using frontend::SourceSpan;
using frontend::Type;
using interp::Value;

namespace {

ExprRef local(int l, Ty ty) {
  Expr e;
  e.kind = ExprKind::Local;
  e.ty = ty;
  e.slot = l;
  return make(e);
}

bool has_set_dim(const Type& t) {
  if (t.kind != Type::Kind::Tensor) return false;
  for (const IndexSet& d : t.dims)
    if (d.kind != IndexSet::Kind::Fixed) return true;
  return false;
}
bool is_vector(const Type& t) { return has_set_dim(t) && t.dims.size() == 1; }
bool is_matrix(const Type& t) { return has_set_dim(t) && t.dims.size() == 2; }
bool is_row(const ast::Expr& e) { return e.type && is_vector(*e.type) && e.type->row; }

class SystemTracer {
 public:
  SystemTracer(const std::vector<const ast::Stmt*>& run, interp::Interpreter& in, bool float32)
      : run_(run), in_(in), float32_(float32) {}

  TracedSystem run() {
    TracedSystem out;
    try {
      collect();
      const ast::While* loop = nullptr;
      for (at_ = 0; at_ < run_.size(); ++at_) {
        const ast::Stmt& s = *run_[at_];
        if (const auto* w = s.as<ast::While>()) {
          if (loop) give_up(s.span, "a second while loop in one run of statements");
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
      // A kernel that reaches an error statement puts the variables back for the interpreter
      // to run the statements again; it could not put a field back.
      if (!t_.errors.empty() && first_field_write_ < run_.size()) {
        at_ = first_field_write_;
        give_up(run_[at_]->span, "a field write in a run that may stop at an error statement");
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

 private:
  struct Mat {
    int row_ptr, cols, values, rows, block;
    int64_t length;
  };

  // "while:LINE" for a loop alone, else "statements:FIRST-LAST".
  void name(const ast::While* loop) {
    if (run_.size() == 1 && loop) {
      t_.name = "while";
      if (loop->span.valid()) t_.name += ":" + std::to_string(loop->span.start().line);
      return;
    }
    t_.name = "statements:" + run_lines(run_);
  }

  void trace_loop(const ast::While& loop) {
    ops_ = &t_.body;
    t_.condition = scalar(*loop.condition);
    if (!t_.body.empty()) give_up(loop.condition->span, "a loop condition over vectors");
    for (const auto& s : loop.body) stmt(*s);
    end_section();
    ops_ = &t_.after;
  }

  // Every sum of the section just traced starts at +0.0 first in it, so that no scalar op
  // stands between a start and its pass: fuse_passes may move the pass up to another loop.
  void end_section() {
    if (starts_.empty()) return;
    VectorOp first;
    first.body = std::move(starts_);
    starts_.clear();
    ops_->insert(ops_->begin(), std::move(first));
  }

  // Every variable the run reads or writes, classified by its type.
  void collect() {
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
      if (!c.like)
        give_up(v->span, "vector '" + v->name + "' has no value and no vector gives its shape");
      b_.created.push_back(c);
    }
  }

  void collect_block(const ast::Block& body, const std::function<void(const ast::Expr&)>& expr) {
    for (const auto& s : body) collect_stmt(*s, expr);
  }
  void collect_stmt(const ast::Stmt& s, const std::function<void(const ast::Expr&)>& expr) {
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
      give_up(s.span, std::string(ast::node_kind_name(s.kind)) + " statements in a compiled loop");
    }
  }

  void note(const ast::Variable& v, const SourceSpan& at) {
    if (scalar_local_.count(&v) || vector_slot_.count(&v) || matrix_.count(&v)) return;
    if (v.kind == ast::Variable::Kind::GlobalConst) return;
    if (!v.type) give_up(at, "'" + v.name + "' has no type");
    const Type& t = *v.type;
    if (t.kind == Type::Kind::Scalar) {
      Ty ty = t.scalar == frontend::ScalarKind::Float ? Ty::F64
              : t.scalar == frontend::ScalarKind::Int ? Ty::I32
              : t.scalar == frontend::ScalarKind::Bool
                  ? Ty::Bool
                  : (give_up(at, "a scalar of this type"), Ty::F64);
      scalar_local_[&v] = static_cast<int>(t_.locals.size());
      t_.locals.push_back(ty);
      b_.scalars.push_back(&v);
      b_.scalar_types.push_back(ty);
      return;
    }
    if (is_vector(t)) {
      if (t.component() != frontend::ScalarKind::Float) give_up(at, "a vector of non-floats");
      vector_slot_[&v] = array(&v, SystemBinding::Array::Part::Vector, Ty::F64, v.name);
      const Value& val = in_.variable(v);
      if (!val.empty()) {
        if (!val.is_tensor() || val.tensor().kind() != runtime::ComponentKind::Float)
          give_up(at, "vector '" + v.name + "' does not hold floats");
        size_of_[&v] = size(&v, false, static_cast<int64_t>(val.tensor().size()));
        block_of_[&v] = static_cast<int>(val.tensor().shape().block_size());
      }
      return;
    }
    if (is_matrix(t)) {
      const Value& val = in_.variable(v);
      if (val.kind() != Value::Kind::Matrix || !val.matrix() || !val.matrix()->is_float())
        give_up(at, "matrix '" + v.name + "' has no float value before the loop");
      const runtime::SystemMatrix& m = *val.matrix();
      if (m.block_rows() != m.block_cols()) give_up(at, "a matrix of non-square blocks");
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
    give_up(at, "'" + v.name + "' of type " + frontend::to_string(t) + " in a compiled loop");
  }

  // `S.f`, a field of a set as a vector: its array, read or written in place (a binary32
  // field widened at each read and rounded at each write, as the interpreter converts it).
  void note_field(const ast::FieldRead& f) {
    const auto* set = f.base->as<ast::VarRef>();
    if (!set) give_up(f.span, "a field of a set expression");
    const FieldKey key{set->var, f.field_index};
    if (field_slot_.count(key)) return;
    const Value& sv = in_.variable(*set->var);
    if (sv.kind() != Value::Kind::Set || !sv.binding() || !sv.binding()->set)
      give_up(f.span, "set '" + set->var->name + "' is not bound");
    const interp::SetBinding& b = *sv.binding();
    const runtime::Field& field = std::as_const(*b.set).field(b.fields[f.field_index]);
    if (field.type().kind != runtime::ComponentKind::Float)
      give_up(f.span, "field '" + f.field + "' does not hold floats");
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
  static std::pair<const ast::Variable*, int> field_key(const ast::FieldRead& f) {
    return {f.base->as<ast::VarRef>()->var, f.field_index};
  }

  int array(const ast::Variable* v, SystemBinding::Array::Part part, Ty ty, std::string name) {
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
  int size(const ast::Variable* v, bool rows, int64_t n, int field = -1) {
    const std::pair<bool, int64_t> key{rows, n};
    if (auto it = sizes_.find(key); it != sizes_.end()) return it->second;
    t_.sizes.push_back((rows ? "block rows of " : "components of ") + v->name + " (" +
                       std::to_string(n) + ")");
    b_.sizes.push_back({v, rows, field});
    size_value_.push_back(n);
    return sizes_[key] = static_cast<int>(t_.sizes.size() - 1);
  }

  // Ops: consecutive scalar statements share one Scalar op.
  void scalar_stmt(Stmt s) {
    if (sink_) return sink_->push_back(std::move(s));
    if (ops_->empty() || ops_->back().kind != VectorOp::Kind::Scalar ||
        ops_->back().guard != guard_) {
      ops_->emplace_back();
      ops_->back().guard = guard_;
    }
    ops_->back().body.push_back(std::move(s));
  }
  // A loop over vectors, under the guard of the branch being traced.
  void push_op(VectorOp op, const SourceSpan& at) {
    if (sink_) give_up(at, "a vector operation inside an if in a compiled loop");
    op.guard = guard_;
    ops_->push_back(std::move(op));
  }
  void set_local(int l, ExprRef v, const SourceSpan& at) {
    Stmt s;
    s.kind = StmtKind::SetLocal;
    s.slot = l;
    s.value = std::move(v);
    s.span = at;
    scalar_stmt(std::move(s));
  }
  int temp(Ty ty) {
    t_.locals.push_back(ty);
    return static_cast<int>(t_.locals.size() - 1);
  }

  int length_of(const ast::Expr& e) {
    if (const auto* r = e.as<ast::VarRef>()) {
      if (auto it = size_of_.find(r->var); it != size_of_.end()) return it->second;
    }
    if (const auto* f = e.as<ast::FieldRead>(); f && f->of_set)
      return field_size_.at(field_key(*f));
    if (const auto* t = e.as<ast::Transpose>()) return length_of(*t->operand);
    if (const auto* b = e.as<ast::Binary>()) {
      const bool lv = b->lhs->type && is_vector(*b->lhs->type);
      return length_of(lv ? *b->lhs : *b->rhs);
    }
    if (const auto* u = e.as<ast::Unary>()) return length_of(*u->operand);
    give_up(e.span, "the length of this vector expression");
  }

  // Components per element of a vector expression: the runs an inner product sums first.
  int group_of(const ast::Expr& e) {
    if (const auto* f = e.as<ast::FieldRead>(); f && f->of_set)
      return field_block_.at(field_key(*f));
    if (const auto* r = e.as<ast::VarRef>()) {
      if (auto it = block_of_.find(r->var); it != block_of_.end()) return it->second;
    }
    if (const auto* t = e.as<ast::Transpose>()) return group_of(*t->operand);
    if (const auto* b = e.as<ast::Binary>()) {
      const bool lv = b->lhs->type && is_vector(*b->lhs->type);
      return group_of(lv ? *b->lhs : *b->rhs);
    }
    if (const auto* u = e.as<ast::Unary>()) return group_of(*u->operand);
    give_up(e.span, "the blocks of this vector expression");
  }

  // u' * v, dot(u, v): a reduction pass into a new local, from +0.0 in storage order, each
  // element's block summed first.
  ExprRef dot(const ast::Expr& u, const ast::Expr& v, const SourceSpan& at) {
    const int n = length_of(u);
    if (length_of(v) != n) give_up(at, "a dot product of vectors of different lengths");
    const int group = group_of(u);
    if (group_of(v) != group || group < 1)
      give_up(at, "a dot product of vectors blocked differently");
    const int t = temp(Ty::F64);
    // The sum starts at +0.0 at the top of every iteration, so that no scalar op stands
    // between the start and its pass: fuse_passes may move the pass up to another loop.
    Stmt start;
    start.kind = StmtKind::SetLocal;
    start.slot = t;
    start.value = fconst(0.0);
    start.span = at;
    starts_.push_back(std::move(start));
    ExprRef a = component(u), b = component(v);
    VectorOp pass;
    pass.kind = VectorOp::Kind::Pass;
    pass.length = n;
    pass.group = group;
    pass.sums = {t};
    Stmt s;
    s.kind = StmtKind::SetLocal;
    s.slot = t;
    s.value = node(ExprKind::Binary, Ty::F64, static_cast<uint8_t>(BinOp::Add),
                   {local(t, Ty::F64),
                    node(ExprKind::Binary, Ty::F64, static_cast<uint8_t>(BinOp::Mul), {a, b}, at)},
                   at);
    s.span = at;
    pass.body.push_back(std::move(s));
    push_op(std::move(pass), at);
    return local(t, Ty::F64);
  }

  // An operator's, call's or literal's value as the interpreter's float32 mode leaves it.
  ExprRef rounded(ExprRef v, const SourceSpan& at) const {
    if (!float32_ || v->ty != Ty::F64) return v;
    if (v->kind == ExprKind::Const) return fconst(static_cast<double>(static_cast<float>(v->f)));
    return node(ExprKind::Unary, Ty::F64, static_cast<uint8_t>(UnOp::Round32), {std::move(v)}, at);
  }
  bool single(int slot) const { return t_.arrays[static_cast<size_t>(slot)].single; }

  Ty scalar_ty(const ast::Expr& e) {
    if (!e.type || e.type->kind != Type::Kind::Scalar)
      give_up(e.span, "a non-scalar where a scalar was expected");
    switch (e.type->scalar) {
      case frontend::ScalarKind::Float: return Ty::F64;
      case frontend::ScalarKind::Int: return Ty::I32;
      case frontend::ScalarKind::Bool: return Ty::Bool;
      default: give_up(e.span, "a scalar of this type");
    }
  }

  ExprRef scalar(const ast::Expr& e) {
    const Ty ty = scalar_ty(e);
    switch (e.kind) {
      case ast::NodeKind::IntLit:
        return iconst(static_cast<int32_t>(e.as<ast::IntLit>()->value), Ty::I32);
      case ast::NodeKind::FloatLit: return rounded(fconst(e.as<ast::FloatLit>()->value), e.span);
      case ast::NodeKind::BoolLit: return iconst(e.as<ast::BoolLit>()->value, Ty::Bool);
      case ast::NodeKind::VarRef: {
        const ast::Variable& v = *e.as<ast::VarRef>()->var;
        if (v.kind == ast::Variable::Kind::GlobalConst) {
          const Value& g = in_.global(v);
          if (g.kind() == Value::Kind::Float) return fconst(g.as_float());
          if (g.kind() == Value::Kind::Int) return iconst(g.as_int(), Ty::I32);
          if (g.kind() == Value::Kind::Bool) return iconst(g.as_bool(), Ty::Bool);
          give_up(e.span, "a constant of this kind");
        }
        auto it = scalar_local_.find(&v);
        if (it == scalar_local_.end()) give_up(e.span, "'" + v.name + "' is not a scalar");
        return local(it->second, ty);
      }
      case ast::NodeKind::Unary: {
        const auto& u = *e.as<ast::Unary>();
        ExprRef x = scalar(*u.operand);
        if (u.op == ast::Unary::Op::Plus) return x;
        if (u.op == ast::Unary::Op::Not)
          return node(ExprKind::Unary, Ty::Bool, static_cast<uint8_t>(UnOp::Not), {x}, e.span);
        if (ty == Ty::F64)
          return node(ExprKind::Unary, Ty::F64, static_cast<uint8_t>(UnOp::Neg), {x}, e.span);
        give_up(e.span, "integer negation in a compiled loop");
      }
      case ast::NodeKind::Binary: {
        const auto& b = *e.as<ast::Binary>();
        using Op = ast::Binary::Op;
        if (b.op == Op::Mul && is_row(*b.lhs) && b.rhs->type && is_vector(*b.rhs->type))
          return rounded(dot(*b.lhs, *b.rhs, e.span), e.span);
        ExprRef l = scalar(*b.lhs), r = scalar(*b.rhs);
        if (l->ty != r->ty) give_up(e.span, "operands of different types");
        BinOp op;
        switch (b.op) {
          case Op::Add: op = BinOp::Add; break;
          case Op::Sub: op = BinOp::Sub; break;
          case Op::Mul:
          case Op::ElemMul: op = BinOp::Mul; break;
          case Op::Div:
          case Op::ElemDiv:
            if (ty == Ty::I32)
              check_divisor(r, "integer division by zero", e.span);
            else if (ty != Ty::F64)
              give_up(e.span, "this division in a compiled loop");
            op = BinOp::Div;
            break;
          case Op::And: op = BinOp::And; break;
          case Op::Or: op = BinOp::Or; break;
          case Op::Xor: op = BinOp::Xor; break;
          default: give_up(e.span, "this operator in a compiled loop");
        }
        return rounded(node(ExprKind::Binary, l->ty, static_cast<uint8_t>(op), {l, r}, e.span),
                       e.span);
      }
      case ast::NodeKind::Compare: {
        const auto& c = *e.as<ast::Compare>();
        std::vector<ExprRef> v;
        for (const auto& o : c.operands) v.push_back(scalar(*o));
        ExprRef result;
        for (size_t i = 0; i < c.ops.size(); ++i) {
          if (v[i]->ty != v[i + 1]->ty || v[i]->ty == Ty::Bool)
            give_up(e.span, "this comparison in a compiled loop");
          ExprRef one = node(ExprKind::Compare, Ty::Bool, static_cast<uint8_t>(c.ops[i]),
                             {v[i], v[i + 1]}, e.span);
          result = result ? node(ExprKind::Binary, Ty::Bool, static_cast<uint8_t>(BinOp::And),
                                 {one, result}, e.span)
                          : one;
        }
        return result;
      }
      case ast::NodeKind::Call: {
        const auto& c = *e.as<ast::Call>();
        using frontend::Intrinsic;
        if (c.intrinsic == Intrinsic::Dot)
          return rounded(dot(*c.args[0], *c.args[1], e.span), e.span);
        if (c.intrinsic == Intrinsic::Norm) {
          ExprRef d = dot(*c.args[0], *c.args[0], e.span);
          return rounded(
              node(ExprKind::Math, Ty::F64, static_cast<uint8_t>(MathFn::Sqrt), {d}, e.span),
              e.span);
        }
        if (c.intrinsic == Intrinsic::Mod) {
          ExprRef x = scalar(*c.args[0]), y = scalar(*c.args[1]);
          if (x->ty != Ty::I32 || y->ty != Ty::I32) give_up(e.span, "mod of non-integers");
          check_divisor(y, "mod by zero", e.span);
          return node(ExprKind::Binary, Ty::I32, static_cast<uint8_t>(BinOp::Mod), {x, y}, e.span);
        }
        MathFn f;
        switch (c.intrinsic) {
          case Intrinsic::Sqrt: f = MathFn::Sqrt; break;
          case Intrinsic::Abs: f = MathFn::Abs; break;
          case Intrinsic::Log: f = MathFn::Log; break;
          case Intrinsic::Exp: f = MathFn::Exp; break;
          case Intrinsic::Max: f = MathFn::Max; break;
          case Intrinsic::Min: f = MathFn::Min; break;
          case Intrinsic::Pow: f = MathFn::Pow; break;
          default: give_up(e.span, "this call in a compiled loop");
        }
        std::vector<ExprRef> args;
        for (const auto& a : c.args) {
          args.push_back(scalar(*a));
          if (args.back()->ty != Ty::F64) give_up(e.span, "a math function of a non-float");
        }
        return rounded(
            node(ExprKind::Math, Ty::F64, static_cast<uint8_t>(f), std::move(args), e.span),
            e.span);
      }
      default: break;
    }
    give_up(e.span, std::string(ast::node_kind_name(e.kind)) + " expressions in a compiled loop");
  }

  // Component k of a vector expression (ExprKind::Element is k).
  ExprRef component(const ast::Expr& e) {
    if (!e.type || !is_vector(*e.type)) return scalar(e);
    switch (e.kind) {
      case ast::NodeKind::VarRef: {
        auto it = vector_slot_.find(e.as<ast::VarRef>()->var);
        if (it == vector_slot_.end()) give_up(e.span, "an unknown vector");
        check_has_value(*e.as<ast::VarRef>()->var, e.span);
        return load(it->second, e.span);
      }
      case ast::NodeKind::FieldRead:
        if (!e.as<ast::FieldRead>()->of_set) break;
        return load(field_slot_.at(field_key(*e.as<ast::FieldRead>())), e.span);
      case ast::NodeKind::Transpose: return component(*e.as<ast::Transpose>()->operand);
      case ast::NodeKind::Unary: {
        const auto& u = *e.as<ast::Unary>();
        ExprRef x = component(*u.operand);
        if (u.op == ast::Unary::Op::Plus) return x;
        if (u.op == ast::Unary::Op::Neg)
          return node(ExprKind::Unary, Ty::F64, static_cast<uint8_t>(UnOp::Neg), {x}, e.span);
        break;
      }
      case ast::NodeKind::Binary: {
        const auto& b = *e.as<ast::Binary>();
        using Op = ast::Binary::Op;
        if (b.op == Op::Mul && b.lhs->type && is_matrix(*b.lhs->type)) return product(b, e.span);
        const bool lv = is_vector(*b.lhs->type), rv = is_vector(*b.rhs->type);
        BinOp op;
        switch (b.op) {
          case Op::Add: op = BinOp::Add; break;
          case Op::Sub: op = BinOp::Sub; break;
          case Op::Mul:
          case Op::ElemMul:
            if (b.op == Op::Mul && lv && rv)
              give_up(e.span, "a product of two vectors inside a vector expression");
            op = BinOp::Mul;
            break;
          case Op::Div:
          case Op::ElemDiv: op = BinOp::Div; break;
          default: give_up(e.span, "this operator on vectors in a compiled loop");
        }
        if ((op == BinOp::Add || op == BinOp::Sub) && !(lv && rv))
          give_up(e.span, "a vector plus a scalar");
        if (lv && rv && length_of(*b.lhs) != length_of(*b.rhs))
          give_up(e.span, "vectors of different lengths");
        ExprRef l = component(*b.lhs), r = component(*b.rhs);
        if (l->ty != Ty::F64 || r->ty != Ty::F64)
          give_up(e.span, "a vector operation on non-floats");
        return rounded(node(ExprKind::Binary, Ty::F64, static_cast<uint8_t>(op), {l, r}, e.span),
                       e.span);
      }
      default: break;
    }
    give_up(e.span,
            std::string(ast::node_kind_name(e.kind)) + " vector expressions in a compiled loop");
  }

  void assign(const ast::Variable& target, const ast::Expr& value, const SourceSpan& at) {
    if (auto it = scalar_local_.find(&target); it != scalar_local_.end()) {
      ExprRef v = scalar(value);
      if (v->ty != t_.locals[it->second]) give_up(at, "an assignment of another type");
      return set_local(it->second, v, at);
    }
    auto vt = vector_slot_.find(&target);
    if (vt == vector_slot_.end()) give_up(at, "an assignment to '" + target.name + "'");
    // The controller makes such a vector before the loop runs, where the interpreter would
    // leave it without a value when the branch does not run (unless the run assigned it
    // before, outside any if).
    if (guard_ >= 0 && !assigned_.count(&target))
      for (const SystemBinding::Created& c : b_.created)
        if (c.var == &target) give_up(at, "a vector first assigned inside an if");
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
  void check_has_value(const ast::Variable& v, const SourceSpan& at) const {
    if (assigned_.count(&v)) return;
    for (const SystemBinding::Created& c : b_.created)
      if (c.var == &v) give_up(at, "'" + v.name + "' is read before it has a value");
  }

  // `S.f = v`: the field's array, written in place.
  void assign_field(const ast::FieldRead& target, const ast::Expr& value, const SourceSpan& at) {
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
  void store_own_product(int slot, int n, const ast::Expr& value, const SourceSpan& at) {
    t_.arrays[slot].written = true;
    store_pass(slot, n, product(*value.as<ast::Binary>(), at), at);
  }

  // `A * x` with A a matrix variable of the run.
  bool is_product(const ast::Expr& value) const {
    const auto* b = value.as<ast::Binary>();
    if (!b || b->op != ast::Binary::Op::Mul) return false;
    const auto* a = b->lhs->as<ast::VarRef>();
    return a && matrix_.count(a->var);
  }

  // Array `slot` (of `n` components) = value: a sparse product `A * x`, or a pass.
  void store_vector(int slot, int n, const ast::Expr& value, const SourceSpan& at) {
    t_.arrays[slot].written = true;
    if (is_product(value)) {
      const auto& b = *value.as<ast::Binary>();
      if (!single(slot))
        return spmv(matrix_.at(b.lhs->as<ast::VarRef>()->var), *b.rhs, slot, n, at);
      // A product writes binary64 rows: a binary32 field takes them through a scratch vector.
      return store_pass(slot, n, product(b, at), at);
    }
    if (value.type && is_vector(*value.type) && length_of(value) != n)
      give_up(at, "an assignment of another length");
    store_pass(slot, n, component(value), at);
  }

  // A pass over `n` components storing `value` (the visited component's) into array `slot`.
  void store_pass(int slot, int n, ExprRef value, const SourceSpan& at) {
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
  void spmv(const Mat& m, const ast::Expr& x, int y, int length, const SourceSpan& at) {
    if (!x.type || !is_vector(*x.type)) give_up(at, "a matrix times something other than a vector");
    const int n = length_of(x);
    if (size_value_[static_cast<size_t>(n)] != m.length ||
        size_value_[static_cast<size_t>(length)] != m.length)
      give_up(at, "a product whose lengths do not match");
    if (group_of(x) != m.block) give_up(at, "vector blocks differ from the matrix's");
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
  ExprRef product(const ast::Binary& b, const SourceSpan& at) {
    const auto* a = b.lhs->as<ast::VarRef>();
    if (!a || !matrix_.count(a->var)) give_up(at, "a product of a matrix expression");
    const Mat& m = matrix_.at(a->var);
    const int n = length_of(*b.rhs);
    const int y = scratch(n);
    spmv(m, *b.rhs, y, n, at);
    return load(y, at);
  }

  // The array slot that holds a vector expression: a vector variable's own, or a scratch
  // vector a pass fills.
  int vector_operand(const ast::Expr& x, int n, const SourceSpan& at) {
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

  int scratch(int n) {
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

  ExprRef load(int slot, const SourceSpan& at) {
    Expr l;
    l.kind = ExprKind::Load;
    l.ty = Ty::F64;
    l.slot = slot;
    l.ops = {element()};
    l.span = at;
    return make(std::move(l));
  }

  // The visited component of a pass.
  static ExprRef element() {
    Expr k;
    k.kind = ExprKind::Element;
    k.ty = Ty::I32;
    return make(k);
  }

  void stmt(const ast::Stmt& s) {
    if (const auto* i = s.as<ast::If>()) return has_vectors(*i) ? guarded_if(*i) : if_stmt(*i, 0);
    if (s.is<ast::Print>()) return error_stmt(s.span);
    if (const auto* d = s.as<ast::VarDecl>()) {
      if (!d->init) give_up(s.span, "a declaration without a value");
      return assign(*d->var, *d->init, s.span);
    }
    const auto& a = *s.as<ast::Assign>();
    if (a.index_notation || a.targets.size() != 1)
      give_up(s.span, "this assignment in a compiled loop");
    if (const auto* f = a.targets[0]->as<ast::FieldRead>(); f && f->of_set)
      return assign_field(*f, *a.value, s.span);
    const auto* target = a.targets[0]->as<ast::VarRef>();
    if (!target) give_up(s.span, "an assignment to part of a variable");
    assign(*target->var, *a.value, s.span);
  }

  // Branch `from` of an if (and the elifs after it, nested in its else) as one If statement
  // of scalar statements. The conditions are traced where the interpreter evaluates them.
  void if_stmt(const ast::If& i, size_t from) {
    Stmt s;
    s.kind = StmtKind::If;
    s.span = i.conditions[from]->span;
    s.value = scalar(*i.conditions[from]);
    if (s.value->ty != Ty::Bool) give_up(s.span, "a condition that is not a boolean");
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
  static bool mentions_vector(const ast::Expr& e) {
    if (e.type && has_set_dim(*e.type)) return true;
    bool found = false;
    ast::for_each_child(e, [&](const ast::Expr& c) { found = found || mentions_vector(c); });
    return found;
  }
  static bool has_vectors(const ast::If& i) {
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
  void guarded_if(const ast::If& i) {
    if (sink_) give_up(i.span, "vector operations inside an if in an if");
    const int outer = guard_;
    const SourceSpan at = i.span;
    auto both = [&](ExprRef a, ExprRef b) {
      return a ? node(ExprKind::Binary, Ty::Bool, static_cast<uint8_t>(BinOp::And), {a, b}, at) : b;
    };
    ExprRef rest = outer >= 0 ? local(outer, Ty::Bool) : nullptr;
    for (size_t k = 0; k < i.conditions.size(); ++k) {
      guard_ = -1;
      ExprRef c = scalar(*i.conditions[k]);
      if (c->ty != Ty::Bool) give_up(i.conditions[k]->span, "a condition that is not a boolean");
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
  void check_divisor(const ExprRef& d, const char* message, const SourceSpan& at) {
    if (d->kind == ExprKind::Const && d->i != 0) return;
    check(node(ExprKind::Compare, Ty::Bool, static_cast<uint8_t>(CmpOp::Ne),
               {d, iconst(0, Ty::I32)}, at),
          message, at);
  }

  // An error statement: a check that always fails. Only the interpreter formats the message,
  // so a kernel that reaches it hands the whole loop back (TraceController::run_loop_kernel).
  void error_stmt(const SourceSpan& at) { check(iconst(0, Ty::Bool), "error statement", at); }

  // A check that `ok` holds; a kernel where it does not hands the loop back.
  void check(ExprRef ok, const char* message, const SourceSpan& at) {
    Stmt s;
    s.kind = StmtKind::Check;
    s.value = std::move(ok);
    s.error = static_cast<int>(t_.errors.size());
    s.span = at;
    t_.errors.push_back({at, message});
    scalar_stmt(std::move(s));
  }

  const std::vector<const ast::Stmt*>& run_;
  interp::Interpreter& in_;
  bool float32_ = false;
  size_t at_ = 0;                        // the statement of the run being collected or traced
  size_t first_field_write_ = SIZE_MAX;  // the first statement that writes a field
  using FieldKey = std::pair<const ast::Variable*, int>;  // a set and its field's index
  std::map<FieldKey, int> field_slot_, field_size_, field_block_;
  std::map<FieldKey, const frontend::Type*> field_type_;
  SystemTrace t_;
  std::vector<VectorOp>* ops_ = &t_.before;  // the section being traced
  SystemBinding b_;
  std::map<const ast::Variable*, int> scalar_local_, vector_slot_, size_of_, block_of_;
  std::map<const ast::Variable*, Mat> matrix_;
  std::map<std::pair<bool, int64_t>, int> sizes_;
  std::vector<int64_t> size_value_;  // per size: the length it was traced for
  int scratch_count_ = 0;
  std::set<const ast::Variable*> assigned_;  // vectors assigned so far outside any if
  std::vector<Stmt>* sink_ = nullptr;        // where scalar statements go inside an if's branch
  int guard_ = -1;            // the Bool local the ops traced now run under (guarded_if), or -1
  std::vector<Stmt> starts_;  // the section's sums' +0.0 starts, first in it
};

}  // namespace

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

TracedSystem trace_system(const std::vector<const ast::Stmt*>& run, interp::Interpreter& in,
                          bool float32) {
  return SystemTracer(run, in, float32).run();
}

}  // namespace simit::jit
