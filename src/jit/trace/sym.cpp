// Symbolic values and their shapes (jit/trace/sym.h).
#include "jit/trace/sym.h"

#include <string>

#include "jit/ir_build.h"
#include "jit/trace/abort_reasons.h"
#include "jit/tunables.h"

namespace simit::jit::trace_detail {

using frontend::IndexSet;
using frontend::ScalarKind;
using frontend::SourceSpan;
using frontend::Type;

Sym tensor(Ty ty, std::vector<int> dims, std::vector<ExprRef> c, std::vector<int> block) {
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
    default: give_up(at, AbortReason::ScalarKindValues, frontend::to_string(k));
  }
}

bool is_blocked(const Type& t) { return t.block && t.block->kind != Type::Kind::Scalar; }

// The fixed outer dimensions of a dense tensor type (none for a scalar).
std::vector<int> outer_dims_of(const Type& t, const SourceSpan& at) {
  if (t.kind == Type::Kind::Scalar) return {};
  if (t.kind != Type::Kind::Tensor) give_up(at, AbortReason::ValueType, frontend::to_string(t));
  std::vector<int> d;
  for (const IndexSet& i : t.dims) {
    if (i.kind != IndexSet::Kind::Fixed) give_up(at, AbortReason::TensorOverSet);
    d.push_back(i.size);
  }
  return d;
}

// The fixed dimensions of a small unblocked dense tensor type (none for a scalar): fields,
// result blocks and global vectors' blocks.
std::vector<int> dims_of(const Type& t, const SourceSpan& at) {
  if (is_blocked(t)) give_up(at, AbortReason::BlockedValue, frontend::to_string(t));
  return outer_dims_of(t, at);
}

// The dimensions of each block of a blocked dense tensor type (none when it is not blocked).
std::vector<int> block_dims_of(const Type& t, const SourceSpan& at) {
  if (t.kind != Type::Kind::Tensor || !is_blocked(t)) return {};
  if (is_blocked(*t.block)) give_up(at, AbortReason::NestedBlocks);
  return outer_dims_of(*t.block, at);
}

// Every component of a dense tensor becomes a value of its own: large ones stay interpreted.
void check_components(size_t n, const SourceSpan& at) {
  if (n > kMaxDenseComponents)
    give_up(at, AbortReason::TensorTooLarge, std::to_string(n),
            std::to_string(kMaxDenseComponents));
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
Sym as_declared(Sym value, const Type& t, const SourceSpan& at, bool reshape) {
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
    give_up(at, AbortReason::ReshapeComponents, std::to_string(value.size()),
            std::to_string(shape.size()));
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
      if (t.shape().is_blocked()) give_up(at, AbortReason::BlockedConstant);
      check_components(t.size(), at);
      std::vector<int> dims;
      for (int i = 0; i < t.shape().order(); ++i) dims.push_back(t.shape().dim(i));
      std::vector<ExprRef> c;
      for (size_t i = 0; i < t.size(); ++i) {
        switch (t.kind()) {
          case runtime::ComponentKind::Float: c.push_back(fconst(t.floats()[i])); break;
          case runtime::ComponentKind::Int: c.push_back(iconst(t.ints()[i])); break;
          case runtime::ComponentKind::Bool: c.push_back(iconst(t.bools()[i], Ty::Bool)); break;
          default: give_up(at, AbortReason::ConstantComponentType);
        }
      }
      const Ty ty = t.kind() == runtime::ComponentKind::Float ? Ty::F64
                    : t.kind() == runtime::ComponentKind::Int ? Ty::I32
                                                              : Ty::Bool;
      return tensor(ty, std::move(dims), std::move(c));
    }
    default: give_up(at, AbortReason::ConstantKind);
  }
}

// Row-major offset of constant indices into dims.
size_t offset_of(const std::vector<int>& dims, const std::vector<int64_t>& idx,
                 const SourceSpan& at) {
  size_t off = 0;
  for (size_t k = 0; k < dims.size(); ++k) {
    if (idx[k] < 0 || idx[k] >= dims[k]) give_up(at, AbortReason::IndexOutOfRange);
    off = off * static_cast<size_t>(dims[k]) + static_cast<size_t>(idx[k]);
  }
  return off;
}

}  // namespace simit::jit::trace_detail
