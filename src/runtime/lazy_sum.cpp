// LazySum (runtime/lazy_sum.h): add_into's sum, block by block where it is read.
#include "runtime/lazy_sum.h"

#include <algorithm>
#include <cstring>
#include <stdexcept>
#include <string>

namespace simit::runtime {

namespace {

// Whether every block of a lies in b's pattern (both canonical: ascending columns per row).
bool blocks_within(const MatrixPattern& a, const MatrixPattern& b) {
  if (!a.canonical() || !b.canonical() || a.rows() != b.rows() || a.cols() != b.cols())
    return false;
  const int32_t *ar = a.row_ptr().data(), *ac = a.col_idx().data();
  const int32_t *br = b.row_ptr().data(), *bc = b.col_idx().data();
  for (int r = 0; r < a.rows(); ++r) {
    int32_t k = br[r];
    for (int32_t i = ar[r]; i < ar[r + 1]; ++i) {
      while (k < br[r + 1] && bc[k] < ac[i]) ++k;
      if (k == br[r + 1] || bc[k] != ac[i]) return false;
    }
  }
  return true;
}

}  // namespace

bool fits_into(const SystemMatrix& a, const SystemMatrix& b) {
  if (!a.is_float() || !b.is_float() || a.block_rows() != b.block_rows() ||
      a.block_cols() != b.block_cols())
    return false;
  return a.shared_pattern() == b.shared_pattern() || blocks_within(a.pattern(), b.pattern());
}

LazySum::LazySum(std::shared_ptr<const SystemMatrix> a, double alpha, PatternPtr b_pattern,
                 const double* b_values, int block_size, double beta, bool float32)
    : a_(std::move(a)),
      va_(a_->values()),  // home first (a matrix an executor holds elsewhere)
      alpha_(alpha),
      pb_(std::move(b_pattern)),
      vb_(b_values),
      bs_(block_size),
      beta_(beta),
      float32_(float32),
      same_(a_->shared_pattern() == pb_) {
  // Its blocks are summed in a stack array of kMaxBlock values (callers test the size first).
  if (bs_ < 1 || bs_ > kMaxBlock)
    throw std::invalid_argument("LazySum: blocks of 1 to " + std::to_string(kMaxBlock) +
                                " values, not " + std::to_string(bs_));
}

void LazySum::write(double* out) const {
  const size_t bs = static_cast<size_t>(bs_);
  const int32_t rows = pb_->rows();
  for (int32_t r = 0; r < rows; ++r)
    row(r, [&](int32_t k, const double* block) {
      std::memcpy(out + static_cast<size_t>(k) * bs, block, bs * sizeof(double));
    });
}

}  // namespace simit::runtime
