// Symbolic values of a traced function's expressions (Sym): a tensor's components as loop-IR
// expressions, or an element, the endpoints, a global vector or matrix, or a result; and the
// shape helpers that turn declared types and program constants into them.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "frontend/source.h"
#include "frontend/types.h"
#include "interp/value.h"
#include "jit/loop_ir.h"

namespace simit::jit::trace_detail {

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

Sym tensor(Ty ty, std::vector<int> dims, std::vector<ExprRef> c, std::vector<int> block = {});
Sym scalar(Ty ty, ExprRef e);

Ty ty_of(frontend::ScalarKind k, const frontend::SourceSpan& at);
bool is_blocked(const frontend::Type& t);
// The fixed outer dimensions of a dense tensor type (none for a scalar).
std::vector<int> outer_dims_of(const frontend::Type& t, const frontend::SourceSpan& at);
// The fixed dimensions of a small unblocked dense tensor type (none for a scalar): fields,
// result blocks and global vectors' blocks.
std::vector<int> dims_of(const frontend::Type& t, const frontend::SourceSpan& at);
// The dimensions of each block of a blocked dense tensor type (none when it is not blocked).
std::vector<int> block_dims_of(const frontend::Type& t, const frontend::SourceSpan& at);
// Every component of a dense tensor becomes a value of its own: large ones stay interpreted.
void check_components(size_t n, const frontend::SourceSpan& at);
Sym zero_of(const frontend::Type& t, const frontend::SourceSpan& at);
// A value bound to a variable of declared type `t`, in the variable's shape (sym.cpp).
Sym as_declared(Sym value, const frontend::Type& t, const frontend::SourceSpan& at,
                bool reshape = false);

// For each component of a blocked matrix or vector in its logical (unblocked) row-major
// order, its position in the blocked order: runtime::unblock's permutation for two levels.
std::vector<size_t> logical_positions(const Sym& s);
// Whether a blocked tensor has an unblocked form the tracer handles: its blocks have as many
// dimensions as it has (runtime::Shape::uniform), and it is a vector or a matrix.
bool has_logical_form(const Sym& s);
// The unblocked form of a blocked tensor (has_logical_form), and back.
Sym unblocked(const Sym& s);
Sym reblocked(const Sym& logical, std::vector<int> dims, std::vector<int> block);

// Constants of the program (and the literal values of externs, for their shapes).
Sym const_of(const interp::Value& v, const frontend::SourceSpan& at);
// Row-major offset of constant indices into dims.
size_t offset_of(const std::vector<int>& dims, const std::vector<int64_t>& idx,
                 const frontend::SourceSpan& at);

}  // namespace simit::jit::trace_detail
