// PrunedMatrix (jit/pruned_matrix.h): one pass over the values, copying the non-zero blocks.
#include "jit/pruned_matrix.h"

#include <algorithm>

namespace simit::jit {

void PrunedMatrix::assign(const runtime::SystemMatrix& m) {
  const auto& rp = m.pattern().row_ptr();
  const auto& ci = m.pattern().col_idx();
  const int bs = m.block_size();
  const double* v = m.values();
  row_ptr.resize(rp.size());
  cols.clear();
  values.clear();
  total = m.pattern().nnz();
  row_ptr[0] = 0;
  for (size_t r = 0; r + 1 < rp.size(); ++r) {
    for (int32_t k = rp[r]; k < rp[r + 1]; ++k) {
      const double* blk = v + static_cast<size_t>(k) * bs;
      // A block is dropped only when every component is +0.0 or -0.0.
      if (std::all_of(blk, blk + bs, [](double x) { return x == 0.0; })) continue;
      cols.push_back(ci[k]);
      // Stored by columns: a compiled product reads block column j as one vector.
      const int n = m.block_rows();
      for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) values.push_back(blk[i * n + j]);
    }
    row_ptr[r + 1] = static_cast<int32_t>(cols.size());
  }
  kept = static_cast<int64_t>(cols.size());
}

}  // namespace simit::jit
