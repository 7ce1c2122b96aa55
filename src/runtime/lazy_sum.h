// add_into's sum (runtime/system_ops.h) computed block by block where it is read, rather than
// written over b's values in a pass of its own: a fused `A = M - h^2 K` (jit/matrix_sum.h)
// whose only reader is a solver loop's binary32 copy of A is summed as the copy is made.
#pragma once

#include <cstdint>
#include <memory>

#include "runtime/system_matrix.h"

namespace simit::runtime {

// add_into's arithmetic for one component: x + beta * o, with x the A part of the union's
// sum (0.0 + alpha a, or alpha a where the patterns are one); under --float32 the product and
// the sum are each rounded to binary32, as the interpreter rounds `beta * B` and the sum.
template <bool F32>
inline double sum_component(double x, double beta, double o) {
  if constexpr (F32) {
    return static_cast<float>(x + static_cast<double>(static_cast<float>(beta * o)));
  } else {
    return x + beta * o;
  }
}

// Row r of add_into(a, alpha, b, beta)'s sum, the one arithmetic of add_into and LazySum (so
// that a sum read block by block has the bits of the sum written out): for each of b's blocks
// k in order, its values into dest(k), which may be b's own block (each value reads only its
// own), then done(k, dest(k)). a's values va lie on pa (`same`: b's pattern pb), b's are vb;
// blocks of BS values (0: bs, known at run time). Over the union, whose blocks are b's: 0.0 +
// alpha a where a has the block (+0.0 where it has none), then + beta b; on one pattern alpha
// a + beta b (add()'s combine, without the zero).
template <bool F32, int BS, class Dest, class Done>
void sum_row(const MatrixPattern& pa, const double* va, double alpha, const MatrixPattern& pb,
             const double* vb, double beta, int bs_now, bool same, int32_t r, Dest&& dest,
             Done&& done) {
  const size_t bs = BS ? static_cast<size_t>(BS) : static_cast<size_t>(bs_now);
  const int32_t* rpb = pb.row_ptr().data();
  if (same) {
    for (int32_t k = rpb[r]; k < rpb[r + 1]; ++k) {
      const double* x = va + static_cast<size_t>(k) * bs;
      const double* y = vb + static_cast<size_t>(k) * bs;
      double* o = dest(k);
      for (size_t c = 0; c < bs; ++c) o[c] = sum_component<F32>(alpha * x[c], beta, y[c]);
      done(k, static_cast<const double*>(o));
    }
    return;
  }
  int32_t i = pa.row_ptr()[static_cast<size_t>(r)];
  const int32_t a_end = pa.row_ptr()[static_cast<size_t>(r) + 1];
  const int32_t* ca = pa.col_idx().data();
  const int32_t* cb = pb.col_idx().data();
  for (int32_t k = rpb[r]; k < rpb[r + 1]; ++k) {
    const double* y = vb + static_cast<size_t>(k) * bs;
    double* o = dest(k);
    if (i < a_end && ca[i] == cb[k]) {
      const double* x = va + static_cast<size_t>(i++) * bs;
      for (size_t c = 0; c < bs; ++c) o[c] = sum_component<F32>(0.0 + alpha * x[c], beta, y[c]);
    } else {
      for (size_t c = 0; c < bs; ++c) o[c] = sum_component<F32>(0.0, beta, y[c]);
    }
    done(k, static_cast<const double*>(o));
  }
}

// Whether add_into(a, alpha, b, beta) can sum a into b's storage: float components, the same
// blocks, and every block of a within b's pattern. (A LazySum needs blocks of at most
// LazySum::kMaxBlock values too.)
bool fits_into(const SystemMatrix& a, const SystemMatrix& b);

// The values add_into(a, alpha, b, beta) gives b, row by row, from b's values as they are
// now (b_values, read only). a's blocks lie within b's pattern (fits_into), of at most
// kMaxBlock values; a is kept alive and must not change while the sum is read.
class LazySum {
 public:
  LazySum(std::shared_ptr<const SystemMatrix> a, double alpha, PatternPtr b_pattern,
          const double* b_values, int block_size, double beta, bool float32);

  const MatrixPattern& pattern() const { return *pb_; }
  const PatternPtr& shared_pattern() const { return pb_; }
  int block_size() const { return bs_; }
  bool float32() const { return float32_; }  // each value rounded to binary32

  // The largest block a LazySum sums (8 x 8): its blocks are summed on the stack.
  static constexpr int kMaxBlock = 64;

  // Calls f(k, block) for each block k of row r in order, `block` holding its block_size()
  // summed values for the length of the call. BS is the block size when known at compile time
  // (the loops over a block's values then unroll and vectorise), else 0. Safe to call from
  // several threads at once.
  template <int BS = 0, class F>
  void row(int32_t r, F&& f) const {
    if (float32_)
      row_in<true, BS>(r, f);
    else
      row_in<false, BS>(r, f);
  }

  // Every value of the sum into `out` (b's own storage or another array of its size).
  void write(double* out) const;

 private:
  template <bool F32, int BS, class F>
  void row_in(int32_t r, F& f) const {
    double o[BS ? BS : kMaxBlock];
    sum_row<F32, BS>(
        a_->pattern(), va_, alpha_, *pb_, vb_, beta_, bs_, same_, r, [&o](int32_t) { return o; },
        f);
  }

  std::shared_ptr<const SystemMatrix> a_;
  const double* va_;
  double alpha_;
  PatternPtr pb_;
  const double* vb_;
  int bs_;
  double beta_;
  bool float32_;
  bool same_;  // a on b's pattern
};

}  // namespace simit::runtime
