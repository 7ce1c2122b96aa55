// Sparsity patterns from edge sets and grids, their registry, and block-sparse matrices.
#include "runtime/system_matrix.h"

#include <algorithm>
#include <set>
#include <type_traits>

namespace simit::runtime {

namespace {

std::vector<int> members_in(const Set& edges, const Set& target) {
  std::vector<int> members;
  for (int m = 0; m <= edges.arity(); ++m)
    if (&member_set(edges, m) == &target) members.push_back(m);
  return members;
}

int32_t checked_count(int64_t n, const char* what) {
  if (n > INT32_MAX) throw Fault(std::string("a matrix pattern with more than 2^31 ") + what);
  return static_cast<int32_t>(n);
}

bool rows_canonical(const std::vector<int32_t>& row_ptr, const std::vector<int32_t>& col_idx) {
  for (size_t r = 0; r + 1 < row_ptr.size(); ++r)
    for (int32_t k = row_ptr[r] + 1; k < row_ptr[r + 1]; ++k)
      if (col_idx[k] <= col_idx[k - 1]) return false;
  return true;
}

// For each row, the (element, row member) incidences that touch it, as element * R + i.
struct Incidences {
  std::vector<int64_t> start;  // rows + 1
  std::vector<int64_t> at;
};

Incidences row_incidences(const Set& edges, int rows, const std::vector<int>& rm) {
  Incidences inc;
  inc.start.assign(static_cast<size_t>(rows) + 1, 0);
  const int64_t n = edges.size(), r_count = static_cast<int64_t>(rm.size());
  for (int64_t e = 0; e < n; ++e)
    for (int m : rm) ++inc.start[member_element(edges, static_cast<int>(e), m) + 1];
  for (int r = 0; r < rows; ++r) inc.start[r + 1] += inc.start[r];
  inc.at.resize(static_cast<size_t>(inc.start[rows]));
  std::vector<int64_t> next(inc.start.begin(), inc.start.end() - 1);
  for (int64_t e = 0; e < n; ++e)
    for (int64_t i = 0; i < r_count; ++i)
      inc.at[next[member_element(edges, static_cast<int>(e), rm[i])]++] = e * r_count + i;
  return inc;
}

// Row by row: the distinct columns its incidences reach (sorted), then each incidence's
// block positions through a dense column -> position map, so no search is needed.
void build_rows(const Set& edges, const std::vector<int>& cm, const Incidences& inc, int cols,
                std::vector<int32_t>& row_ptr, std::vector<int32_t>& col_idx,
                AssemblyIndex& index) {
  const int64_t r_count = static_cast<int64_t>(index.row_members.size());
  const size_t c_count = cm.size(), pairs = index.pairs();
  const size_t rows = inc.start.size() - 1;
  std::vector<int32_t> mark(static_cast<size_t>(cols), -1), slot(static_cast<size_t>(cols), 0);
  row_ptr.assign(rows + 1, 0);
  for (size_t r = 0; r < rows; ++r) {
    const size_t row_start = col_idx.size();
    for (int64_t k = inc.start[r]; k < inc.start[r + 1]; ++k) {
      const int e = static_cast<int>(inc.at[k] / r_count);
      for (int m : cm) {
        const int32_t c = member_element(edges, e, m);
        if (mark[c] == static_cast<int32_t>(r)) continue;
        mark[c] = static_cast<int32_t>(r);
        col_idx.push_back(c);
      }
    }
    std::sort(col_idx.begin() + static_cast<std::ptrdiff_t>(row_start), col_idx.end());
    const int32_t row_end = checked_count(static_cast<int64_t>(col_idx.size()), "blocks");
    for (int32_t k = static_cast<int32_t>(row_start); k < row_end; ++k) slot[col_idx[k]] = k;
    for (int64_t k = inc.start[r]; k < inc.start[r + 1]; ++k) {
      const int64_t e = inc.at[k] / r_count, i = inc.at[k] % r_count;
      int32_t* out = index.table.data() + static_cast<size_t>(e) * pairs + i * c_count;
      for (size_t j = 0; j < c_count; ++j)
        out[j] = slot[member_element(edges, static_cast<int>(e), cm[j])];
    }
    row_ptr[r + 1] = row_end;
  }
  col_idx.shrink_to_fit();
}

int32_t position_in_row(const std::vector<int32_t>& row_ptr, const std::vector<int32_t>& col_idx,
                        int row, int col) {
  auto first = col_idx.begin() + row_ptr[row], last = col_idx.begin() + row_ptr[row + 1];
  auto it = std::lower_bound(first, last, col);
  return it != last && *it == col ? static_cast<int32_t>(it - col_idx.begin()) : -1;
}

// An axis kept only where it fits the pattern's rows (columns).
MeshAxisPtr fitting(MeshAxisPtr axis, int blocks) {
  return axis && axis->mesh_numbers.size() == static_cast<size_t>(blocks) ? std::move(axis)
                                                                          : nullptr;
}

}  // namespace

// ---------------------------------------------------------------------------
// Mesh axes

MeshAxisPtr MeshAxis::of(const Set& s) {
  if (!s.has_mesh_numbers()) return nullptr;
  auto axis = std::make_shared<MeshAxis>();
  axis->set = s.describe();
  axis->mesh_numbers.assign(s.mesh_numbers().begin(), s.mesh_numbers().end());
  return axis;
}

std::string MeshAxis::element(int block) const {
  const bool known = block >= 0 && static_cast<size_t>(block) < mesh_numbers.size();
  return "element " + std::to_string(known ? mesh_numbers[static_cast<size_t>(block)] : block) +
         " of " + set;
}

// ---------------------------------------------------------------------------
// Construction

std::shared_ptr<const MatrixPattern> MatrixPattern::assembled(const Set& edges, const Set& rows,
                                                              const Set& cols) {
  std::shared_ptr<MatrixPattern> p(new MatrixPattern);
  p->rows_ = rows.size();
  p->cols_ = cols.size();
  const std::vector<int> rm = members_in(edges, rows), cm = members_in(edges, cols);
  p->assembly_ = AssemblyIndex{rm, cm, {}};
  p->assembly_.table.resize(static_cast<size_t>(edges.size()) * p->assembly_.pairs());
  build_rows(edges, cm, row_incidences(edges, p->rows_, rm), p->cols_, p->row_ptr_, p->col_idx_,
             p->assembly_);
  p->edges_id_ = edges.id();
  p->row_axis_ = MeshAxis::of(rows);
  p->col_axis_ = &cols == &rows ? p->row_axis_ : MeshAxis::of(cols);
  return p;
}

std::shared_ptr<const MatrixPattern> MatrixPattern::from_csr(int rows, int cols,
                                                             std::vector<int32_t> row_ptr,
                                                             std::vector<int32_t> col_idx,
                                                             MeshAxisPtr row_axis,
                                                             MeshAxisPtr col_axis) {
  if (rows < 0 || cols < 0 || row_ptr.size() != static_cast<size_t>(rows) + 1 ||
      row_ptr.front() != 0 || row_ptr.back() != static_cast<int32_t>(col_idx.size()))
    throw Fault("invalid sparse matrix: row pointers do not match the " + std::to_string(rows) +
                " rows and " + std::to_string(col_idx.size()) + " entries");
  for (int r = 0; r < rows; ++r)
    if (row_ptr[r + 1] < row_ptr[r])
      throw Fault("invalid sparse matrix: row pointers decrease at row " + std::to_string(r));
  for (int32_t c : col_idx)
    if (c < 0 || c >= cols)
      throw Fault("invalid sparse matrix: column " + std::to_string(c) + " outside 0.." +
                  std::to_string(cols - 1));
  std::shared_ptr<MatrixPattern> p(new MatrixPattern);
  p->rows_ = rows;
  p->cols_ = cols;
  p->canonical_ = rows_canonical(row_ptr, col_idx);
  p->row_ptr_ = std::move(row_ptr);
  p->col_idx_ = std::move(col_idx);
  p->row_axis_ = fitting(std::move(row_axis), rows);
  p->col_axis_ = fitting(std::move(col_axis), cols);
  return p;
}

std::shared_ptr<const MatrixPattern> MatrixPattern::stencil(
    const Set& grid, const std::vector<std::vector<int>>& offsets) {
  if (!grid.is_grid()) throw Fault(grid.describe() + " is not a grid");
  const int n = grid.points().size();
  const int k = static_cast<int>(offsets.size());
  std::vector<int32_t> row_ptr(static_cast<size_t>(n) + 1), col_idx;
  col_idx.reserve(static_cast<size_t>(n) * k);
  for (int p = 0; p < n; ++p) {
    row_ptr[p] = checked_count(static_cast<int64_t>(p) * k, "blocks");
    for (const std::vector<int>& o : offsets) col_idx.push_back(grid.grid_point_at(p, o));
  }
  row_ptr[n] = checked_count(static_cast<int64_t>(n) * k, "blocks");
  MeshAxisPtr points = MeshAxis::of(grid.points());
  return from_csr(n, n, std::move(row_ptr), std::move(col_idx), points, points);
}

// ---------------------------------------------------------------------------
// Queries

int32_t MatrixPattern::find(int row, int col) const {
  if (row < 0 || row >= rows_ || col < 0 || col >= cols_)
    throw Fault("matrix position (" + std::to_string(row) + ", " + std::to_string(col) +
                ") is outside a " + std::to_string(rows_) + " x " + std::to_string(cols_) +
                " block matrix");
  if (canonical_) return position_in_row(row_ptr_, col_idx_, row, col);
  for (int32_t k = row_ptr_[row]; k < row_ptr_[row + 1]; ++k)
    if (col_idx_[k] == col) return k;
  return -1;
}

int32_t MatrixPattern::assembly_position(const Set& edges, int element, int row_element,
                                         int col_element) const {
  if (edges.id() != edges_id_)
    throw Fault("this matrix pattern was not assembled through " + edges.describe());
  const AssemblyIndex& a = assembly_;
  for (size_t i = 0; i < a.row_members.size(); ++i) {
    if (member_element(edges, element, a.row_members[i]) != row_element) continue;
    for (size_t j = 0; j < a.col_members.size(); ++j)
      if (member_element(edges, element, a.col_members[j]) == col_element)
        return a.position(element, static_cast<int>(i), static_cast<int>(j));
    return -1;
  }
  return -1;
}

size_t MatrixPattern::index_bytes() const {
  return (row_ptr_.size() + col_idx_.size()) * sizeof(int32_t);
}

size_t MatrixPattern::assembly_bytes() const { return assembly_.table.size() * sizeof(int32_t); }

// ---------------------------------------------------------------------------
// Derived patterns

PatternUnion unite(const MatrixPattern& a, const MatrixPattern& b) {
  if (a.rows() != b.rows() || a.cols() != b.cols())
    throw Fault("cannot add a " + std::to_string(a.rows()) + " x " + std::to_string(a.cols()) +
                " block matrix to a " + std::to_string(b.rows()) + " x " +
                std::to_string(b.cols()) + " one");
  std::vector<int32_t> row_ptr(static_cast<size_t>(a.rows()) + 1, 0), col_idx;
  col_idx.reserve(static_cast<size_t>(std::max(a.nnz(), b.nnz())));
  std::vector<int32_t> row;
  for (int r = 0; r < a.rows(); ++r) {
    row.assign(a.col_idx().begin() + a.row_ptr()[r], a.col_idx().begin() + a.row_ptr()[r + 1]);
    row.insert(row.end(), b.col_idx().begin() + b.row_ptr()[r],
               b.col_idx().begin() + b.row_ptr()[r + 1]);
    std::sort(row.begin(), row.end());
    col_idx.insert(col_idx.end(), row.begin(), std::unique(row.begin(), row.end()));
    row_ptr[r + 1] = checked_count(static_cast<int64_t>(col_idx.size()), "blocks");
  }
  PatternUnion u;
  auto place = [&](const MatrixPattern& p, std::vector<int32_t>& to) {
    to.resize(static_cast<size_t>(p.nnz()));
    for (int r = 0; r < p.rows(); ++r)
      for (int32_t k = p.row_ptr()[r]; k < p.row_ptr()[r + 1]; ++k)
        to[k] = position_in_row(row_ptr, col_idx, r, p.col_idx()[k]);
  };
  place(a, u.from_a);
  place(b, u.from_b);
  u.to_a.assign(col_idx.size(), -1);
  u.to_b.assign(col_idx.size(), -1);
  for (size_t k = 0; k < u.from_a.size(); ++k)
    u.to_a[static_cast<size_t>(u.from_a[k])] = static_cast<int32_t>(k);
  for (size_t k = 0; k < u.from_b.size(); ++k)
    u.to_b[static_cast<size_t>(u.from_b[k])] = static_cast<int32_t>(k);
  u.pattern = MatrixPattern::from_csr(a.rows(), a.cols(), std::move(row_ptr), std::move(col_idx),
                                      a.row_axis() ? a.row_axis() : b.row_axis(),
                                      a.col_axis() ? a.col_axis() : b.col_axis());
  return u;
}

PatternTranspose transpose(const MatrixPattern& p) {
  std::vector<int32_t> row_ptr(static_cast<size_t>(p.cols()) + 1, 0);
  for (int32_t c : p.col_idx()) ++row_ptr[c + 1];
  for (int c = 0; c < p.cols(); ++c) row_ptr[c + 1] += row_ptr[c];
  std::vector<int32_t> next(row_ptr.begin(), row_ptr.end() - 1), col_idx(p.col_idx().size());
  PatternTranspose t;
  t.position.resize(p.col_idx().size());
  for (int r = 0; r < p.rows(); ++r)
    for (int32_t k = p.row_ptr()[r]; k < p.row_ptr()[r + 1]; ++k) {
      const int32_t at = next[p.col_idx()[k]]++;
      col_idx[at] = r;
      t.position[k] = at;
    }
  t.pattern = MatrixPattern::from_csr(p.cols(), p.rows(), std::move(row_ptr), std::move(col_idx),
                                      p.col_axis(), p.row_axis());
  return t;
}

// ---------------------------------------------------------------------------
// Registry

PatternPtr PatternRegistry::assembled(const Set& edges, const Set& rows, const Set& cols) {
  const auto key = std::make_tuple(edges.id(), rows.id(), cols.id());
  const uint64_t versions[3] = {edges.topology_version(), rows.topology_version(),
                                cols.topology_version()};
  auto it = assembled_.find(key);
  if (it != assembled_.end() && std::equal(versions, versions + 3, it->second.versions))
    return it->second.pattern;
  Entry e{{versions[0], versions[1], versions[2]}, MatrixPattern::assembled(edges, rows, cols)};
  ++builds_;
  return assembled_.insert_or_assign(key, std::move(e)).first->second.pattern;
}

PatternPtr PatternRegistry::stencil(const Set& grid, const std::vector<std::vector<int>>& offsets) {
  if (!grid.is_grid()) throw Fault(grid.describe() + " is not a grid");
  auto key = std::make_pair(grid.id(), offsets);
  const uint64_t versions[3] = {grid.topology_version(), grid.points().topology_version(), 0};
  auto it = stencils_.find(key);
  if (it != stencils_.end() && std::equal(versions, versions + 3, it->second.versions))
    return it->second.pattern;
  Entry e{{versions[0], versions[1], versions[2]}, MatrixPattern::stencil(grid, offsets)};
  ++builds_;
  return stencils_.insert_or_assign(std::move(key), std::move(e)).first->second.pattern;
}

std::shared_ptr<const PatternUnion> PatternRegistry::united(const PatternPtr& a,
                                                            const PatternPtr& b) {
  auto& slot = unions_[{a.get(), b.get()}];
  if (!slot.second) {
    slot = {{a, b}, std::make_shared<const PatternUnion>(unite(*a, *b))};
    ++builds_;
  }
  return slot.second;
}

std::shared_ptr<const PatternTranspose> PatternRegistry::transposed(const PatternPtr& p) {
  auto& slot = transposes_[p.get()];
  if (!slot.second) {
    slot = {p, std::make_shared<const PatternTranspose>(transpose(*p))};
    ++builds_;
  }
  return slot.second;
}

void PatternRegistry::clear() {
  assembled_.clear();
  stencils_.clear();
  unions_.clear();
  transposes_.clear();
}

// ---------------------------------------------------------------------------
// Matrices

SystemMatrix::SystemMatrix(PatternPtr pattern, int block_rows, int block_cols, ComponentKind kind)
    : pattern_(std::move(pattern)), block_rows_(block_rows), block_cols_(block_cols), kind_(kind) {
  if (!pattern_) throw Fault("a system matrix needs a pattern");
  if (block_rows < 1 || block_cols < 1)
    throw Fault("invalid block size " + std::to_string(block_rows) + " x " +
                std::to_string(block_cols));
  const size_t n = static_cast<size_t>(pattern_->nnz()) * block_size();
  switch (kind) {
    case ComponentKind::Float: values_.assign(n, 0.0); break;
    case ComponentKind::Int:
    case ComponentKind::Bool: ints_.assign(n, 0); break;
    case ComponentKind::Complex: complexes_.assign(n, Complex()); break;
    default:
      throw Fault(std::string("system matrices of ") + component_name(kind) +
                  " components are not supported");
  }
}

SystemMatrix::SystemMatrix(Unset, PatternPtr pattern, int block_rows, int block_cols)
    : pattern_(std::move(pattern)), block_rows_(block_rows), block_cols_(block_cols) {
  values_.resize(static_cast<size_t>(pattern_->nnz()) * block_size());
}

void SystemMatrix::set_zero() {
  residency::settle(values_.data());  // every value written here: nothing to bring back
  std::fill(values_.begin(), values_.end(), 0.0);
  std::fill(ints_.begin(), ints_.end(), 0);
  std::fill(complexes_.begin(), complexes_.end(), Complex());
}

template <class T>
T SystemMatrix::component_as(int64_t i, int64_t j) const {
  if (i < 0 || i >= scalar_rows() || j < 0 || j >= scalar_cols())
    throw Fault("matrix component (" + std::to_string(i) + ", " + std::to_string(j) +
                ") is outside a " + std::to_string(scalar_rows()) + " x " +
                std::to_string(scalar_cols()) + " matrix");
  const int r = static_cast<int>(i / block_rows_), c = static_cast<int>(j / block_cols_);
  const size_t within = static_cast<size_t>(i % block_rows_) * block_cols_ + j % block_cols_;
  const MatrixPattern& p = *pattern_;
  const T* v = data<T>();
  if (p.canonical()) {
    const int32_t k = p.find(r, c);
    return k < 0 ? T(0) : v[static_cast<size_t>(k) * block_size() + within];
  }
  // Repeated stencil entries add; ints wrap like the language's int arithmetic.
  using Sum = std::conditional_t<std::is_same_v<T, int32_t>, uint32_t, T>;
  Sum sum = 0;
  for (int32_t k = p.row_ptr()[r]; k < p.row_ptr()[r + 1]; ++k)
    if (p.col_idx()[k] == c)
      sum += static_cast<Sum>(v[static_cast<size_t>(k) * block_size() + within]);
  return static_cast<T>(sum);
}

template double SystemMatrix::component_as<double>(int64_t, int64_t) const;
template int32_t SystemMatrix::component_as<int32_t>(int64_t, int64_t) const;
template Complex SystemMatrix::component_as<Complex>(int64_t, int64_t) const;

double SystemMatrix::component(int64_t i, int64_t j) const {
  if (kind_ == ComponentKind::Complex)
    throw Fault("a component of a complex matrix is not a double");
  return is_float() ? component_as<double>(i, j) : component_as<int32_t>(i, j);
}

BlockDims block_dims(const Shape& block) {
  if (block.is_scalar()) return {};
  if (block.order() != 2 || !block.uniform())
    throw Fault("a system matrix cannot have blocks of shape " + block.str());
  const Shape logical = block.logical();
  return {logical.dim(0), logical.dim(1)};
}

size_t memory_bytes(std::span<const SystemMatrix* const> matrices) {
  std::set<const MatrixPattern*> seen;
  size_t bytes = 0;
  for (const SystemMatrix* m : matrices) {
    bytes += m->value_bytes();
    if (seen.insert(&m->pattern()).second) bytes += m->pattern().bytes();
  }
  return bytes;
}

}  // namespace simit::runtime
