// specialise (jit/specialise.h): the kept blocks, their pattern and the remapped table.
#include "jit/specialise.h"

#include <chrono>

namespace simit::jit {

std::optional<SpecialisedPattern> specialise(const runtime::PatternPtr& full,
                                             const std::vector<uint8_t>& marks, double max_kept,
                                             bool keep_diagonal) {
  const auto start = std::chrono::steady_clock::now();
  const runtime::MatrixPattern& p = *full;
  const int64_t total = p.nnz();
  if (!p.has_assembly_index() || !p.canonical() || static_cast<int64_t>(marks.size()) != total)
    return std::nullopt;
  std::vector<int32_t> position(static_cast<size_t>(total), -1);
  int32_t kept = 0;
  for (int r = 0; r < p.rows(); ++r)
    for (int32_t k = p.row_ptr()[r]; k < p.row_ptr()[r + 1]; ++k)
      if (marks[static_cast<size_t>(k)] || (keep_diagonal && p.col_idx()[k] == r))
        position[static_cast<size_t>(k)] = kept++;
  if (static_cast<double>(kept) > max_kept * static_cast<double>(total)) return std::nullopt;
  SpecialisedPattern s;
  s.full = full;
  s.kept = kept;
  s.total = total;
  std::vector<int32_t> row_ptr(static_cast<size_t>(p.rows()) + 1, 0), col_idx;
  col_idx.reserve(static_cast<size_t>(kept));
  for (int r = 0; r < p.rows(); ++r) {
    for (int32_t k = p.row_ptr()[r]; k < p.row_ptr()[r + 1]; ++k)
      if (position[static_cast<size_t>(k)] >= 0) col_idx.push_back(p.col_idx()[k]);
    row_ptr[static_cast<size_t>(r) + 1] = static_cast<int32_t>(col_idx.size());
  }
  s.pattern = runtime::MatrixPattern::from_csr(p.rows(), p.cols(), std::move(row_ptr),
                                               std::move(col_idx), p.row_axis(), p.col_axis());
  const std::vector<int32_t>& table = p.assembly().table;
  s.table.resize(table.size());
  for (size_t i = 0; i < table.size(); ++i)
    s.table[i] = table[i] < 0 ? -1 : position[static_cast<size_t>(table[i])];
  s.build_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return s;
}

bool same_blocks(const SpecialisedPattern& a, const SpecialisedPattern& b) {
  return a.full == b.full && a.kept == b.kept && a.table == b.table;
}

}  // namespace simit::jit
