// The tracer (jit/trace_site.h): symbolic execution of a mapped function into loop IR.
#include "jit/trace_site.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <unordered_map>
#include <unordered_set>

#include "frontend/ast_walk.h"
#include "jit/ir_build.h"
#include "jit/tunables.h"
#include "jit/zero_fold.h"

namespace simit::jit {

namespace ast = frontend::ast;
using frontend::IndexSet;
using frontend::ScalarKind;
using frontend::SourceSpan;
using frontend::Type;

namespace {

// ---------------------------------------------------------------------------
// Expression constructors, folding constants as they go.

bool is_const(const ExprRef& e) { return e->kind == ExprKind::Const; }

// The zero folding of the trace being built (null while a site is traced without it); the
// constructors below are free functions shared by every part of the tracer.
thread_local ZeroFold* zero_fold = nullptr;

// A folded constant that keeps its operands' looseness where it is a zero.
ExprRef folded(double v, const ExprRef& a, const ExprRef& b = nullptr) {
  ExprRef c = fconst(v);
  if (zero_fold && v == 0.0 && (a->loose || (b && b->loose))) {
    Expr e = *c;
    e.loose = true;
    return make(std::move(e));
  }
  return c;
}

ExprRef made(Expr e) {
  if (zero_fold) zero_fold->propagate(e);
  return make(std::move(e));
}

ExprRef unary(UnOp op, Ty ty, ExprRef a, SourceSpan at = {}) {
  if (is_const(a)) {
    switch (op) {
      case UnOp::Neg:
        if (ty == Ty::F64) return folded(-a->f, a);
        return iconst(static_cast<int32_t>(0u - static_cast<uint32_t>(a->i)));
      case UnOp::Not: return iconst(!a->i, Ty::Bool);
      case UnOp::Round32: return folded(static_cast<double>(static_cast<float>(a->f)), a);
      case UnOp::ToF64: return fconst(static_cast<double>(a->i));
    }
  }
  Expr e;
  e.kind = ExprKind::Unary;
  e.ty = ty;
  e.op = static_cast<uint8_t>(op);
  e.ops = {std::move(a)};
  e.span = at;
  return made(std::move(e));
}

ExprRef binary(BinOp op, Ty ty, ExprRef a, ExprRef b, SourceSpan at = {}) {
  if (is_const(a) && is_const(b)) {
    if (ty == Ty::F64) {
      if (zero_fold && op == BinOp::Div && b->loose)
        throw FoldConflict{"a division by a value whose zero sign folding may change"};
      switch (op) {
        case BinOp::Add: return folded(a->f + b->f, a, b);
        case BinOp::Sub: return folded(a->f - b->f, a, b);
        case BinOp::Mul: return folded(a->f * b->f, a, b);
        case BinOp::Div: return folded(a->f / b->f, a, b);
        default: break;
      }
    } else if (ty == Ty::I32) {
      const uint32_t x = static_cast<uint32_t>(a->i), y = static_cast<uint32_t>(b->i);
      switch (op) {
        case BinOp::Add: return iconst(static_cast<int32_t>(x + y));
        case BinOp::Sub: return iconst(static_cast<int32_t>(x - y));
        case BinOp::Mul: return iconst(static_cast<int32_t>(x * y));
        // A zero divisor is not folded: its check fails when the code runs.
        case BinOp::Div:
          if (b->i == -1) return iconst(static_cast<int32_t>(0u - x));
          if (b->i != 0) return iconst(a->i / b->i);
          break;
        case BinOp::Mod:
          if (b->i == -1) return iconst(0);
          if (b->i != 0) return iconst(a->i % b->i);
          break;
        default: break;
      }
    } else {
      switch (op) {
        case BinOp::And: return iconst(a->i && b->i, Ty::Bool);
        case BinOp::Or: return iconst(a->i || b->i, Ty::Bool);
        case BinOp::Xor: return iconst((a->i != 0) != (b->i != 0), Ty::Bool);
        default: break;
      }
    }
  }
  if (zero_fold && ty == Ty::F64 && !(is_const(a) && is_const(b)))
    if (ExprRef f = zero_fold->binary(op, a, b)) return f;
  Expr e;
  e.kind = ExprKind::Binary;
  e.ty = ty;
  e.op = static_cast<uint8_t>(op);
  e.ops = {std::move(a), std::move(b)};
  e.span = at;
  return made(std::move(e));
}

ExprRef compare(CmpOp op, ExprRef a, ExprRef b, SourceSpan at = {}) {
  if (is_const(a) && is_const(b)) {
    const bool f = a->ty == Ty::F64;
    const double x = f ? a->f : static_cast<double>(a->i), y = f ? b->f : static_cast<double>(b->i);
    bool r = false;
    switch (op) {
      case CmpOp::Eq: r = x == y; break;
      case CmpOp::Ne: r = x != y; break;
      case CmpOp::Lt: r = x < y; break;
      case CmpOp::Gt: r = x > y; break;
      case CmpOp::Le: r = x <= y; break;
      case CmpOp::Ge: r = x >= y; break;
    }
    return iconst(r, Ty::Bool);
  }
  Expr e;
  e.kind = ExprKind::Compare;
  e.ty = Ty::Bool;
  e.op = static_cast<uint8_t>(op);
  e.ops = {std::move(a), std::move(b)};
  e.span = at;
  return make(std::move(e));
}

ExprRef math(MathFn f, std::vector<ExprRef> args, SourceSpan at) {
  Expr e;
  e.kind = ExprKind::Math;
  e.ty = Ty::F64;
  e.op = static_cast<uint8_t>(f);
  e.ops = std::move(args);
  e.span = at;
  return made(std::move(e));
}

ExprRef leaf(ExprKind k, Ty ty, int slot) {
  Expr e;
  e.kind = k;
  e.ty = ty;
  e.slot = slot;
  return make(std::move(e));
}

// ---------------------------------------------------------------------------
// Symbolic values of the traced function's expressions.

struct Sym {
  enum class Kind { None, Tensor, Element, Tuple, Vector, Matrix, Result };
  Kind kind = Kind::None;
  Ty ty = Ty::F64;
  std::vector<int> dims;   // Tensor: dimensions (none for a scalar); of the blocks if blocked
  std::vector<int> block;  // Tensor: each block's dimensions (none when not blocked)
  // Tensor: components in the runtime's order, row-major within each block and the blocks
  // row-major one after another (runtime/tensor.h).
  std::vector<ExprRef> c;
  int member = -1;     // Element: 0 the visited element, k + 1 its endpoint k
  int slot = -1;       // Vector, Matrix: array slot; Result: result index
  bool inout = false;  // Element: its fields may be written

  size_t size() const { return c.size(); }
  bool scalar() const { return kind == Kind::Tensor && dims.empty(); }
  bool blocked() const { return !block.empty(); }
  size_t block_size() const { return blocked() ? size() / blocks() : 1; }
  size_t blocks() const {
    size_t n = 1;
    for (int d : dims) n *= static_cast<size_t>(d);
    return n;
  }
  bool same_shape(const Sym& o) const { return dims == o.dims && block == o.block; }
};

Sym tensor(Ty ty, std::vector<int> dims, std::vector<ExprRef> c, std::vector<int> block = {}) {
  Sym s;
  s.kind = Sym::Kind::Tensor;
  s.ty = ty;
  s.dims = std::move(dims);
  s.block = std::move(block);
  s.c = std::move(c);
  return s;
}
Sym scalar(Ty ty, ExprRef e) { return tensor(ty, {}, {std::move(e)}); }

Ty ty_of(ScalarKind k, const SourceSpan& at) {
  switch (k) {
    case ScalarKind::Float: return Ty::F64;
    case ScalarKind::Int: return Ty::I32;
    case ScalarKind::Bool: return Ty::Bool;
    default: give_up(at, std::string(frontend::to_string(k)) + " values are not compiled");
  }
}

bool is_blocked(const Type& t) { return t.block && t.block->kind != Type::Kind::Scalar; }

// The fixed outer dimensions of a dense tensor type (none for a scalar).
std::vector<int> outer_dims_of(const Type& t, const SourceSpan& at) {
  if (t.kind == Type::Kind::Scalar) return {};
  if (t.kind != Type::Kind::Tensor)
    give_up(at, "a value of type " + frontend::to_string(t) + " is not compiled");
  std::vector<int> d;
  for (const IndexSet& i : t.dims) {
    if (i.kind != IndexSet::Kind::Fixed) give_up(at, "a tensor over a set is not compiled here");
    d.push_back(i.size);
  }
  return d;
}

// The fixed dimensions of a small unblocked dense tensor type (none for a scalar): fields,
// result blocks and global vectors' blocks.
std::vector<int> dims_of(const Type& t, const SourceSpan& at) {
  if (is_blocked(t)) give_up(at, "a blocked value of type " + frontend::to_string(t) + " here");
  return outer_dims_of(t, at);
}

// The dimensions of each block of a blocked dense tensor type (none when it is not blocked).
std::vector<int> block_dims_of(const Type& t, const SourceSpan& at) {
  if (t.kind != Type::Kind::Tensor || !is_blocked(t)) return {};
  if (is_blocked(*t.block)) give_up(at, "tensors blocked on more than one level are not compiled");
  return outer_dims_of(*t.block, at);
}

// Every component of a dense tensor becomes a value of its own: large ones stay interpreted.
void check_components(size_t n, const SourceSpan& at) {
  if (n > kMaxDenseComponents)
    give_up(at, "a dense tensor of " + std::to_string(n) + " components (more than " +
                    std::to_string(kMaxDenseComponents) + ") is not compiled");
}

Sym zero_of(const Type& t, const SourceSpan& at) {
  const Ty ty = ty_of(t.component(), at);
  std::vector<int> d = outer_dims_of(t, at), b = block_dims_of(t, at);
  size_t n = 1;
  for (int x : d) n *= static_cast<size_t>(x);
  for (int x : b) n *= static_cast<size_t>(x);
  check_components(n, at);
  return tensor(ty, std::move(d),
                std::vector<ExprRef>(n, ty == Ty::F64 ? fconst(0.0) : iconst(0, ty)), std::move(b));
}

// A value bound to a variable of declared type `t` takes the variable's shape, as the
// interpreter stores it: a scalar fills every component of a tensor (`var E :
// matrix[3,3](float) = 0.0;`, `w = 0.0;`, `var w : vector[1](float) = 2.0`). With `reshape`
// (a declaration's initialiser, which the interpreter reshapes) a tensor of as many
// components keeps its components in order under the declared dimensions (`const m :
// tensor[1,3](float) = [1.0, 2.0, 3.0]`). Values of other kinds (elements, sets, system
// tensors) and tensors over sets are left as they are.
Sym as_declared(Sym value, const Type& t, const SourceSpan& at, bool reshape = false) {
  if (value.kind != Sym::Kind::Tensor || t.kind != Type::Kind::Tensor) return value;
  for (const IndexSet& i : t.dims)
    if (i.kind != IndexSet::Kind::Fixed) return value;
  if (is_blocked(t) && is_blocked(*t.block)) return value;  // the tracer gives up on it later
  Sym shape = zero_of(t, at);
  if (value.same_shape(shape)) return value;
  if (value.scalar()) {
    for (ExprRef& c : shape.c) c = value.c[0];
    shape.ty = value.ty;
    return shape;
  }
  if (!reshape) return value;
  if (value.size() != shape.size())
    give_up(at, "a value of " + std::to_string(value.size()) +
                    " components bound to a variable of " + std::to_string(shape.size()));
  value.dims = std::move(shape.dims);
  value.block = std::move(shape.block);
  return value;
}

// For each component of a blocked matrix or vector in its logical (unblocked) row-major
// order, its position in the blocked order: runtime::unblock's permutation for two levels.
std::vector<size_t> logical_positions(const Sym& s) {
  const size_t bs = s.block_size();
  std::vector<size_t> at;
  at.reserve(s.size());
  if (s.dims.size() == 1) {
    for (size_t k = 0; k < s.size(); ++k) at.push_back(k);
    return at;
  }
  const int cols = s.dims[1], br = s.block[0], bc = s.block[1];
  for (int r = 0; r < s.dims[0] * br; ++r)
    for (int c = 0; c < cols * bc; ++c)
      at.push_back((static_cast<size_t>(r / br) * cols + c / bc) * bs +
                   static_cast<size_t>(r % br) * bc + c % bc);
  return at;
}

// Whether a blocked tensor has an unblocked form the tracer handles: its blocks have as many
// dimensions as it has (runtime::Shape::uniform), and it is a vector or a matrix.
bool has_logical_form(const Sym& s) {
  return s.blocked() && s.block.size() == s.dims.size() && s.dims.size() <= 2;
}

// The unblocked form of a blocked tensor (has_logical_form), and back.
Sym unblocked(const Sym& s) {
  std::vector<ExprRef> c;
  for (size_t p : logical_positions(s)) c.push_back(s.c[p]);
  std::vector<int> d;
  for (size_t k = 0; k < s.dims.size(); ++k) d.push_back(s.dims[k] * s.block[k]);
  return tensor(s.ty, std::move(d), std::move(c));
}
Sym reblocked(const Sym& logical, std::vector<int> dims, std::vector<int> block) {
  Sym s = tensor(logical.ty, std::move(dims), logical.c, std::move(block));
  const std::vector<size_t> at = logical_positions(s);
  for (size_t k = 0; k < at.size(); ++k) s.c[at[k]] = logical.c[k];
  return s;
}

// Constants of the program (and the literal values of externs, for their shapes).
Sym const_of(const interp::Value& v, const SourceSpan& at) {
  using K = interp::Value::Kind;
  switch (v.kind()) {
    case K::Float: return scalar(Ty::F64, fconst(v.as_float()));
    case K::Int: return scalar(Ty::I32, iconst(v.as_int()));
    case K::Bool: return scalar(Ty::Bool, iconst(v.as_bool(), Ty::Bool));
    case K::Tensor: {
      const runtime::Tensor& t = v.tensor();
      if (t.shape().is_blocked()) give_up(at, "blocked constants are not compiled");
      check_components(t.size(), at);
      std::vector<int> dims;
      for (int i = 0; i < t.shape().order(); ++i) dims.push_back(t.shape().dim(i));
      std::vector<ExprRef> c;
      for (size_t i = 0; i < t.size(); ++i) {
        switch (t.kind()) {
          case runtime::ComponentKind::Float: c.push_back(fconst(t.floats()[i])); break;
          case runtime::ComponentKind::Int: c.push_back(iconst(t.ints()[i])); break;
          case runtime::ComponentKind::Bool: c.push_back(iconst(t.bools()[i], Ty::Bool)); break;
          default: give_up(at, "constants of this component type are not compiled");
        }
      }
      const Ty ty = t.kind() == runtime::ComponentKind::Float ? Ty::F64
                    : t.kind() == runtime::ComponentKind::Int ? Ty::I32
                                                              : Ty::Bool;
      return tensor(ty, std::move(dims), std::move(c));
    }
    default: give_up(at, "a constant of this kind is not compiled");
  }
}

// Row-major offset of constant indices into dims.
size_t offset_of(const std::vector<int>& dims, const std::vector<int64_t>& idx,
                 const SourceSpan& at) {
  size_t off = 0;
  for (size_t k = 0; k < dims.size(); ++k) {
    if (idx[k] < 0 || idx[k] >= dims[k]) give_up(at, "index out of range");
    off = off * static_cast<size_t>(dims[k]) + static_cast<size_t>(idx[k]);
  }
  return off;
}

// ---------------------------------------------------------------------------

ExprRef scratch_read(int array, ExprRef index, const SourceSpan& at) {
  Expr e;
  e.kind = ExprKind::Scratch;
  e.ty = Ty::F64;
  e.slot = array;
  e.ops = {std::move(index)};
  e.span = at;
  return make(std::move(e));
}

class Tracer {
 public:
  Tracer(const SiteShape& shape, bool fold) : in_(shape), fold_(fold) {}

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
    ExprRef r = leaf(ExprKind::Local, trace_.locals[l], l);
    if (!loose_locals_.count(l)) return r;
    Expr e = *r;
    e.loose = true;
    return make(std::move(e));
  }
  void set_local(int l, ExprRef v, const SourceSpan& at) {
    if (v->loose) loose_locals_.insert(l);
    Stmt s;
    s.kind = StmtKind::SetLocal;
    s.slot = l;
    s.value = std::move(v);
    s.span = at;
    emit(std::move(s));
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
    if (++statements_ > kMaxTraceStatements) give_up({}, "the trace is too large to compile");
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
        return leaf(ExprKind::Scalar, ty, static_cast<int>(i));
    sources_.push_back(src);
    trace_.scalars.push_back(ty);
    return leaf(ExprKind::Scalar, ty, static_cast<int>(sources_.size() - 1));
  }
  ExprRef member_index(int member) {
    return member == 0 ? leaf(ExprKind::Element, Ty::I32, 0)
                       : leaf(ExprKind::Endpoint, Ty::I32, member - 1);
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
  Sym round(Sym s, const SourceSpan& at) {
    if (!in_.float32 || s.kind != Sym::Kind::Tensor || s.ty != Ty::F64) return s;
    for (ExprRef& e : s.c) e = unary(UnOp::Round32, Ty::F64, e, at);
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
      ExprRef one = compare(CmpOp::Lt, math(MathFn::Abs, {e}, at), fconst(HUGE_VAL), at);
      ok = ok ? binary(BinOp::And, Ty::Bool, ok, one, at) : one;
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
      ExprRef one = compare(CmpOp::Ne, d, iconst(0), at);
      ok = ok ? binary(BinOp::And, Ty::Bool, ok, one, at) : one;
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
  Trace trace_;
  std::vector<ScalarSource> sources_;
  std::vector<bool> mutable_;
  std::vector<Frame> frames_;
  std::vector<Stmt>* out_ = &trace_.body;
  std::vector<int> blocks_{0};            // the blocks open now, outermost first
  std::unordered_set<int> loose_locals_;  // locals set to a loose value (jit/zero_fold.h)
  bool fold_ = false, fold_failed_ = false;
  int next_block_ = 1;
  SourceSpan error_at_;  // the first error statement traced
  std::map<std::tuple<int, int, int>, CachedLoad> loads_;
  std::vector<bool> scratch_loose_;  // per scratch array (new_scratch)
  size_t statements_ = 0;
  int inline_depth_ = 0;
};

int Tracer::field_array(int member, const std::string& name, const SourceSpan& at) {
  const runtime::Set& s = member_set(member);
  const int f = s.field_index(name);
  if (f < 0) give_up(at, "field '" + name + "' is not bound");
  const runtime::FieldType& ft = s.field(f).type();
  ArraySlot a;
  a.kind = ArraySlot::Kind::Field;
  a.member = member;
  a.index = f;
  switch (ft.kind) {
    case runtime::ComponentKind::Float: a.ty = Ty::F64; break;
    case runtime::ComponentKind::Int: a.ty = Ty::I32; break;
    case runtime::ComponentKind::Bool: a.ty = Ty::Bool; break;
    default: give_up(at, "fields of this component type are not compiled");
  }
  a.single = ft.single;
  a.components = static_cast<int>(ft.components());
  a.name = s.name() + "." + name;
  return array(std::move(a));
}

ExprRef Tracer::load(int slot, int member, int comp, const SourceSpan& at) {
  const auto key = std::make_tuple(slot, member, comp);
  if (auto it = loads_.find(key); it != loads_.end()) {
    if (std::find(blocks_.begin(), blocks_.end(), it->second.block) != blocks_.end())
      return read_local(it->second.local);
  }
  Expr e;
  e.kind = ExprKind::Load;
  e.ty = trace_.arrays[slot].ty;
  e.slot = slot;
  e.comp = comp;
  e.ops = {member_index(member)};
  e.span = at;
  const int l = new_local(e.ty, false);
  set_local(l, make(std::move(e)), at);
  loads_[key] = {l, blocks_.back()};
  return read_local(l);
}

// ---------------------------------------------------------------------------
// Expressions

int64_t Tracer::const_int(const ast::Expr& e) {
  Sym s = eval(e);
  if (!s.scalar() || !is_const(s.c[0]) || s.ty != Ty::I32)
    give_up(e.span, "an index that is not a constant");
  return s.c[0]->i;
}

Sym Tracer::eval(const ast::Expr& e) {
  switch (e.kind) {
    case ast::NodeKind::IntLit:
      return scalar(Ty::I32,
                    iconst(static_cast<int32_t>(static_cast<const ast::IntLit&>(e).value)));
    case ast::NodeKind::FloatLit:
      return round(scalar(Ty::F64, fconst(static_cast<const ast::FloatLit&>(e).value)), e.span);
    case ast::NodeKind::BoolLit:
      return scalar(Ty::Bool, iconst(static_cast<const ast::BoolLit&>(e).value, Ty::Bool));
    case ast::NodeKind::DenseLit: {
      const auto& d = static_cast<const ast::DenseLit&>(e);
      check_components(d.component == ScalarKind::Float ? d.floats.size() : d.ints.size(), e.span);
      std::vector<ExprRef> c;
      if (d.component == ScalarKind::Float) {
        for (double v : d.floats) c.push_back(fconst(v));
        return round(tensor(Ty::F64, d.shape, std::move(c)), e.span);
      }
      if (d.component == ScalarKind::Int) {
        for (long long v : d.ints) c.push_back(iconst(static_cast<int32_t>(v)));
        return tensor(Ty::I32, d.shape, std::move(c));
      }
      give_up(e.span, "complex literals are not compiled");
    }
    case ast::NodeKind::VarRef: return eval_var(static_cast<const ast::VarRef&>(e));
    case ast::NodeKind::FieldRead: return eval_field(static_cast<const ast::FieldRead&>(e));
    case ast::NodeKind::TupleRead: return eval_tuple(static_cast<const ast::TupleRead&>(e));
    case ast::NodeKind::TensorRead: return eval_read(static_cast<const ast::TensorRead&>(e));
    case ast::NodeKind::Unary: {
      const auto& u = static_cast<const ast::Unary&>(e);
      Sym x = eval(*u.operand);
      if (x.kind != Sym::Kind::Tensor) give_up(e.span, "unary operator on a non-tensor");
      if (u.op == ast::Unary::Op::Plus) return x;
      if (u.op == ast::Unary::Op::Not) {
        if (x.ty != Ty::Bool) give_up(e.span, "not of a non-boolean");
        for (ExprRef& c : x.c) c = unary(UnOp::Not, Ty::Bool, c, e.span);
        return x;
      }
      if (x.ty == Ty::Bool) give_up(e.span, "negation of a boolean");
      for (ExprRef& c : x.c) c = unary(UnOp::Neg, x.ty, c, e.span);
      return x;
    }
    case ast::NodeKind::Binary: return eval_binary(static_cast<const ast::Binary&>(e));
    case ast::NodeKind::Compare: return eval_compare(static_cast<const ast::Compare&>(e));
    case ast::NodeKind::Transpose: {
      Sym x = eval(*static_cast<const ast::Transpose&>(e).operand);
      if (x.kind != Sym::Kind::Tensor) give_up(e.span, "transpose of a non-tensor");
      if (x.dims.size() <= 1) return x;
      if (x.dims.size() != 2) give_up(e.span, "transpose of a tensor of order 3 or more");
      if (x.blocked() && !has_logical_form(x))
        give_up(e.span, "transpose of a matrix whose blocks are not matrices");
      // A blocked matrix swaps its blocks and each block's dimensions (runtime::transpose):
      // the transpose of its unblocked form.
      const Sym l = x.blocked() ? unblocked(x) : x;
      const int m = l.dims[0], n = l.dims[1];
      std::vector<ExprRef> c(l.c.size());
      for (int i = 0; i < m; ++i)
        for (int j = 0; j < n; ++j)
          c[static_cast<size_t>(j) * m + i] = l.c[static_cast<size_t>(i) * n + j];
      Sym t = tensor(x.ty, {n, m}, std::move(c));
      if (!x.blocked()) return t;
      return reblocked(t, {x.dims[1], x.dims[0]}, {x.block[1], x.block[0]});
    }
    case ast::NodeKind::Call: return eval_call(static_cast<const ast::Call&>(e));
    default: break;
  }
  give_up(e.span, std::string(ast::node_kind_name(e.kind)) + " expressions are not compiled");
}

Sym Tracer::eval_var(const ast::VarRef& r) {
  const ast::Variable& v = *r.var;
  using K = ast::Variable::Kind;
  if (v.kind == K::GlobalConst || v.kind == K::Extern) {
    const interp::Value* g = in_.global(v);
    if (!g || g->empty()) give_up(r.span, "global '" + v.name + "' has no value");
    Sym s = const_of(*g, r.span);
    if (v.kind == K::Extern)  // externs may change between calls: read them at each call
      for (size_t i = 0; i < s.c.size(); ++i)
        s.c[i] = scalar_arg(s.ty, {-1, &v, static_cast<int>(i)});
    return s;
  }
  auto it = frame().vars.find(&v);
  if (it == frame().vars.end()) give_up(r.span, "'" + v.name + "' is read before it is set");
  if (it->second.kind == Sym::Kind::Result)
    give_up(r.span, "reading a result of the mapped function");
  return it->second;
}

Sym Tracer::eval_field(const ast::FieldRead& f) {
  if (f.of_set) give_up(f.span, "reading a whole set field");
  Sym base = eval(*f.base);
  if (base.kind != Sym::Kind::Element) give_up(f.span, "a field of something other than a member");
  const int slot = field_array(base.member, f.field, f.span);
  return load_tensor(slot, base.member, dims_of(*f.type, f.span), f.span);
}

// The components of array `slot` at a member as a tensor: each loaded once (cached per
// block); a float tensor of more than kTileAbove components by one loop into a scratch array.
Sym Tracer::load_tensor(int slot, int member, std::vector<int> dims, const SourceSpan& at) {
  const ArraySlot& a = trace_.arrays[slot];
  const size_t n = static_cast<size_t>(a.components);
  std::vector<ExprRef> c;
  if (a.ty != Ty::F64 || n <= kTileAbove) {
    for (int k = 0; k < a.components; ++k) c.push_back(load(slot, member, k, at));
    return tensor(a.ty, std::move(dims), std::move(c));
  }
  const auto key = std::make_tuple(slot, member, -1);
  auto it = loads_.find(key);
  if (it == loads_.end() ||
      std::find(blocks_.begin(), blocks_.end(), it->second.block) == blocks_.end()) {
    const int array = new_scratch(n, false);
    for_loop(a.components, at, [&](const ExprRef& k) {
      Expr e;
      e.kind = ExprKind::Load;
      e.ty = Ty::F64;
      e.slot = slot;
      e.ops = {member_index(member), k};
      e.span = at;
      put(array, k, make(std::move(e)), at);
    });
    it = loads_.insert_or_assign(key, CachedLoad{array, blocks_.back()}).first;
  }
  for (size_t k = 0; k < n; ++k)
    c.push_back(read_scratch(it->second.local, iconst(static_cast<int64_t>(k)), at));
  return tensor(Ty::F64, std::move(dims), std::move(c));
}

Sym Tracer::eval_tuple(const ast::TupleRead& t) {
  Sym base = eval(*t.base);
  if (base.kind != Sym::Kind::Tuple) give_up(t.span, "a tuple other than the endpoints");
  const int64_t k = t.index ? const_int(*t.index) : t.member_index;
  if (k < 0 || k >= trace_.arity) give_up(t.span, "endpoint index out of range");
  Sym s;
  s.kind = Sym::Kind::Element;
  s.member = static_cast<int>(k) + 1;
  return s;
}

Sym Tracer::eval_read(const ast::TensorRead& r) {
  if (r.index_notation) give_up(r.span, "index notation is not compiled");
  Sym base = eval(*r.base);
  if (base.kind == Sym::Kind::Vector) {
    // `f(p)`: the block of a global vector argument at a member.
    if (r.indices.size() != 1 || !r.indices[0])
      give_up(r.span, "a global vector read that is not at a member");
    Sym at = eval(*r.indices[0]);
    if (at.kind != Sym::Kind::Element)
      give_up(r.span, "a global vector read that is not at a member");
    return load_tensor(base.slot, at.member, dims_of(*r.type, r.span), r.span);
  }
  if (base.kind == Sym::Kind::Matrix) return read_matrix_block(base, r);
  if (base.kind != Sym::Kind::Tensor) give_up(r.span, "reading from this value is not compiled");
  if (r.indices.size() != base.dims.size()) give_up(r.span, "index count does not match");
  if (base.blocked()) return read_block(base, r);
  // Constant indices and slices: the result keeps the sliced dimensions.
  std::vector<int64_t> fixed(r.indices.size(), -1);
  std::vector<int> out_dims;
  for (size_t k = 0; k < r.indices.size(); ++k) {
    if (r.indices[k])
      fixed[k] = const_int(*r.indices[k]);
    else
      out_dims.push_back(base.dims[k]);
  }
  std::vector<ExprRef> c;
  std::vector<int64_t> idx(fixed.size(), 0);
  for (size_t k = 0; k < fixed.size(); ++k) idx[k] = fixed[k] >= 0 ? fixed[k] : 0;
  while (true) {
    c.push_back(base.c[offset_of(base.dims, idx, r.span)]);
    int k = static_cast<int>(idx.size()) - 1;
    for (; k >= 0; --k) {
      if (fixed[k] >= 0) continue;
      if (++idx[k] < base.dims[k]) break;
      idx[k] = 0;
    }
    if (k < 0) break;
  }
  return tensor(base.ty, std::move(out_dims), std::move(c));
}

// `A(i, j)`: one block of a blocked tensor, as a tensor of the block's shape.
Sym Tracer::read_block(const Sym& base, const ast::TensorRead& r) {
  std::vector<int64_t> idx;
  for (const auto& i : r.indices) {
    if (!i) give_up(r.span, "slices of blocked tensors are not compiled");
    idx.push_back(const_int(*i));
  }
  const size_t bs = base.block_size(), first = offset_of(base.dims, idx, r.span) * bs;
  return tensor(base.ty, base.block,
                std::vector<ExprRef>(base.c.begin() + static_cast<std::ptrdiff_t>(first),
                                     base.c.begin() + static_cast<std::ptrdiff_t>(first + bs)));
}

// `A(p, q)` of a global matrix argument at two members of the element: the block where the
// controller's position table finds it in A's pattern, zero outside it (as the interpreter).
Sym Tracer::read_matrix_block(const Sym& matrix, const ast::TensorRead& r) {
  if (r.indices.size() != 2 || !r.indices[0] || !r.indices[1])
    give_up(r.span, "a global matrix read that is not one block");
  const Sym row = eval(*r.indices[0]), col = eval(*r.indices[1]);
  if (row.kind != Sym::Kind::Element || col.kind != Sym::Kind::Element)
    give_up(r.span, "a global matrix read that is not at members of the element");
  const int arg = trace_.arrays[matrix.slot].index;
  const std::string name = trace_.arrays[matrix.slot].name + ".positions";
  const int table = array({ArraySlot::Kind::Positions, 0, arg, Ty::I32, false, false, 0, name, {}});
  std::vector<std::pair<int, int>>& reads = trace_.arrays[table].reads;
  const std::pair<int, int> pair{row.member, col.member};
  auto found = std::find(reads.begin(), reads.end(), pair);
  const int comp = static_cast<int>(found - reads.begin());
  if (found == reads.end()) reads.push_back(pair);
  trace_.arrays[table].components = static_cast<int>(reads.size());
  const ExprRef pos = load(table, 0, comp, r.span);
  const int bs = trace_.arrays[matrix.slot].components;
  std::vector<int> locals;
  std::vector<ExprRef> c;
  for (int k = 0; k < bs; ++k) {
    locals.push_back(new_local(Ty::F64, true));
    set_local(locals.back(), fconst(0.0), r.span);
  }
  emit_if(compare(CmpOp::Ge, pos, iconst(0), r.span), r.span, [&] {
    for (int k = 0; k < bs; ++k) {
      Expr e;
      e.kind = ExprKind::Load;
      e.ty = Ty::F64;
      e.slot = matrix.slot;
      e.comp = k;
      e.ops = {pos};
      e.span = r.span;
      set_local(locals[static_cast<size_t>(k)], make(std::move(e)), r.span);
    }
  });
  for (int l : locals) c.push_back(read_local(l));
  Sym out = tensor(Ty::F64, dims_of(*r.type, r.span), std::move(c));
  if (out.size() != static_cast<size_t>(bs)) give_up(r.span, "a matrix block of another shape");
  return out;
}

Sym Tracer::elementwise(BinOp op, const Sym& l, const Sym& r, const SourceSpan& at) {
  if (l.ty != r.ty) give_up(at, "operands of different component types");
  if (!l.scalar() && !r.scalar() && !l.same_shape(r))
    give_up(at, "element-wise operation on different shapes");
  if (Sym tiled; tiled_elementwise(op, l, r, at, tiled)) return tiled;
  const Sym& shape = l.scalar() ? r : l;
  std::vector<ExprRef> c;
  for (size_t i = 0; i < shape.size(); ++i)
    c.push_back(binary(op, l.ty, l.scalar() ? l.c[0] : l.c[i], r.scalar() ? r.c[0] : r.c[i], at));
  return tensor(l.ty, shape.dims, std::move(c), shape.block);
}

// Products sum from +0.0 over k in ascending order (docs/arithmetic.md); an outer product
// is one rounding per component.
Sym Tracer::product(const Sym& l, bool lrow, const Sym& r, bool rrow, const SourceSpan& at) {
  if (l.ty != Ty::F64 || r.ty != Ty::F64)
    give_up(at, "products of non-float tensors are not compiled");
  auto sum = [&](int n, auto term) {
    ExprRef s = fconst(0.0);
    for (int k = 0; k < n; ++k) s = binary(BinOp::Add, Ty::F64, s, term(k), at);
    return s;
  };
  auto mul = [&](const ExprRef& a, const ExprRef& b) {
    return binary(BinOp::Mul, Ty::F64, a, b, at);
  };
  const size_t lo = l.dims.size(), ro = r.dims.size();
  if (lo == 1 && ro == 1) {
    const int n = l.dims[0], m = r.dims[0];
    if (lrow && !rrow) {
      if (n != m) give_up(at, "inner product of different lengths");
      return scalar(Ty::F64, sum(n, [&](int k) { return mul(l.c[k], r.c[k]); }));
    }
    if (lrow || !rrow) give_up(at, "product of two vectors of the same orientation");
    if (Sym tiled; tiled_outer(l, r, at, tiled)) return tiled;
    check_components(static_cast<size_t>(n) * m, at);
    std::vector<ExprRef> c;
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < m; ++j) c.push_back(mul(l.c[i], r.c[j]));
    return tensor(Ty::F64, {n, m}, std::move(c));
  }
  if (lo == 2 && ro == 1) {
    const int m = l.dims[0], n = l.dims[1];
    if (r.dims[0] != n) give_up(at, "matrix-vector dimensions do not match");
    if (Sym tiled; tiled_matvec(l, r, false, at, tiled)) return tiled;
    std::vector<ExprRef> c;
    for (int i = 0; i < m; ++i)
      c.push_back(sum(n, [&](int k) { return mul(l.c[i * n + k], r.c[k]); }));
    return tensor(Ty::F64, {m}, std::move(c));
  }
  if (lo == 1 && ro == 2) {
    const int n = r.dims[0], m = r.dims[1];
    if (l.dims[0] != n) give_up(at, "vector-matrix dimensions do not match");
    if (Sym tiled; tiled_matvec(r, l, true, at, tiled)) return tiled;
    std::vector<ExprRef> c;
    for (int j = 0; j < m; ++j)
      c.push_back(sum(n, [&](int k) { return mul(l.c[k], r.c[k * m + j]); }));
    return tensor(Ty::F64, {m}, std::move(c));
  }
  if (lo == 2 && ro == 2) {
    const int m = l.dims[0], n = l.dims[1], p = r.dims[1];
    if (r.dims[0] != n) give_up(at, "matrix dimensions do not match");
    if (static_cast<size_t>(m) * n * p > kMaxUnrolledProduct) return tiled_product(l, r, at);
    std::vector<ExprRef> c;
    for (int i = 0; i < m; ++i)
      for (int j = 0; j < p; ++j)
        c.push_back(sum(n, [&](int k) { return mul(l.c[i * n + k], r.c[k * p + j]); }));
    return tensor(Ty::F64, {m, p}, std::move(c));
  }
  give_up(at, "products of tensors of order 3 or more are not compiled");
}

ExprRef i32_add(ExprRef a, int64_t k, const SourceSpan& at) {
  return k == 0 ? a : binary(BinOp::Add, Ty::I32, std::move(a), iconst(k), at);
}
ExprRef i32_mul(ExprRef a, int64_t k, const SourceSpan& at) {
  return binary(BinOp::Mul, Ty::I32, std::move(a), iconst(k), at);
}

// The largest tile extent up to kTile that divides n, so that every tile is whole.
int tile_extent(int n) {
  for (int t = std::min(n, kTile); t > 1; --t)
    if (n % t == 0) return t;
  return 1;
}

// Whether tensor s reads its components from one scratch array in order (a matrix also
// transposed), component k at a constant position.
Tracer::ScratchView Tracer::scratch_view(const Sym& s) const {
  if (s.kind != Sym::Kind::Tensor || s.blocked() || s.dims.empty() || s.c.empty() ||
      s.c[0]->kind != ExprKind::Scratch)
    return {};
  const int array = s.c[0]->slot;
  if (static_cast<size_t>(trace_.scratch[static_cast<size_t>(array)]) != s.size()) return {};
  auto at = [&](size_t k, size_t want) {
    const Expr& e = *s.c[k];
    return e.kind == ExprKind::Scratch && e.slot == array && is_const(e.ops[0]) &&
           static_cast<size_t>(e.ops[0]->i) == want &&
           e.loose == scratch_loose_[static_cast<size_t>(array)];
  };
  if (s.dims.size() != 2) {
    for (size_t k = 0; k < s.size(); ++k)
      if (!at(k, k)) return {};
    return {array, false};
  }
  const size_t rows = static_cast<size_t>(s.dims[0]), cols = static_cast<size_t>(s.dims[1]);
  bool straight = true, transposed = true;
  for (size_t i = 0; i < rows; ++i)
    for (size_t j = 0; j < cols; ++j) {
      straight = straight && at(i * cols + j, i * cols + j);
      transposed = transposed && at(i * cols + j, j * rows + i);
    }
  if (straight) return {array, false};
  if (transposed) return {array, true};
  return {};
}

// Tensor s in a scratch array: where it already lies, or put there now.
Tracer::ScratchView Tracer::in_scratch(const Sym& s, const SourceSpan& at) {
  if (ScratchView v = scratch_view(s); v.array >= 0) return v;
  // A zero folded into a component may have the other sign (jit/zero_fold.h): the array is
  // loose, and so is what is computed from it.
  bool loose = false;
  for (const ExprRef& e : s.c) loose = loose || e->loose;
  const int array = new_scratch(s.size(), loose);
  for (size_t k = 0; k < s.size(); ++k) {
    put(array, iconst(static_cast<int64_t>(k)), s.c[k], at);
    check_size();
  }
  return {array, false};
}

// An element-wise operation on a matrix of more than kTileAbove components whose operands lie
// in scratch arrays in order (a tiled product's result, a scalar; an unrolled operand beside
// one in a scratch array is put into one): one loop over the components into a new scratch
// array, each the interpreter's one operation. False where it does not apply (the operation
// is then unrolled).
bool Tracer::tiled_elementwise(BinOp op, const Sym& l, const Sym& r, const SourceSpan& at,
                               Sym& out) {
  const Sym& shape = l.scalar() ? r : l;
  if (l.ty != Ty::F64 || shape.size() <= kTileAbove) return false;
  // -1: one value for every component (a scalar, or a tensor of one constant, as a sum that
  // starts from zeros is); -2: neither that nor a scratch array.
  auto array_of = [&](const Sym& s) {
    if (!s.scalar()) {
      const ScratchView v = scratch_view(s);
      if (v.array >= 0) return v.transposed ? -2 : v.array;
    }
    if (s.c[0]->loose) return -2;  // a loose zero folds: not here
    if (s.scalar()) return -1;
    for (const ExprRef& e : s.c)
      if (!is_const(e) || e->loose || std::memcmp(&e->f, &s.c[0]->f, sizeof(double)) != 0)
        return -2;
    return -1;
  };
  int la = array_of(l), ra = array_of(r);
  if ((la < 0 && ra < 0) || (la == -2 && ra == -2)) return false;
  // One operand in a scratch array, the other unrolled: the other joins it there, so that a
  // chain of operations on a tiled result stays one loop each.
  auto join = [&](const Sym& s, int& a) {
    if (a != -2 || s.scalar() || scratch_view(s).array >= 0) return a != -2;
    a = in_scratch(s, at).array;
    return true;
  };
  if (!join(l, la) || !join(r, ra)) return false;
  // A division by a loose zero depends on its sign (as unrolled, ZeroFold stops there).
  if (op == BinOp::Div && ra >= 0 && scratch_loose_[static_cast<size_t>(ra)])
    throw FoldConflict{"a division by a tiled tensor that may hold a folded zero"};
  const bool loose = (la >= 0 && scratch_loose_[static_cast<size_t>(la)]) ||
                     (ra >= 0 && scratch_loose_[static_cast<size_t>(ra)]);
  const int result = new_scratch(shape.size(), loose);
  for_loop(static_cast<int>(shape.size()), at, [&](const ExprRef& k) {
    ExprRef a = la >= 0 ? scratch_read(la, k, at) : l.c[0];
    ExprRef b = ra >= 0 ? scratch_read(ra, k, at) : r.c[0];
    put(result, k, node(ExprKind::Binary, Ty::F64, static_cast<uint8_t>(op), {a, b}, at), at);
  });
  std::vector<ExprRef> c;
  for (size_t k = 0; k < shape.size(); ++k)
    c.push_back(read_scratch(result, iconst(static_cast<int64_t>(k)), at));
  out = tensor(Ty::F64, shape.dims, std::move(c), shape.block);
  return true;
}

// A matrix of more than kTileAbove components that lies in a scratch array (in order or
// transposed) times a vector, or a row vector times it: one loop over the result's
// components, each one's sum from +0.0 over k unrolled in it, the factors in the order the
// unrolled product multiplies them. False where it does not apply.
bool Tracer::tiled_matvec(const Sym& a, const Sym& x, bool row_vector, const SourceSpan& at,
                          Sym& out) {
  if (a.size() <= kTileAbove || a.blocked() || x.blocked()) return false;
  const ScratchView v = scratch_view(a);
  if (v.array < 0) return false;
  for (const ExprRef& e : x.c)
    if (e->loose) return false;  // a folded zero's product would fold inside the loop
  const int rows = a.dims[0], cols = a.dims[1];
  // Component (i, k) of the matrix lies at i * ai + k * ak of its array.
  const int ai = v.transposed ? 1 : cols, ak = v.transposed ? rows : 1;
  // A * x: result i is the sum over k of a(i, k) x(k); x' * A: result j of x(k) a(k, j).
  const int trips = row_vector ? cols : rows, n = row_vector ? rows : cols;
  const int per_result = row_vector ? ak : ai, per_k = row_vector ? ai : ak;
  const int result =
      new_scratch(static_cast<size_t>(trips), scratch_loose_[static_cast<size_t>(v.array)]);
  auto mul = [&](ExprRef p, ExprRef q) {
    if (row_vector) std::swap(p, q);
    return node(ExprKind::Binary, Ty::F64, static_cast<uint8_t>(BinOp::Mul), {p, q}, at);
  };
  for_loop(trips, at, [&](const ExprRef& i) {
    const ExprRef first = local_i32(i32_mul(i, per_result, at), at);
    ExprRef sum = fconst(0.0);
    for (int k = 0; k < n; ++k) {
      ExprRef term =
          mul(scratch_read(v.array, i32_add(first, static_cast<int64_t>(k) * per_k, at), at),
              x.c[static_cast<size_t>(k)]);
      sum = node(ExprKind::Binary, Ty::F64, static_cast<uint8_t>(BinOp::Add), {sum, term}, at);
    }
    put(result, i, sum, at);
  });
  std::vector<ExprRef> c;
  for (int i = 0; i < trips; ++i) c.push_back(read_scratch(result, iconst(i), at));
  out = tensor(Ty::F64, {trips}, std::move(c));
  return true;
}

// An outer product u v' of more than kTileAbove components: u in a scratch array, one loop
// over its components, each a row of the result (one rounding per component, as unrolled).
// False where it does not apply.
bool Tracer::tiled_outer(const Sym& u, const Sym& v, const SourceSpan& at, Sym& out) {
  const int n = u.dims[0], m = v.dims[0];
  if (static_cast<size_t>(n) * m <= kTileAbove || u.blocked() || v.blocked()) return false;
  for (const Sym* s : {&u, &v})
    for (const ExprRef& e : s->c)
      if (e->loose) return false;  // as in tiled_matvec
  check_components(static_cast<size_t>(n) * m, at);
  const int ua = in_scratch(u, at).array;
  const int result = new_scratch(static_cast<size_t>(n) * m, false);
  for_loop(n, at, [&](const ExprRef& i) {
    const ExprRef row = local_i32(i32_mul(i, m, at), at);
    const ExprRef ui = scratch_read(ua, i, at);
    for (int j = 0; j < m; ++j)
      put(result, i32_add(row, j, at),
          node(ExprKind::Binary, Ty::F64, static_cast<uint8_t>(BinOp::Mul),
               {ui, v.c[static_cast<size_t>(j)]}, at),
          at);
  });
  std::vector<ExprRef> c;
  for (int k = 0; k < n * m; ++k) c.push_back(read_scratch(result, iconst(k), at));
  out = tensor(Ty::F64, {n, m}, std::move(c));
  return true;
}

// An m x n by n x p product too large to unroll: loops over the result's tiles (up to
// kTile x kTile), a tile's rows, and k, each component summed from +0.0 in ascending k like
// the unrolled product, so the bits are the same. A row's kTile sums share each l(i, k).
Sym Tracer::tiled_product(const Sym& l, const Sym& r, const SourceSpan& at) {
  const int m = l.dims[0], n = l.dims[1], p = r.dims[1];
  const ScratchView lv = in_scratch(l, at), rv = in_scratch(r, at);
  if (static_cast<size_t>(m) * p > kMaxDenseComponents)
    give_up(at, "a product of " + std::to_string(static_cast<size_t>(m) * p) +
                    " components (more than " + std::to_string(kMaxDenseComponents) +
                    ") is not compiled");
  const int out =
      new_scratch(static_cast<size_t>(m) * p, scratch_loose_[static_cast<size_t>(lv.array)] ||
                                                  scratch_loose_[static_cast<size_t>(rv.array)]);
  const int tr = tile_extent(m), tc = tile_extent(p);
  // Component (i, k) of l lies at i * li + k * lk of its array; (k, j) of r at k * rk + j * rj.
  const int li = lv.transposed ? 1 : n, lk = lv.transposed ? m : 1;
  const int rk = rv.transposed ? 1 : p, rj = rv.transposed ? n : 1;
  auto loop = [&](int trips, auto&& body) { for_loop(trips, at, body); };
  auto put = [&](const ExprRef& index, ExprRef value) {
    this->put(out, index, std::move(value), at);
  };
  loop(m / tr, [&](const ExprRef& ti) {
    const ExprRef l_rows = local_i32(i32_mul(ti, static_cast<int64_t>(tr) * li, at), at);
    const ExprRef o_rows = local_i32(i32_mul(ti, static_cast<int64_t>(tr) * p, at), at);
    loop(p / tc, [&](const ExprRef& tj) {
      const ExprRef r_cols = local_i32(i32_mul(tj, static_cast<int64_t>(tc) * rj, at), at);
      const ExprRef o_tile =
          local_i32(binary(BinOp::Add, Ty::I32, o_rows, i32_mul(tj, tc, at), at), at);
      // The tile row by row: each row's tc sums over k, the row's value of l read once per k.
      loop(tr, [&](const ExprRef& a) {
        const ExprRef l_row =
            local_i32(binary(BinOp::Add, Ty::I32, l_rows, i32_mul(a, li, at), at), at);
        const ExprRef o_row =
            local_i32(binary(BinOp::Add, Ty::I32, o_tile, i32_mul(a, p, at), at), at);
        std::vector<ExprRef> o_at;
        for (int b = 0; b < tc; ++b) {
          o_at.push_back(i32_add(o_row, b, at));
          put(o_at.back(), fconst(0.0));
        }
        loop(n, [&](const ExprRef& k) {
          const ExprRef lk_at =
              local_i32(binary(BinOp::Add, Ty::I32, l_row, i32_mul(k, lk, at), at), at);
          const ExprRef r_at =
              local_i32(binary(BinOp::Add, Ty::I32, r_cols, i32_mul(k, rk, at), at), at);
          const ExprRef lval = scratch_read(lv.array, lk_at, at);
          for (int b = 0; b < tc; ++b) {
            const ExprRef rval =
                scratch_read(rv.array, i32_add(r_at, static_cast<int64_t>(b) * rj, at), at);
            const ExprRef& o = o_at[static_cast<size_t>(b)];
            put(o, binary(BinOp::Add, Ty::F64, scratch_read(out, o, at),
                          binary(BinOp::Mul, Ty::F64, lval, rval, at), at));
          }
        });
      });
    });
  });
  check_size();
  std::vector<ExprRef> c;
  for (int k = 0; k < m * p; ++k) c.push_back(read_scratch(out, iconst(k), at));
  return tensor(Ty::F64, {m, p}, std::move(c));
}

// Products of blocked tensors are products of their unblocked forms, blocked level by level
// like the operands (interp/operators.cpp), except the inner product, which sums each block
// first (docs/arithmetic.md).
Sym Tracer::blocked_product(const Sym& l, bool lrow, const Sym& r, bool rrow,
                            const SourceSpan& at) {
  if (!has_logical_form(l) || !has_logical_form(r))
    give_up(at, "a product of tensors blocked differently is not compiled");
  if (l.ty != Ty::F64 || r.ty != Ty::F64)
    give_up(at, "products of non-float tensors are not compiled");
  const bool lv = l.dims.size() == 1, rv = r.dims.size() == 1;
  if (lv && rv && lrow && !rrow) {
    if (!l.same_shape(r)) give_up(at, "inner product of vectors blocked differently");
    ExprRef total = fconst(0.0);
    for (size_t b = 0, bs = l.block_size(); b < l.blocks(); ++b) {
      ExprRef s = fconst(0.0);
      for (size_t k = b * bs; k < (b + 1) * bs; ++k)
        s = binary(BinOp::Add, Ty::F64, s, binary(BinOp::Mul, Ty::F64, l.c[k], r.c[k], at), at);
      total = binary(BinOp::Add, Ty::F64, total, s, at);
    }
    return scalar(Ty::F64, total);
  }
  std::vector<int> dims, block;
  if (lv && rv) {
    dims = {l.dims[0], r.dims[0]};
    block = {l.block[0], r.block[0]};
  } else if (!lv && rv) {
    dims = {l.dims[0]};
    block = {l.block[0]};
  } else if (lv) {
    dims = {r.dims[1]};
    block = {r.block[1]};
  } else {
    dims = {l.dims[0], r.dims[1]};
    block = {l.block[0], r.block[1]};
  }
  return reblocked(product(unblocked(l), lrow, unblocked(r), rrow, at), std::move(dims),
                   std::move(block));
}

Sym Tracer::eval_binary(const ast::Binary& b) {
  using Op = ast::Binary::Op;
  Sym l = eval(*b.lhs), r = eval(*b.rhs);
  if (l.kind != Sym::Kind::Tensor || r.kind != Sym::Kind::Tensor)
    give_up(b.span, "operators on system tensors are not compiled inside a mapped function");
  // Operands used more than once (products, broadcasts) are computed once.
  l = settle(std::move(l), b.span);
  r = settle(std::move(r), b.span);
  auto is_row = [](const ast::Expr& e) {
    return e.type && e.type->kind == Type::Kind::Tensor && e.type->dims.size() == 1 && e.type->row;
  };
  Sym v;
  switch (b.op) {
    case Op::Add: v = elementwise(BinOp::Add, l, r, b.span); break;
    case Op::Sub: v = elementwise(BinOp::Sub, l, r, b.span); break;
    case Op::ElemMul: v = elementwise(BinOp::Mul, l, r, b.span); break;
    case Op::ElemDiv:
    case Op::Div:
      if (l.ty == Ty::I32)
        check_divisors(r, "integer division by zero", b.span);
      else if (l.ty != Ty::F64)
        give_up(b.span, "division of non-numbers");
      v = elementwise(BinOp::Div, l, r, b.span);
      break;
    case Op::Mul:
      if (l.scalar() || r.scalar())
        v = elementwise(BinOp::Mul, l, r, b.span);
      else if (l.blocked() || r.blocked())
        v = blocked_product(l, is_row(*b.lhs), r, is_row(*b.rhs), b.span);
      else
        v = product(l, is_row(*b.lhs), r, is_row(*b.rhs), b.span);
      break;
    case Op::And:
    case Op::Or:
    case Op::Xor:
      if (l.ty != Ty::Bool || !l.scalar() || !r.scalar()) give_up(b.span, "logic on non-booleans");
      v = elementwise(b.op == Op::And  ? BinOp::And
                      : b.op == Op::Or ? BinOp::Or
                                       : BinOp::Xor,
                      l, r, b.span);
      break;
    default:
      give_up(b.span,
              std::string("operator ") + ast::binary_op_spelling(b.op) + " is not compiled");
  }
  return finite(round(std::move(v), b.span), b.span);
}

Sym Tracer::eval_compare(const ast::Compare& c) {
  std::vector<Sym> v;
  for (const auto& o : c.operands) {
    v.push_back(eval(*o));
    if (!v.back().scalar()) give_up(c.span, "comparison of non-scalars");
  }
  ExprRef result = iconst(1, Ty::Bool);
  for (size_t i = 0; i < c.ops.size(); ++i) {
    if (v[i].ty != v[i + 1].ty) give_up(c.span, "comparison of different types");
    if (v[i].ty == Ty::Bool && c.ops[i] != ast::Compare::Op::Eq && c.ops[i] != ast::Compare::Op::Ne)
      give_up(c.span, "ordering of booleans");
    ExprRef a = v[i].c[0], b = v[i + 1].c[0];
    if (v[i].ty == Ty::Bool) {  // compare truth values as integers
      a = make(Expr{ExprKind::Select, Ty::I32, 0, 0, 0, 0.0, 0, {a, iconst(1), iconst(0)}, c.span});
      b = make(Expr{ExprKind::Select, Ty::I32, 0, 0, 0, 0.0, 0, {b, iconst(1), iconst(0)}, c.span});
    }
    ExprRef one = compare(static_cast<CmpOp>(c.ops[i]), a, b, c.span);
    result = i == 0 ? one : binary(BinOp::And, Ty::Bool, one, result, c.span);
  }
  return scalar(Ty::Bool, result);
}

// det of the submatrix (rows x cols) of the n x n matrix a, by cofactor expansion along its
// first row, as runtime/dense_linalg.cpp computes it.
ExprRef Tracer::det(const std::vector<ExprRef>& a, int n, const std::vector<int>& rows,
                    const std::vector<int>& cols) {
  const size_t m = rows.size();
  if (m == 1) return a[static_cast<size_t>(rows[0]) * n + cols[0]];
  ExprRef sum = fconst(0.0);
  for (size_t j = 0; j < m; ++j) {
    std::vector<int> sub;
    for (size_t c = 0; c < m; ++c)
      if (c != j) sub.push_back(cols[c]);
    ExprRef minor = det(a, n, std::vector<int>(rows.begin() + 1, rows.end()), sub);
    if (j % 2) minor = unary(UnOp::Neg, Ty::F64, minor);
    sum = binary(BinOp::Add, Ty::F64, sum,
                 binary(BinOp::Mul, Ty::F64, a[static_cast<size_t>(rows[0]) * n + cols[j]], minor));
  }
  return sum;
}

Sym Tracer::eval_intrinsic(const ast::Call& c) {
  using frontend::Intrinsic;
  if (c.intrinsic == Intrinsic::ProjectSpd || c.intrinsic == Intrinsic::ProjectSpdAbs)
    return decompose(c)[0];
  std::vector<Sym> a;
  for (const auto& arg : c.args) {
    a.push_back(settle(eval(*arg), c.span));
    if (a.back().kind != Sym::Kind::Tensor) give_up(c.span, "an intrinsic of a non-tensor");
    if (a.back().blocked())
      give_up(c.span, std::string("intrinsic ") + frontend::intrinsic_name(c.intrinsic) +
                          " of a blocked tensor is not compiled");
  }
  auto f1 = [&](MathFn f) {
    if (!a[0].scalar() || a[0].ty != Ty::F64) give_up(c.span, "a math function of a non-float");
    return scalar(Ty::F64, math(f, {a[0].c[0]}, c.span));
  };
  auto f2 = [&](MathFn f) {
    if (!a[0].scalar() || !a[1].scalar() || a[0].ty != Ty::F64 || a[1].ty != Ty::F64)
      give_up(c.span, "a math function of non-floats");
    return scalar(Ty::F64, math(f, {a[0].c[0], a[1].c[0]}, c.span));
  };
  auto dot = [&](const Sym& x, const Sym& y) {
    if (x.ty != Ty::F64 || y.ty != Ty::F64 || x.size() != y.size())
      give_up(c.span, "dot of these operands");
    ExprRef s = fconst(0.0);
    for (size_t i = 0; i < x.size(); ++i)
      s = binary(BinOp::Add, Ty::F64, s, binary(BinOp::Mul, Ty::F64, x.c[i], y.c[i], c.span),
                 c.span);
    return s;
  };
  auto square = [&](const Sym& m) {
    if (m.dims.size() != 2 || m.dims[0] != m.dims[1] || m.dims[0] < 2 || m.dims[0] > 4 ||
        m.ty != Ty::F64)
      give_up(c.span, "det or inv of this shape is not compiled");
    return m.dims[0];
  };
  Sym v;
  switch (c.intrinsic) {
    case Intrinsic::Mod:
      if (!a[0].scalar() || !a[1].scalar() || a[0].ty != Ty::I32 || a[1].ty != Ty::I32)
        give_up(c.span, "mod of non-integers");
      check_divisors(a[1], "mod by zero", c.span);
      v = scalar(Ty::I32, binary(BinOp::Mod, Ty::I32, a[0].c[0], a[1].c[0], c.span));
      break;
    case Intrinsic::Sin: v = f1(MathFn::Sin); break;
    case Intrinsic::Cos: v = f1(MathFn::Cos); break;
    case Intrinsic::Tan: v = f1(MathFn::Tan); break;
    case Intrinsic::Asin: v = f1(MathFn::Asin); break;
    case Intrinsic::Acos: v = f1(MathFn::Acos); break;
    case Intrinsic::Sqrt: v = f1(MathFn::Sqrt); break;
    case Intrinsic::Cbrt: v = f1(MathFn::Cbrt); break;
    case Intrinsic::Log: v = f1(MathFn::Log); break;
    case Intrinsic::Exp: v = f1(MathFn::Exp); break;
    case Intrinsic::Abs: v = f1(MathFn::Abs); break;
    case Intrinsic::Atan2: v = f2(MathFn::Atan2); break;
    case Intrinsic::Pow: v = f2(MathFn::Pow); break;
    case Intrinsic::Max: v = f2(MathFn::Max); break;
    case Intrinsic::Min: v = f2(MathFn::Min); break;
    case Intrinsic::Dot: v = scalar(Ty::F64, dot(a[0], a[1])); break;
    case Intrinsic::Norm: v = scalar(Ty::F64, math(MathFn::Sqrt, {dot(a[0], a[0])}, c.span)); break;
    case Intrinsic::Cross: {
      if (a[0].size() != 3 || a[1].size() != 3 || a[0].ty != Ty::F64)
        give_up(c.span, "cross of these operands");
      const auto& x = a[0].c;
      const auto& y = a[1].c;
      auto term = [&](int i, int j, int k, int l) {
        return binary(BinOp::Sub, Ty::F64, binary(BinOp::Mul, Ty::F64, x[i], y[j], c.span),
                      binary(BinOp::Mul, Ty::F64, x[k], y[l], c.span), c.span);
      };
      v = tensor(Ty::F64, {3}, {term(1, 2, 2, 1), term(2, 0, 0, 2), term(0, 1, 1, 0)});
      break;
    }
    case Intrinsic::Det:
    case Intrinsic::Det2:
    case Intrinsic::Det4: {
      const int n = square(a[0]);
      std::vector<int> all(n);
      for (int i = 0; i < n; ++i) all[i] = i;
      v = scalar(Ty::F64, det(a[0].c, n, all, all));
      break;
    }
    case Intrinsic::Inv:
    case Intrinsic::Inv2:
    case Intrinsic::Inv4: {
      const int n = square(a[0]);
      std::vector<int> all(n);
      for (int i = 0; i < n; ++i) all[i] = i;
      const ExprRef d = settle(det(a[0].c, n, all, all), c.span);
      // The interpreter's singular-matrix error: the controller re-runs the site to report it.
      emit_check(compare(CmpOp::Ne, d, fconst(0.0), c.span),
                 "inverse of a singular matrix (determinant is 0)", c.span);
      std::vector<ExprRef> out(static_cast<size_t>(n) * n);
      for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
          std::vector<int> rows, cols;
          for (int r = 0; r < n; ++r)
            if (r != i) rows.push_back(r);
          for (int q = 0; q < n; ++q)
            if (q != j) cols.push_back(q);
          ExprRef cof = det(a[0].c, n, rows, cols);
          if ((i + j) % 2) cof = unary(UnOp::Neg, Ty::F64, cof);
          out[static_cast<size_t>(j) * n + i] = binary(BinOp::Div, Ty::F64, cof, d, c.span);
        }
      v = tensor(Ty::F64, {n, n}, std::move(out));
      break;
    }
    default:
      give_up(c.span, std::string("intrinsic ") + frontend::intrinsic_name(c.intrinsic) +
                          " is not compiled");
  }
  return finite(round(std::move(v), c.span), c.span);
}

// svd, eig, polar, project_spd: a call into the runtime's decompositions (the interpreter's
// own code, so the bits agree), with its results in new locals.
std::vector<Sym> Tracer::decompose(const ast::Call& c) {
  using frontend::Intrinsic;
  Decomposition d;
  switch (c.intrinsic) {
    case Intrinsic::Svd: d = Decomposition::Svd; break;
    case Intrinsic::Eig: d = Decomposition::Eig; break;
    case Intrinsic::Polar: d = Decomposition::Polar; break;
    case Intrinsic::ProjectSpd: d = Decomposition::ProjectSpd; break;
    case Intrinsic::ProjectSpdAbs: d = Decomposition::ProjectSpdAbs; break;
    default: give_up(c.span, "a call with several results that is not a decomposition");
  }
  if (c.args.size() != 1) give_up(c.span, "a decomposition of several arguments");
  Sym given = settle(eval(*c.args[0]), c.span);
  if (given.kind != Sym::Kind::Tensor || given.ty != Ty::F64 || given.dims.size() != 2)
    give_up(c.span, "a decomposition of this value is not compiled");
  // project_spd decomposes a blocked matrix in its unblocked form (runtime/decompositions.h);
  // the others take unblocked matrices only.
  const bool blocked = given.blocked();
  if (blocked && (!has_logical_form(given) ||
                  (d != Decomposition::ProjectSpd && d != Decomposition::ProjectSpdAbs)))
    give_up(c.span, "a decomposition of this blocked matrix is not compiled");
  const Sym a = blocked ? unblocked(given) : given;
  if (a.dims[0] != a.dims[1]) give_up(c.span, "a decomposition of a matrix that is not square");
  const int n = a.dims[0];
  trace_.errors.push_back(
      {c.span, std::string(frontend::intrinsic_name(c.intrinsic)) + " needs a symmetric matrix"});
  Stmt s;
  if (zero_fold) ZeroFold::require_exact(a.c, "a decomposition");
  s.kind = StmtKind::Decompose;
  s.fn = static_cast<int>(d);
  s.n = n;
  s.args = a.c;
  s.error = static_cast<int>(trace_.errors.size() - 1);
  s.span = c.span;
  std::vector<Sym> out;
  for (int count : decomposition_results(d, n)) {
    std::vector<ExprRef> comps;
    for (int k = 0; k < count; ++k) {
      const int l = new_local(Ty::F64, false);
      s.outs.push_back(l);
      comps.push_back(read_local(l));
    }
    out.push_back(round(tensor(Ty::F64, count == n ? std::vector<int>{n} : std::vector<int>{n, n},
                               std::move(comps)),
                        c.span));
  }
  emit(std::move(s));
  if (blocked) out[0] = reblocked(out[0], given.dims, given.block);
  for (Sym& r : out) r = finite(std::move(r), c.span);
  return out;
}

Sym Tracer::eval_call(const ast::Call& c) {
  if (c.intrinsic != frontend::Intrinsic::None) return eval_intrinsic(c);
  std::vector<Sym> r = call_user(c);
  if (r.empty()) return {};
  return r[0];
}

std::vector<Sym> Tracer::call_user(const ast::Call& c) {
  const ast::FuncDecl& f = *c.func;
  if (f.is_extern || !f.generics.empty())
    give_up(c.span, "calls of extern or generic functions are not compiled");
  if (++inline_depth_ > kMaxInlineDepth) give_up(c.span, "calls nested too deeply to inline");
  std::vector<Sym> args;
  for (const auto& a : c.args) args.push_back(settle(eval(*a), c.span));
  Frame callee;
  for (size_t i = 0; i < f.params.size() && i < args.size(); ++i) {
    const ast::Param& p = f.params[i];
    if (p.inout && args[i].kind == Sym::Kind::Tensor)
      give_up(c.span, "inout tensor arguments are not compiled");
    callee.vars[p.var] = p.var->type ? as_declared(args[i], *p.var->type, c.span) : args[i];
    callee.bound_at[p.var] = static_cast<int>(blocks_.size());
  }
  for (const ast::Param& r : f.results) {
    callee.vars[r.var] = zero_of(*r.var->type, r.span);
    callee.bound_at[r.var] = static_cast<int>(blocks_.size());
  }
  // Loads cached by the caller stay valid: the callee reads the same arrays.
  frames_.push_back(std::move(callee));
  const size_t errors_before = trace_.errors.size();
  exec_block(f.body);
  // A check failing in the callee reports the call stack the interpreter would.
  for (size_t i = errors_before; i < trace_.errors.size(); ++i)
    trace_.errors[i].frames.emplace_back(f.name, c.span);
  std::vector<Sym> out;
  for (const ast::Param& r : f.results) out.push_back(frame().vars[r.var]);
  frames_.pop_back();
  --inline_depth_;
  return out;
}

// ---------------------------------------------------------------------------
// Statements

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
      if (a.index_notation) give_up(a.span, "index notation is not compiled");
      if (a.targets.size() == 1) return assign(*a.targets[0], eval(*a.value), a.span);
      const auto* call = a.value->as<ast::Call>();
      if (!call) give_up(a.span, "a multiple assignment from something other than a call");
      std::vector<Sym> values = call->func ? call_user(*call) : decompose(*call);
      if (values.size() != a.targets.size()) give_up(a.span, "result count does not match");
      for (size_t i = 0; i < values.size(); ++i)
        assign(*a.targets[i], std::move(values[i]), a.span);
      return;
    }
    case ast::NodeKind::ExprStmt: {
      const auto& e = static_cast<const ast::ExprStmt&>(s);
      const auto* call = e.expr->as<ast::Call>();
      if (!call || !call->func)
        give_up(s.span, "expression statements other than calls are not compiled");
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
  give_up(s.span, std::string(ast::node_kind_name(s.kind)) + " statements are not compiled");
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
    give_up(s.span, "a loop whose bounds are not constants");
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
  if (zero_fold) zero_fold->open();
  then_body();
  if (zero_fold)
    if (auto check = zero_fold->close(trace_.errors, at)) st.body.push_back(std::move(*check));
  blocks_.pop_back();
  out_ = saved;
  emit(std::move(st));
}

// Conditions that fold choose their branch now; the first that does not becomes an If whose
// else part holds the rest of the chain (from condition `first` on).
void Tracer::exec_if_from(const ast::If& s, size_t first) {
  for (size_t i = first; i < s.conditions.size(); ++i) {
    Sym c = eval(*s.conditions[i]);
    if (!c.scalar() || c.ty != Ty::Bool) give_up(s.span, "a condition that is not a boolean");
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
      if (zero_fold) zero_fold->open();
      fn();
      if (zero_fold)
        if (auto check = zero_fold->close(trace_.errors, s.span)) body.push_back(std::move(*check));
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

void Tracer::bind(const ast::Variable& v, Sym value, const SourceSpan& at) {
  Frame& f = frame();
  if (auto m = f.merged.find(&v); m != f.merged.end()) {
    if (value.kind != Sym::Kind::Tensor || value.size() != m->second.size())
      give_up(at, "an assignment that changes a variable's shape");
    // Every component is read before any is written: `t = t'` reads t's own locals.
    value = settle(std::move(value), at);
    for (size_t i = 0; i < value.size(); ++i) set_local(m->second[i], value.c[i], at);
    Sym& cur = f.vars[&v];
    cur.dims = value.dims;
    cur.block = value.block;
    return;
  }
  if (auto b = f.bound_at.find(&v);
      b != f.bound_at.end() && b->second < static_cast<int>(blocks_.size()))
    give_up(at, "an assignment inside a branch to '" + v.name + "' that the tracer did not expect");
  f.vars[&v] = value.kind == Sym::Kind::Tensor ? settle(std::move(value), at) : std::move(value);
  f.bound_at[&v] = static_cast<int>(blocks_.size());
}

void Tracer::assign(const ast::Expr& target, Sym value, const SourceSpan& at) {
  if (const auto* v = target.as<ast::VarRef>()) {
    auto it = frame().vars.find(v->var);
    if (it != frame().vars.end() && it->second.kind == Sym::Kind::Result)
      give_up(at, "assigning a whole result of the mapped function");
    // `v = 0.0` on a tensor broadcasts; a variable keeps its declared shape.
    if (v->var->type) value = as_declared(std::move(value), *v->var->type, at);
    return bind(*v->var, std::move(value), at);
  }
  if (const auto* f = target.as<ast::FieldRead>())
    return store_field(*f, nullptr, std::move(value), at);
  const auto* r = target.as<ast::TensorRead>();
  if (!r) give_up(at, "this assignment target is not compiled");
  if (r->index_notation) give_up(at, "index notation is not compiled");
  // Writes into the function's system-tensor results.
  // `K(x, y)(a, d) = s`: one component of a block (the pass marks the whole target).
  if (const auto* inner = r->base->as<ast::TensorRead>(); inner && r->assembles_result >= 0)
    return assign_result(*inner, r, std::move(value), at);
  if (r->assembles_result >= 0) return assign_result(*r, nullptr, std::move(value), at);
  std::vector<int64_t> idx;
  for (const auto& i : r->indices) {
    if (!i) give_up(at, "slice assignments are not compiled");
    idx.push_back(const_int(*i));
  }
  if (const auto* f = r->base->as<ast::FieldRead>())
    return store_field(*f, &idx, std::move(value), at);
  // `B(i, j)(a, b) = x`: a component of a block of a blocked local.
  const ast::TensorRead* outer = r;
  std::vector<int64_t> sub;
  if (const auto* in = r->base->as<ast::TensorRead>()) {
    outer = in;
    sub = std::move(idx);
    idx.clear();
    for (const auto& i : in->indices) {
      if (!i) give_up(at, "slice assignments are not compiled");
      idx.push_back(const_int(*i));
    }
  }
  const auto* base = outer->base->as<ast::VarRef>();
  if (!base) give_up(at, "this assignment target is not compiled");
  assign_part(*base->var, idx, outer != r ? &sub : nullptr, std::move(value), at);
}

// A write of a component of a local, or of a block or a block's component when it is blocked
// (a scalar fills the block, as in the interpreter).
void Tracer::assign_part(const ast::Variable& v, const std::vector<int64_t>& idx,
                         const std::vector<int64_t>* sub, Sym value, const SourceSpan& at) {
  auto it = frame().vars.find(&v);
  Sym cur = it != frame().vars.end() ? it->second : zero_of(*v.type, at);
  if (cur.kind != Sym::Kind::Tensor) give_up(at, "a component write into a non-tensor");
  if (sub && !cur.blocked()) give_up(at, "a component write into a component");
  if (idx.size() != cur.dims.size() || (sub && sub->size() != cur.block.size()))
    give_up(at, "index count does not match");
  size_t first = offset_of(cur.dims, idx, at), count = 1;
  if (cur.blocked()) {
    first *= cur.block_size();
    count = cur.block_size();
    if (sub) {
      first += offset_of(cur.block, *sub, at);
      count = 1;
    }
  }
  if (value.kind != Sym::Kind::Tensor || value.ty != cur.ty)
    give_up(at, "a component write of another type");
  if (!value.scalar() && (value.size() != count || value.blocked()))
    give_up(at, "a write of a block of another shape");
  // Computed once, and every component read before any is written (`B(0, 0) = B(0, 0)'`).
  if (count > 1) value = settle(std::move(value), at);
  auto part = [&](size_t k) { return value.scalar() ? value.c[0] : value.c[k]; };
  if (auto m = frame().merged.find(&v); m != frame().merged.end()) {
    for (size_t k = 0; k < count; ++k) set_local(m->second[first + k], part(k), at);
    return;
  }
  for (size_t k = 0; k < count; ++k) cur.c[first + k] = part(k);
  bind(v, std::move(cur), at);
}

void Tracer::store_field(const ast::FieldRead& f, const std::vector<int64_t>* idx, Sym value,
                         const SourceSpan& at) {
  if (f.of_set) give_up(at, "writing a whole set field");
  Sym base = eval(*f.base);
  if (base.kind != Sym::Kind::Element || base.member != 0)
    give_up(at, "a field write to another element");
  const int slot = field_array(0, f.field, f.span);
  ArraySlot& a = trace_.arrays[slot];
  a.written = true;
  trace_.writes_fields = true;
  if (value.kind != Sym::Kind::Tensor || value.ty != a.ty || value.blocked())
    give_up(at, "a field write of another type");
  std::vector<int> dims = dims_of(*f.type, f.span);
  size_t first = 0, count = static_cast<size_t>(a.components);
  if (idx) {
    first = offset_of(dims, *idx, at);
    count = 1;
  }
  if (!value.scalar() && value.size() != count) give_up(at, "a field write of another shape");
  value = settle(std::move(value), at);
  for (size_t k = 0; k < count; ++k) {
    Stmt s;
    s.kind = StmtKind::Store;
    s.slot = slot;
    s.comp = static_cast<int>(first + k);
    s.index = member_index(0);
    s.value = value.scalar() ? value.c[0] : value.c[k];
    s.span = at;
    emit(std::move(s));
  }
  forget_loads(slot);
}

void Tracer::assign_result(const ast::TensorRead& r, const ast::TensorRead* component, Sym value,
                           const SourceSpan& at) {
  const auto* base = r.base->as<ast::VarRef>();
  auto it = base ? frame().vars.find(base->var) : frame().vars.end();
  if (it == frame().vars.end() || it->second.kind != Sym::Kind::Result || frames_.size() != 1)
    give_up(at, "a result write outside the mapped function");
  const int res = it->second.slot;
  const int slot = array({ArraySlot::Kind::Result, 0, res, Ty::F64, false, true, 0, "", {}});
  ArraySlot& a = trace_.arrays[slot];
  if (value.kind != Sym::Kind::Tensor || value.ty != Ty::F64)
    give_up(at, "a result write of a non-float");
  if (value.blocked()) give_up(at, "a result write of a blocked value");
  std::vector<int64_t> sub;
  if (component)
    for (const auto& i : component->indices) {
      if (!i) give_up(at, "slices of result blocks are not compiled");
      sub.push_back(const_int(*i));
    }
  std::vector<int> members;
  for (const auto& i : r.indices) {
    if (!i) give_up(at, "a result write at a slice");
    Sym m = eval(*i);
    if (m.kind != Sym::Kind::Element) give_up(at, "a result write not at a member of the element");
    members.push_back(m.member);
  }
  const runtime::MatrixPattern* pattern = in_.patterns[res];
  int pair = -1;
  ExprRef index;
  if (pattern) {
    if (members.size() != 2) give_up(at, "a matrix write with one index");
    const runtime::AssemblyIndex& ai = pattern->assembly();
    auto local = [&](const std::vector<int>& ms, int m) {
      auto p = std::find(ms.begin(), ms.end(), m);
      if (p == ms.end()) give_up(at, "a matrix write outside the element's pattern");
      return static_cast<int>(p - ms.begin());
    };
    pair = local(ai.row_members, members[0]) * static_cast<int>(ai.col_members.size()) +
           local(ai.col_members, members[1]);
  } else {
    if (members.size() != 1) give_up(at, "a vector write with two indices");
    index = member_index(members[0]);
  }
  // The block's shape comes from the result's type.
  const Type& rt = *base->var->type;
  const std::vector<int> block = rt.block ? dims_of(*rt.block, at) : std::vector<int>{};
  size_t bsize = 1;
  for (int d : block) bsize *= static_cast<size_t>(d);
  a.components = static_cast<int>(bsize);
  size_t first = 0, count = bsize;
  if (component) {
    first = offset_of(block, sub, at);
    count = 1;
  }
  if (!value.scalar() && value.size() != count) give_up(at, "a result write of another shape");
  for (size_t k = 0; k < count; ++k) {
    Stmt s;
    s.kind = StmtKind::Assemble;
    s.slot = slot;
    s.comp = static_cast<int>(first + k);
    s.pair = pair;
    s.index = index;
    s.value = value.scalar() ? value.c[0] : value.c[k];
    s.span = at;
    emit(std::move(s));
  }
}

// A global matrix argument, read by blocks (read_matrix_block).
Sym Tracer::matrix_arg(int k, const ast::Param& p, const interp::Value& v) {
  const runtime::SystemMatrix* m = v.matrix().get();
  if (!m || !m->is_float()) give_up(p.span, "a global matrix argument of non-float components");
  // The interpreter sums the repeated blocks of a stencil pattern where it reads one.
  if (!m->pattern().canonical())
    give_up(p.span, "a global matrix argument whose pattern repeats blocks");
  ArraySlot a;
  a.kind = ArraySlot::Kind::Matrix;
  a.index = k;
  a.components = m->block_size();
  a.name = p.name;
  Sym s;
  s.kind = Sym::Kind::Matrix;
  s.slot = array(std::move(a));
  return s;
}

TracedSite Tracer::run() {
  TracedSite out;
  const ast::Assembly& site = *in_.site;
  const ast::FuncDecl& f = *site.callee;
  trace_.name = f.name;
  if (site.func_span.valid()) trace_.name += ":" + std::to_string(site.func_span.start().line);
  trace_.arity = in_.target->arity();
  trace_.reduce = in_.reduce;
  trace_.float32 = in_.float32;
  ZeroFold folding;
  struct Active {  // zero_fold points at this trace's folding while it is traced
    explicit Active(ZeroFold* f) { zero_fold = f; }
    ~Active() { zero_fold = nullptr; }
  } active(fold_ ? &folding : nullptr);
  try {
    if (!f.generics.empty()) give_up(site.func_span, "generic mapped functions are not compiled");
    if (in_.target->is_grid()) give_up(site.func_span, "maps through grids are not compiled");
    Frame top;
    const auto& partial = *in_.partial_args;
    size_t k = 0;
    for (; k < partial.size(); ++k) {
      const ast::Param& p = f.params[k];
      if (p.inout) give_up(p.span, "inout partial arguments are not compiled");
      const interp::Value& v = partial[k];
      const Type& t = *p.var->type;
      Sym s;
      if (t.kind == Type::Kind::Tensor && t.is_global() &&
          v.kind() == interp::Value::Kind::Matrix) {
        s = matrix_arg(static_cast<int>(k), p, v);
      } else if (t.kind == Type::Kind::Tensor && t.is_global()) {
        if (!v.is_tensor() || v.tensor().kind() != runtime::ComponentKind::Float ||
            t.dims.size() != 1)
          give_up(p.span, "a global argument other than a float vector");
        ArraySlot a;
        a.kind = ArraySlot::Kind::Vector;
        a.index = static_cast<int>(k);
        a.components = static_cast<int>(v.tensor().shape().block_size());
        a.name = p.name;
        s.kind = Sym::Kind::Vector;
        s.slot = array(std::move(a));
      } else {
        s = const_of(v, p.span);
        for (size_t i = 0; i < s.c.size(); ++i)
          s.c[i] = scalar_arg(s.ty, {static_cast<int>(k), nullptr, static_cast<int>(i)});
      }
      top.vars[p.var] = std::move(s);
    }
    if (k < f.params.size()) {
      Sym e;
      e.kind = Sym::Kind::Element;
      e.member = 0;
      e.inout = f.params[k].inout;
      top.vars[f.params[k++].var] = e;
    }
    if (site.pass_endpoints && k < f.params.size()) {
      Sym t;
      t.kind = Sym::Kind::Tuple;
      top.vars[f.params[k++].var] = t;
    }
    if (k != f.params.size())
      give_up(site.func_span, "a mapped function with unexpected parameters");
    trace_.pairs.assign(f.results.size(), 0);
    for (size_t i = 0; i < f.results.size(); ++i) {
      Sym r;
      r.kind = Sym::Kind::Result;
      r.slot = static_cast<int>(i);
      top.vars[f.results[i].var] = r;
      if (in_.patterns[i]) {
        trace_.pairs[i] = static_cast<int>(in_.patterns[i]->assembly().pairs());
        array({ArraySlot::Kind::Table,
               0,
               static_cast<int>(i),
               Ty::I32,
               false,
               false,
               trace_.pairs[i],
               f.results[i].name + ".table",
               {}});
        array({ArraySlot::Kind::Marks,
               0,
               static_cast<int>(i),
               Ty::Bool,
               false,
               true,
               1,
               f.results[i].name + ".marks",
               {}});
      }
      array({ArraySlot::Kind::Result,
             0,
             static_cast<int>(i),
             Ty::F64,
             false,
             true,
             1,
             f.results[i].name,
             {}});
    }
    frames_.push_back(std::move(top));
    exec_block(f.body);
    // A failed check makes the interpreter run the site again, which must not see the
    // fields this trace has already written.
    if (error_at_.valid() && trace_.writes_fields)
      give_up(error_at_, "error statements in an apply with inout fields are not compiled");
    if (fold_)
      if (auto check = folding.close(trace_.errors, site.func_span))
        trace_.body.push_back(std::move(*check));
  } catch (const GiveUp& g) {
    out.reason = g.reason;
    return out;
  } catch (const FoldConflict& c) {
    fold_failed_ = true;
    out.reason = c.reason;
    return out;
  }
  // A call that fails its checks is run again by the interpreter, which a trace that writes
  // fields cannot allow.
  if (folding.used() && trace_.writes_fields) fold_failed_ = true;
  out.scalar_sources = sources_;
  trace_.local_mutable = mutable_;
  out.trace = std::move(trace_);
  return out;
}

}  // namespace

TracedSite trace_site(const SiteShape& shape) {
  Tracer folded(shape, kFoldZeros);
  TracedSite t = folded.run();
  if (!folded.fold_failed()) return t;
  return Tracer(shape, false).run();
}

}  // namespace simit::jit
