// Block CSR to scalar compressed columns, by one counting sort over the blocks.
#include "runtime/sparse_convert.h"

namespace simit::runtime {

namespace {

void check_index_range(int64_t n, const char* what) {
  if (n > INT32_MAX) throw Fault(std::string("a matrix with more than 2^31 scalar ") + what);
}

// Sums entries with equal row that sit next to each other in a column (stencil repeats).
void merge_repeats(EigenSparse& m) {
  int* outer = m.outerIndexPtr();
  int* inner = m.innerIndexPtr();
  double* values = m.valuePtr();
  int out = 0;
  for (Eigen::Index c = 0; c < m.cols(); ++c) {
    const int first = outer[c], last = outer[c + 1];
    outer[c] = out;
    for (int k = first; k < last; ++k) {
      if (out > outer[c] && inner[out - 1] == inner[k]) {
        values[out - 1] += values[k];
      } else {
        inner[out] = inner[k];
        values[out++] = values[k];
      }
    }
  }
  outer[m.cols()] = out;
  m.resizeNonZeros(out);
}

}  // namespace

EigenSparse to_eigen(const SystemMatrix& a) {
  if (!a.is_float())
    throw Fault(std::string("only float matrices convert to Eigen's, not ") +
                component_name(a.kind()) + " ones");
  const int br = a.block_rows(), bc = a.block_cols(), bs = a.block_size();
  const int64_t nnz = a.pattern().nnz() * bs;
  check_index_range(a.scalar_rows(), "rows");
  check_index_range(a.scalar_cols(), "columns");
  check_index_range(nnz, "entries");
  EigenSparse m(a.scalar_rows(), a.scalar_cols());
  m.resizeNonZeros(nnz);
  int* outer = m.outerIndexPtr();
  int* inner = m.innerIndexPtr();
  double* values = m.valuePtr();
  const std::vector<int32_t>& row_ptr = a.pattern().row_ptr();
  const std::vector<int32_t>& col_idx = a.pattern().col_idx();
  std::fill(outer, outer + m.cols() + 1, 0);
  for (int32_t c : col_idx)
    for (int j = 0; j < bc; ++j) outer[static_cast<int64_t>(c) * bc + j + 1] += br;
  for (Eigen::Index c = 0; c < m.cols(); ++c) outer[c + 1] += outer[c];
  std::vector<int> next(outer, outer + m.cols());
  for (int r = 0; r < a.rows(); ++r)
    for (int i = 0; i < br; ++i)
      for (int32_t k = row_ptr[r]; k < row_ptr[r + 1]; ++k) {
        const double* blk = a.block(k) + i * bc;
        for (int j = 0; j < bc; ++j) {
          const int at = next[static_cast<size_t>(col_idx[k]) * bc + j]++;
          inner[at] = r * br + i;
          values[at] = blk[j];
        }
      }
  if (!a.pattern().canonical()) merge_repeats(m);
  return m;
}

Eigen::MatrixXd to_dense(const SystemMatrix& a) { return Eigen::MatrixXd(to_eigen(a)); }

}  // namespace simit::runtime
