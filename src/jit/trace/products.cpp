// The tracer's products (jit/trace/tracer.h): unrolled products of small tensors, tiled
// loops over scratch arrays for large ones, and products of blocked tensors.
#include <algorithm>
#include <cstring>

#include "jit/trace/tracer.h"

namespace simit::jit::trace_detail {

namespace {

// The largest tile extent up to kTile that divides n, so that every tile is whole.
int tile_extent(int n) {
  for (int t = std::min(n, kTile); t > 1; --t)
    if (n % t == 0) return t;
  return 1;
}

}  // namespace

// Products sum from +0.0 over k in ascending order (docs/arithmetic.md); an outer product
// is one rounding per component.
Sym Tracer::product(const Sym& l, bool lrow, const Sym& r, bool rrow, const SourceSpan& at) {
  if (l.ty != Ty::F64 || r.ty != Ty::F64) give_up(at, AbortReason::ProductOfNonFloats);
  auto sum = [&](int n, auto term) {
    ExprRef s = fconst(0.0);
    for (int k = 0; k < n; ++k) s = sum_add(s, term(k), at);
    return s;
  };
  auto mul = [&](const ExprRef& a, const ExprRef& b) { return sum_mul(a, b, at); };
  const size_t lo = l.dims.size(), ro = r.dims.size();
  if (lo == 1 && ro == 1) {
    const int n = l.dims[0], m = r.dims[0];
    if (lrow && !rrow) {
      if (n != m) give_up(at, AbortReason::InnerProductLengths);
      return scalar(Ty::F64, sum(n, [&](int k) { return mul(l.c[k], r.c[k]); }));
    }
    if (lrow || !rrow) give_up(at, AbortReason::ProductOrientation);
    if (Sym tiled; tiled_outer(l, r, at, tiled)) return tiled;
    check_components(static_cast<size_t>(n) * m, at);
    std::vector<ExprRef> c;
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < m; ++j) c.push_back(mul(l.c[i], r.c[j]));
    return tensor(Ty::F64, {n, m}, std::move(c));
  }
  if (lo == 2 && ro == 1) {
    const int m = l.dims[0], n = l.dims[1];
    if (r.dims[0] != n) give_up(at, AbortReason::ProductDimensions, "matrix-vector");
    if (Sym tiled; tiled_matvec(l, r, false, at, tiled)) return tiled;
    std::vector<ExprRef> c;
    for (int i = 0; i < m; ++i)
      c.push_back(sum(n, [&](int k) { return mul(l.c[i * n + k], r.c[k]); }));
    return tensor(Ty::F64, {m}, std::move(c));
  }
  if (lo == 1 && ro == 2) {
    const int n = r.dims[0], m = r.dims[1];
    if (l.dims[0] != n) give_up(at, AbortReason::ProductDimensions, "vector-matrix");
    if (Sym tiled; tiled_matvec(r, l, true, at, tiled)) return tiled;
    std::vector<ExprRef> c;
    for (int j = 0; j < m; ++j)
      c.push_back(sum(n, [&](int k) { return mul(l.c[k], r.c[k * m + j]); }));
    return tensor(Ty::F64, {m}, std::move(c));
  }
  if (lo == 2 && ro == 2) {
    const int m = l.dims[0], n = l.dims[1], p = r.dims[1];
    if (r.dims[0] != n) give_up(at, AbortReason::ProductDimensions, "matrix");
    if (static_cast<size_t>(m) * n * p > kMaxUnrolledProduct) return tiled_product(l, r, at);
    std::vector<ExprRef> c;
    for (int i = 0; i < m; ++i)
      for (int j = 0; j < p; ++j)
        c.push_back(sum(n, [&](int k) { return mul(l.c[i * n + k], r.c[k * p + j]); }));
    return tensor(Ty::F64, {m, p}, std::move(c));
  }
  give_up(at, AbortReason::ProductOfHighOrder);
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
    throw FoldConflict{abort_message(AbortReason::FoldTiledDivision)};
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
    return in_sum(node(ExprKind::Binary, Ty::F64, static_cast<uint8_t>(BinOp::Mul), {p, q}, at),
                  at);
  };
  for_loop(trips, at, [&](const ExprRef& i) {
    const ExprRef first = local_i32(build_.i32_mul(i, per_result, at), at);
    ExprRef sum = fconst(0.0);
    for (int k = 0; k < n; ++k) {
      ExprRef term =
          mul(scratch_read(v.array, build_.i32_add(first, static_cast<int64_t>(k) * per_k, at), at),
              x.c[static_cast<size_t>(k)]);
      sum = in_sum(
          node(ExprKind::Binary, Ty::F64, static_cast<uint8_t>(BinOp::Add), {sum, term}, at), at);
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
    const ExprRef row = local_i32(build_.i32_mul(i, m, at), at);
    const ExprRef ui = scratch_read(ua, i, at);
    for (int j = 0; j < m; ++j)
      put(result, build_.i32_add(row, j, at),
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
    give_up(at, AbortReason::ProductTooLarge, std::to_string(static_cast<size_t>(m) * p),
            std::to_string(kMaxDenseComponents));
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
    const ExprRef l_rows = local_i32(build_.i32_mul(ti, static_cast<int64_t>(tr) * li, at), at);
    const ExprRef o_rows = local_i32(build_.i32_mul(ti, static_cast<int64_t>(tr) * p, at), at);
    loop(p / tc, [&](const ExprRef& tj) {
      const ExprRef r_cols = local_i32(build_.i32_mul(tj, static_cast<int64_t>(tc) * rj, at), at);
      const ExprRef o_tile =
          local_i32(build_.binary(BinOp::Add, Ty::I32, o_rows, build_.i32_mul(tj, tc, at), at), at);
      // The tile row by row: each row's tc sums over k, the row's value of l read once per k.
      loop(tr, [&](const ExprRef& a) {
        const ExprRef l_row = local_i32(
            build_.binary(BinOp::Add, Ty::I32, l_rows, build_.i32_mul(a, li, at), at), at);
        const ExprRef o_row =
            local_i32(build_.binary(BinOp::Add, Ty::I32, o_tile, build_.i32_mul(a, p, at), at), at);
        std::vector<ExprRef> o_at;
        for (int b = 0; b < tc; ++b) {
          o_at.push_back(build_.i32_add(o_row, b, at));
          put(o_at.back(), fconst(0.0));
        }
        loop(n, [&](const ExprRef& k) {
          const ExprRef lk_at = local_i32(
              build_.binary(BinOp::Add, Ty::I32, l_row, build_.i32_mul(k, lk, at), at), at);
          const ExprRef r_at = local_i32(
              build_.binary(BinOp::Add, Ty::I32, r_cols, build_.i32_mul(k, rk, at), at), at);
          const ExprRef lval = scratch_read(lv.array, lk_at, at);
          for (int b = 0; b < tc; ++b) {
            const ExprRef rval =
                scratch_read(rv.array, build_.i32_add(r_at, static_cast<int64_t>(b) * rj, at), at);
            const ExprRef& o = o_at[static_cast<size_t>(b)];
            put(o, sum_add(scratch_read(out, o, at), sum_mul(lval, rval, at), at));
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
    give_up(at, AbortReason::ProductBlockedDifferently);
  if (l.ty != Ty::F64 || r.ty != Ty::F64) give_up(at, AbortReason::ProductOfNonFloats);
  const bool lv = l.dims.size() == 1, rv = r.dims.size() == 1;
  if (lv && rv && lrow && !rrow) {
    if (!l.same_shape(r)) give_up(at, AbortReason::InnerProductBlocks);
    ExprRef total = fconst(0.0);
    for (size_t b = 0, bs = l.block_size(); b < l.blocks(); ++b) {
      ExprRef s = fconst(0.0);
      for (size_t k = b * bs; k < (b + 1) * bs; ++k)
        s = sum_add(s, sum_mul(l.c[k], r.c[k], at), at);
      total = sum_add(total, s, at);
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

}  // namespace simit::jit::trace_detail
