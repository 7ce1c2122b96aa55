// Results read after a run: dense tensors and assembled system matrices, over the runtime's.
#include "api/set_access.h"
#include "runtime/system_matrix.h"
#include "runtime/tensor.h"
#include "simit/program.h"

namespace simit {

ComponentKind DenseResult::kind() const { return api::host_kind(t_->kind()); }
size_t DenseResult::size() const { return t_->size(); }
std::vector<int> DenseResult::dims() const {
  const runtime::Shape& shape = t_->shape();
  std::vector<int> out;
  for (int i = 0; i < shape.rank(); ++i) out.push_back(shape.dim(i));
  return out;
}
const int32_t* DenseResult::ints() const { return t_->ints(); }
const double* DenseResult::floats() const { return t_->floats(); }
const bool* DenseResult::bools() const { return t_->bools(); }
const double_complex* DenseResult::complexes() const { return t_->complexes(); }

int SystemMatrixView::rows() const { return m_->rows(); }
int SystemMatrixView::cols() const { return m_->cols(); }
int SystemMatrixView::block_rows() const { return m_->block_rows(); }
int SystemMatrixView::block_cols() const { return m_->block_cols(); }
std::span<const int32_t> SystemMatrixView::row_ptr() const { return m_->pattern().row_ptr(); }
std::span<const int32_t> SystemMatrixView::col_idx() const { return m_->pattern().col_idx(); }
ComponentKind SystemMatrixView::kind() const { return api::host_kind(m_->kind()); }
std::span<const double> SystemMatrixView::values() const {
  return {m_->values(), m_->values() ? m_->value_count() : 0};
}
std::span<const int32_t> SystemMatrixView::ints() const {
  return {m_->ints(), m_->ints() ? m_->value_count() : 0};
}
std::span<const double_complex> SystemMatrixView::complexes() const {
  return {m_->complexes(), m_->complexes() ? m_->value_count() : 0};
}
double SystemMatrixView::operator()(int64_t i, int64_t j) const { return m_->component(i, j); }

}  // namespace simit
