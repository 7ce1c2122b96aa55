// The tracer's private state (class Tracer), shared by the trace/*.cpp files that define its
// member functions by concern: tracer.cpp (state, loads, run), expressions.cpp, products.cpp,
// intrinsics.cpp, statements.cpp and writes.cpp. Only jit/trace_site.h is public.
#pragma once

#include <cmath>
#include <map>
#include <string>
#include <tuple>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include "frontend/ast.h"
#include "jit/ir_build.h"
#include "jit/loop_ir.h"
#include "jit/trace/abort_reasons.h"
#include "jit/trace/builder.h"
#include "jit/trace/sym.h"
#include "jit/trace_site.h"
#include "jit/tunables.h"
#include "jit/zero_fold.h"

namespace simit::jit::trace_detail {

namespace ast = frontend::ast;
using frontend::IndexSet;
using frontend::ScalarKind;
using frontend::SourceSpan;
using frontend::Type;

// Runs one site's mapped function symbolically into a Trace (jit/trace_site.h).
class Tracer {
 public:
  // `fold`: products by known zeros fold away (jit/zero_fold.h).
  Tracer(const SiteShape& shape, bool fold) : in_(shape), build_(fold) {}

  TracedSite run();
  // Whether the folded trace cannot be used (a conflict, or a trace that writes fields).
  bool fold_failed() const { return fold_failed_; }

 private:
  struct Frame {
    std::unordered_map<const ast::Variable*, Sym> vars;
    std::unordered_map<const ast::Variable*, int> bound_at;  // block depth of the binding
    std::unordered_map<const ast::Variable*, std::vector<int>> merged;  // mutable locals
  };
  struct CachedLoad {
    int local;  // the local loaded into; for a whole tiled tensor (comp -1), its scratch array
    int block;
  };

  // Statements and locals.
  void emit(Stmt s) { out_->push_back(std::move(s)); }
  int new_local(Ty ty, bool mut) {
    trace_.locals.push_back(ty);
    mutable_.push_back(mut);
    return static_cast<int>(trace_.locals.size() - 1);
  }
  ExprRef read_local(int l) {
    ExprRef r = build_.leaf(ExprKind::Local, trace_.locals[l], l);
    if (!loose_locals_.count(l)) return r;
    Expr e = *r;
    e.loose = true;
    return make(std::move(e));
  }
  void set_local(int l, ExprRef v, const SourceSpan& at) {
    if (v->loose) loose_locals_.insert(l);
    emit(jit::set_local(l, std::move(v), at));
  }
  // A value that later statements may read: constants, reads of locals nothing rewrites and
  // components of scratch arrays (each is filled once per element, before any read) stay as
  // they are; anything else is computed into a new local now.
  ExprRef settle(const ExprRef& e, const SourceSpan& at) {
    if (is_const(e) || (e->kind == ExprKind::Local && !mutable_[e->slot]) ||
        e->kind == ExprKind::Element || e->kind == ExprKind::Scalar ||
        (e->kind == ExprKind::Scratch && is_const(e->ops[0])))
      return e;
    const int l = new_local(e->ty, false);
    set_local(l, e, at);
    return read_local(l);
  }
  Sym settle(Sym s, const SourceSpan& at) {
    for (ExprRef& e : s.c) e = settle(e, at);
    return s;
  }
  void check_size() {
    if (++statements_ > kMaxTraceStatements) give_up({}, AbortReason::TraceTooLarge);
  }

  // Arrays and scalar arguments.
  int array(ArraySlot a) {
    for (size_t i = 0; i < trace_.arrays.size(); ++i) {
      const ArraySlot& b = trace_.arrays[i];
      if (b.kind == a.kind && b.member == a.member && b.index == a.index)
        return static_cast<int>(i);
    }
    trace_.arrays.push_back(std::move(a));
    return static_cast<int>(trace_.arrays.size() - 1);
  }
  int field_array(int member, const std::string& name, const SourceSpan& at);
  ExprRef scalar_arg(Ty ty, ScalarSource src) {
    for (size_t i = 0; i < sources_.size(); ++i)
      if (sources_[i].partial == src.partial && sources_[i].global == src.global &&
          sources_[i].component == src.component)
        return build_.leaf(ExprKind::Scalar, ty, static_cast<int>(i));
    sources_.push_back(src);
    trace_.scalars.push_back(ty);
    return build_.leaf(ExprKind::Scalar, ty, static_cast<int>(sources_.size() - 1));
  }
  ExprRef member_index(int member) {
    return member == 0 ? build_.leaf(ExprKind::Element, Ty::I32, 0)
                       : build_.leaf(ExprKind::Endpoint, Ty::I32, member - 1);
  }
  const runtime::Set& member_set(int member) const {
    return runtime::member_set(*in_.target, member);
  }

  // Loads of fields, cached per block so that each component is read once.
  ExprRef load(int slot, int member, int comp, const SourceSpan& at);
  Sym load_tensor(int slot, int member, std::vector<int> dims, const SourceSpan& at);
  void forget_loads(int slot) {
    for (auto it = loads_.begin(); it != loads_.end();)
      it = std::get<0>(it->first) == slot ? loads_.erase(it) : std::next(it);
  }

  // Expressions.
  Sym eval(const ast::Expr& e);
  Sym eval_var(const ast::VarRef& r);
  Sym eval_field(const ast::FieldRead& f);
  Sym eval_tuple(const ast::TupleRead& t);
  Sym eval_read(const ast::TensorRead& r);
  Sym eval_binary(const ast::Binary& b);
  Sym eval_compare(const ast::Compare& c);
  Sym eval_call(const ast::Call& c);
  std::vector<Sym> call_user(const ast::Call& c);
  Sym eval_intrinsic(const ast::Call& c);
  std::vector<Sym> decompose(const ast::Call& c);
  int64_t const_int(const ast::Expr& e);
  // One product or addition inside an operation's sum: under float32 rounded to binary32 as
  // the interpreter rounds it (runtime/sum_rounding.h).
  ExprRef in_sum(ExprRef e, const SourceSpan& at) {
    return in_.float32 ? build_.unary(UnOp::Round32, Ty::F64, std::move(e), at) : e;
  }
  ExprRef sum_add(ExprRef s, ExprRef term, const SourceSpan& at) {
    return in_sum(build_.binary(BinOp::Add, Ty::F64, std::move(s), std::move(term), at), at);
  }
  ExprRef sum_mul(ExprRef a, ExprRef b, const SourceSpan& at) {
    return in_sum(build_.binary(BinOp::Mul, Ty::F64, std::move(a), std::move(b), at), at);
  }
  Sym round(Sym s, const SourceSpan& at) {
    if (!in_.float32 || s.kind != Sym::Kind::Tensor || s.ty != Ty::F64) return s;
    for (ExprRef& e : s.c) e = build_.unary(UnOp::Round32, Ty::F64, e, at);
    return s;
  }
  // --check-finite: where the interpreter checks an operation's value (operators and
  // intrinsic calls), a check that every component is finite.
  Sym finite(Sym s, const SourceSpan& at) {
    if (!in_.check_finite || s.kind != Sym::Kind::Tensor || s.ty != Ty::F64) return s;
    s = settle(std::move(s), at);
    ExprRef ok;
    for (const ExprRef& e : s.c) {
      if (is_const(e) && std::isfinite(e->f)) continue;
      ExprRef one =
          build_.compare(CmpOp::Lt, build_.math(MathFn::Abs, {e}, at), fconst(HUGE_VAL), at);
      ok = ok ? build_.binary(BinOp::And, Ty::Bool, ok, one, at) : one;
    }
    if (ok) emit_check(ok, "the operation produced a NaN or an infinity", at);
    return s;
  }
  // A check that `ok` holds: a kernel where it does not stops with error `message`.
  void emit_check(ExprRef ok, std::string message, const SourceSpan& at) {
    trace_.errors.push_back({at, std::move(message)});
    Stmt check;
    check.kind = StmtKind::Check;
    check.value = std::move(ok);
    check.error = static_cast<int>(trace_.errors.size() - 1);
    check.span = at;
    emit(std::move(check));
  }
  // An integer division's or mod's divisors: a check that each is not zero (the interpreter's
  // error, which the controller has it report by running the site again), but for constants
  // known not to be.
  void check_divisors(const Sym& divisor, const char* message, const SourceSpan& at) {
    ExprRef ok;
    for (const ExprRef& d : divisor.c) {
      if (is_const(d) && d->i != 0) continue;
      ExprRef one = build_.compare(CmpOp::Ne, d, iconst(0), at);
      ok = ok ? build_.binary(BinOp::And, Ty::Bool, ok, one, at) : one;
    }
    if (ok) emit_check(ok, message, at);
  }
  Sym read_block(const Sym& base, const ast::TensorRead& r);
  Sym read_matrix_block(const Sym& matrix, const ast::TensorRead& r);
  Sym matrix_arg(int k, const ast::Param& p, const interp::Value& v);
  template <class F>
  void emit_if(ExprRef condition, const SourceSpan& at, F then_body);
  Sym elementwise(BinOp op, const Sym& l, const Sym& r, const SourceSpan& at);
  Sym blocked_product(const Sym& l, bool lrow, const Sym& r, bool rrow, const SourceSpan& at);
  Sym product(const Sym& l, bool lrow, const Sym& r, bool rrow, const SourceSpan& at);
  // Tiled tensors: a product too large to unroll runs as loops over tiles of scratch arrays.
  struct ScratchView {
    int array = -1;           // the scratch array the matrix's components are read from
    bool transposed = false;  // the matrix is the transpose of the array's
  };
  ScratchView scratch_view(const Sym& s) const;
  ScratchView in_scratch(const Sym& s, const SourceSpan& at);
  Sym tiled_product(const Sym& l, const Sym& r, const SourceSpan& at);
  bool tiled_elementwise(BinOp op, const Sym& l, const Sym& r, const SourceSpan& at, Sym& out);
  bool tiled_matvec(const Sym& a, const Sym& x, bool row_vector, const SourceSpan& at, Sym& out);
  bool tiled_outer(const Sym& u, const Sym& v, const SourceSpan& at, Sym& out);
  // A For statement of `trips` iterations whose body `body(k)` emits, k its I32 local.
  template <class F>
  void for_loop(int trips, const SourceSpan& at, F body) {
    Stmt f;
    f.kind = StmtKind::For;
    f.slot = new_local(Ty::I32, false);
    f.n = trips;
    f.span = at;
    std::vector<Stmt>* outer = out_;
    out_ = &f.body;
    body(read_local(f.slot));
    out_ = outer;
    emit(std::move(f));
  }
  void put(int array, ExprRef index, ExprRef value, const SourceSpan& at) {
    Stmt s;
    s.kind = StmtKind::Put;
    s.slot = array;
    s.index = std::move(index);
    s.value = std::move(value);
    s.span = at;
    emit(std::move(s));
  }
  // A scratch array; `loose`: it may hold zeros of the other sign (jit/zero_fold.h), and so
  // may every value read from it.
  int new_scratch(size_t n, bool loose) {
    trace_.scratch.push_back(static_cast<int>(n));
    scratch_loose_.push_back(loose);
    return static_cast<int>(trace_.scratch.size() - 1);
  }
  ExprRef read_scratch(int array, ExprRef index, const SourceSpan& at) {
    ExprRef e = scratch_read(array, std::move(index), at);
    if (!scratch_loose_[static_cast<size_t>(array)]) return e;
    Expr copy = *e;
    copy.loose = true;
    return make(std::move(copy));
  }
  ExprRef local_i32(ExprRef value, const SourceSpan& at) {
    const int l = new_local(Ty::I32, false);
    set_local(l, std::move(value), at);
    return read_local(l);
  }
  ExprRef det(const std::vector<ExprRef>& a, int n, const std::vector<int>& rows,
              const std::vector<int>& cols);

  // Statements.
  void exec_block(const ast::Block& b);
  void exec(const ast::Stmt& s);
  void exec_if(const ast::If& s);
  void exec_if_from(const ast::If& s, size_t first);
  void exec_for(const ast::ForRange& s);
  void exec_error(const SourceSpan& at);
  void assign(const ast::Expr& target, Sym value, const SourceSpan& at);
  void assign_part(const ast::Variable& v, const std::vector<int64_t>& idx,
                   const std::vector<int64_t>* sub, Sym value, const SourceSpan& at);
  void bind(const ast::Variable& v, Sym value, const SourceSpan& at);
  void assign_result(const ast::TensorRead& r, const ast::TensorRead* component, Sym value,
                     const SourceSpan& at);
  void store_field(const ast::FieldRead& f, const std::vector<int64_t>* idx, Sym value,
                   const SourceSpan& at);
  void merge_assigned(const ast::Block& b);
  void merge(const ast::Variable& v, const SourceSpan& at);

  Frame& frame() { return frames_.back(); }

  const SiteShape& in_;
  Builder build_;  // the expression constructors, with this trace's zero folding
  Trace trace_;
  std::vector<ScalarSource> sources_;
  std::vector<bool> mutable_;
  std::vector<Frame> frames_;
  std::vector<Stmt>* out_ = &trace_.body;
  std::vector<int> blocks_{0};            // the blocks open now, outermost first
  std::unordered_set<int> loose_locals_;  // locals set to a loose value (jit/zero_fold.h)
  bool fold_failed_ = false;
  int next_block_ = 1;
  SourceSpan error_at_;  // the first error statement traced
  std::map<std::tuple<int, int, int>, CachedLoad> loads_;
  std::vector<bool> scratch_loose_;  // per scratch array (new_scratch)
  size_t statements_ = 0;
  int inline_depth_ = 0;
};

// An If with no else part whose body then_body() emits.
template <class F>
void Tracer::emit_if(ExprRef condition, const SourceSpan& at, F then_body) {
  Stmt st;
  st.kind = StmtKind::If;
  st.value = std::move(condition);
  st.span = at;
  std::vector<Stmt>* saved = out_;
  out_ = &st.body;
  blocks_.push_back(next_block_++);
  if (ZeroFold* z = build_.fold()) z->open();
  then_body();
  if (ZeroFold* z = build_.fold())
    if (auto check = z->close(trace_.errors, at)) st.body.push_back(std::move(*check));
  blocks_.pop_back();
  out_ = saved;
  emit(std::move(st));
}

}  // namespace simit::jit::trace_detail
