// Sparse solvers: CHOLMOD for Cholesky, Eigen's SparseLU for LU, forward substitution.
#include "runtime/solvers.h"

#include <cholmod.h>

#include <Eigen/SparseLU>
#include <algorithm>
#include <functional>
#include <string>
#include <vector>

#include "runtime/sparse_convert.h"

namespace simit::runtime {

namespace {

void check_square(const SystemMatrix& a, const char* what) {
  if (!a.is_float())
    throw Fault(std::string(what) + " needs a matrix of float components, not " +
                component_name(a.kind()));
  if (a.scalar_rows() != a.scalar_cols())
    throw Fault(std::string(what) + " needs a square matrix but this one is " +
                std::to_string(a.scalar_rows()) + " x " + std::to_string(a.scalar_cols()));
}

void check_rhs(size_t b, size_t x, int64_t n) {
  if (static_cast<int64_t>(b) != n || static_cast<int64_t>(x) != n)
    throw Fault("a solve with a " + std::to_string(n) + " x " + std::to_string(n) +
                " matrix needs right-hand side and result of " + std::to_string(n) +
                " components, not " + std::to_string(b) + " and " + std::to_string(x));
}

// Scalar row (column) i of a matrix with `block` rows (columns) per block, for messages:
// "row 7 (element 2, component 1)". Where the blocks are the elements of a set a scene
// renumbered (`axis`), the internal numbers mean nothing to the user: the element is named
// by its mesh number instead, "the row of component 1 of element 12 of set 'verts'".
std::string line_str(const char* line, int64_t i, int block, const MeshAxis* axis) {
  if (axis) {
    const std::string element = axis->element(static_cast<int>(i / block));
    return std::string("the ") + line + " of " +
           (block == 1 ? element : "component " + std::to_string(i % block) + " of " + element);
  }
  if (block == 1) return line + (" " + std::to_string(i));
  return line + (" " + std::to_string(i)) + " (element " + std::to_string(i / block) +
         ", component " + std::to_string(i % block) + ")";
}

std::string row_str(int64_t i, const SystemMatrix& a) {
  return line_str("row", i, a.block_rows(), a.pattern().row_axis().get());
}

// The matrix a factorisation reads: the logical matrix without its zero entries. A block
// pattern's explicit zeros (blocks no element writes, zero components of written blocks) would
// change the fill-reducing ordering, and with it the factor's rounding: without them the
// factor, and every solve's bits, are the same for a matrix on any pattern that holds its
// nonzeros (the JIT assembles a map's matrix on the blocks it writes, docs/jit.md).
EigenSparse solver_form(const SystemMatrix& a) {
  EigenSparse m = to_eigen(a);
  m.prune([](auto, auto, double v) { return v != 0.0; });  // a NaN is kept
  m.makeCompressed();
  return m;
}

constexpr const char* kSingularLu =
    "LU factorisation failed: the matrix is singular (elimination found no nonzero pivot for one "
    "of its columns)";

// The singular LU's message for a matrix whose column c is empty: the column is named where it
// is a renumbered set's element (the message is otherwise kSingularLu's).
std::string empty_column_lu(int64_t c, const SystemMatrix& a) {
  const MeshAxis* axis = a.pattern().col_axis().get();
  if (!axis) return kSingularLu;
  return "LU factorisation failed: the matrix is singular (" +
         line_str("column", c, a.block_cols(), axis) + " has no nonzero entry)";
}

// The first column of m without an entry, or -1: the matrix is singular (SparseLU would not
// return on such a matrix, and CHOLMOD would find its pivot zero).
int64_t empty_column(const EigenSparse& m) {
  for (Eigen::Index c = 0; c < m.outerSize(); ++c)
    if (m.outerIndexPtr()[c] == m.outerIndexPtr()[c + 1]) return c;
  return -1;
}

// The structure of the matrix a symbolic analysis was made for: one whose values put their
// zeros elsewhere is analysed again.
struct Structure {
  std::vector<int> outer, inner;
  bool same(const EigenSparse& m) const {
    return std::equal(outer.begin(), outer.end(), m.outerIndexPtr(),
                      m.outerIndexPtr() + m.outerSize() + 1) &&
           std::equal(inner.begin(), inner.end(), m.innerIndexPtr(),
                      m.innerIndexPtr() + m.nonZeros());
  }
  void take(const EigenSparse& m) {
    outer.assign(m.outerIndexPtr(), m.outerIndexPtr() + m.outerSize() + 1);
    inner.assign(m.innerIndexPtr(), m.innerIndexPtr() + m.nonZeros());
  }
};

using VectorSolve = std::function<void(std::span<const double>, std::span<double>)>;

// X = A⁻¹ B column by column; X keeps only the nonzeros of each solved column.
SystemMatrix solve_columns(const SystemMatrix& b, int64_t n, const VectorSolve& solve) {
  if (b.scalar_rows() != n)
    throw Fault("a solve with a " + std::to_string(n) + " x " + std::to_string(n) +
                " matrix needs a right-hand side of " + std::to_string(n) + " rows, not " +
                std::to_string(b.scalar_rows()));
  const EigenSparse bs = to_eigen(b);
  const int cols = static_cast<int>(bs.cols());
  std::vector<double> rhs(static_cast<size_t>(n)), x(static_cast<size_t>(n));
  std::vector<std::vector<std::pair<int32_t, double>>> by_row(static_cast<size_t>(n));
  for (int c = 0; c < cols; ++c) {
    std::fill(rhs.begin(), rhs.end(), 0.0);
    for (EigenSparse::InnerIterator it(bs, c); it; ++it) rhs[it.row()] = it.value();
    solve(rhs, x);
    for (int64_t r = 0; r < n; ++r)
      if (x[r] != 0.0) by_row[r].emplace_back(c, x[r]);
  }
  std::vector<int32_t> row_ptr(static_cast<size_t>(n) + 1, 0), col_idx;
  std::vector<double> values;
  for (int64_t r = 0; r < n; ++r) {
    for (auto [c, v] : by_row[r]) {
      col_idx.push_back(c);
      values.push_back(v);
    }
    row_ptr[r + 1] = static_cast<int32_t>(col_idx.size());
  }
  SystemMatrix out(
      MatrixPattern::from_csr(static_cast<int>(n), cols, std::move(row_ptr), std::move(col_idx)));
  std::copy(values.begin(), values.end(), out.values());
  return out;
}

}  // namespace

// ---------------------------------------------------------------------------
// Cholesky (CHOLMOD)

struct CholeskyFactor::Impl {
  cholmod_common common;
  cholmod_factor* factor = nullptr;
  PatternPtr analysed;  // the pattern the symbolic analysis belongs to
  Structure structure;  // its nonzeros' structure
  int block_rows = 0, block_cols = 0;
  int64_t n = 0;  // CHOLMOD rejects empty matrices, so those never reach it
  // Solve workspace, reused between solves.
  mutable cholmod_dense* x = nullptr;
  mutable cholmod_dense* y = nullptr;
  mutable cholmod_dense* e = nullptr;

  Impl() {
    cholmod_start(&common);
    common.print = 0;  // failures become Faults; CHOLMOD need not print them too
    // LLᵀ also for simplicial factors: LDLᵀ would accept indefinite matrices silently.
    common.final_ll = 1;
  }
  ~Impl() {
    cholmod_free_dense(&x, &common);
    cholmod_free_dense(&y, &common);
    cholmod_free_dense(&e, &common);
    cholmod_free_factor(&factor, &common);
    cholmod_finish(&common);
  }
  void factorize(const SystemMatrix& a);
  void check_status(const char* step) const;
};

void CholeskyFactor::Impl::check_status(const char* step) const {
  if (common.status < CHOLMOD_OK)
    throw Fault(std::string("Cholesky factorisation failed in ") + step + " (CHOLMOD status " +
                std::to_string(common.status) +
                (common.status == CHOLMOD_OUT_OF_MEMORY ? ": out of memory)" : ")"));
}

void CholeskyFactor::Impl::factorize(const SystemMatrix& a) {
  check_square(a, "Cholesky factorisation");
  n = a.scalar_rows();
  if (n == 0) {
    analysed = a.shared_pattern();
    return;
  }
  EigenSparse m = solver_form(a);  // the one conversion; CHOLMOD reads its arrays in place
  if (const int64_t c = empty_column(m); c >= 0) {
    analysed.reset();
    throw Fault(
        "Cholesky factorisation failed: the matrix is not positive definite (the pivot "
        "of " +
        row_str(c, a) + " is not positive)");
  }
  cholmod_sparse s{};
  s.nrow = s.ncol = static_cast<size_t>(m.rows());
  s.nzmax = static_cast<size_t>(m.nonZeros());
  s.p = m.outerIndexPtr();
  s.i = m.innerIndexPtr();
  s.x = m.valuePtr();
  s.stype = 1;  // symmetric: the upper triangle is read, the lower ignored
  s.itype = CHOLMOD_INT;
  s.xtype = CHOLMOD_REAL;
  s.dtype = CHOLMOD_DOUBLE;
  s.sorted = 1;
  s.packed = 1;
  const bool same = factor && analysed == a.shared_pattern() && block_rows == a.block_rows() &&
                    block_cols == a.block_cols() && structure.same(m);
  if (!same) {
    cholmod_free_factor(&factor, &common);
    factor = cholmod_analyze(&s, &common);
    check_status("the analysis");
    analysed = a.shared_pattern();
    structure.take(m);
    block_rows = a.block_rows();
    block_cols = a.block_cols();
  }
  cholmod_factorize(&s, factor, &common);
  if (common.status == CHOLMOD_NOT_POSDEF || factor->minor < factor->n) {
    const int* perm = static_cast<const int*>(factor->Perm);
    const int64_t row = perm ? perm[factor->minor] : static_cast<int64_t>(factor->minor);
    analysed.reset();  // the factor is unusable; analyse afresh next time
    throw Fault(
        "Cholesky factorisation failed: the matrix is not positive definite (the pivot "
        "of " +
        row_str(row, a) + " is not positive)");
  }
  check_status("the numeric factorisation");
}

CholeskyFactor::CholeskyFactor(const SystemMatrix& a) : impl_(std::make_unique<Impl>()) {
  impl_->factorize(a);
}
CholeskyFactor::CholeskyFactor(CholeskyFactor&&) noexcept = default;
CholeskyFactor& CholeskyFactor::operator=(CholeskyFactor&&) noexcept = default;
CholeskyFactor::~CholeskyFactor() = default;

void CholeskyFactor::refactor(const SystemMatrix& a) { impl_->factorize(a); }

int64_t CholeskyFactor::size() const { return impl_->n; }

void CholeskyFactor::solve(std::span<const double> b, std::span<double> x) const {
  const int64_t n = size();
  check_rhs(b.size(), x.size(), n);
  Impl& im = *impl_;
  if (!im.analysed) throw Fault("solve with a failed Cholesky factorisation");
  if (n == 0) return;
  cholmod_dense rhs{};
  rhs.nrow = rhs.nzmax = rhs.d = static_cast<size_t>(n);
  rhs.ncol = 1;
  rhs.x = const_cast<double*>(b.data());  // read only
  rhs.xtype = CHOLMOD_REAL;
  rhs.dtype = CHOLMOD_DOUBLE;
  cholmod_solve2(CHOLMOD_A, im.factor, &rhs, nullptr, &im.x, nullptr, &im.y, &im.e, &im.common);
  im.check_status("the solve");
  const double* result = static_cast<const double*>(im.x->x);
  std::copy(result, result + n, x.begin());
}

std::vector<double> CholeskyFactor::solve(std::span<const double> b) const {
  std::vector<double> x(b.size());
  solve(b, x);
  return x;
}

SystemMatrix CholeskyFactor::solve(const SystemMatrix& b) const {
  return solve_columns(b, size(),
                       [this](std::span<const double> r, std::span<double> x) { solve(r, x); });
}

// ---------------------------------------------------------------------------
// LU (Eigen)

struct LuFactor::Impl {
  Eigen::SparseLU<EigenSparse, Eigen::COLAMDOrdering<int>> lu;
  PatternPtr analysed;
  Structure structure;
  int block_rows = 0, block_cols = 0;
  int64_t n = 0;

  void factorize(const SystemMatrix& a) {
    check_square(a, "LU factorisation");
    n = a.scalar_rows();
    if (n == 0) {  // SparseLU divides by the size
      analysed = a.shared_pattern();
      return;
    }
    EigenSparse m = solver_form(a);
    if (const int64_t c = empty_column(m); c >= 0) {
      analysed.reset();
      throw Fault(empty_column_lu(c, a));
    }
    if (!(analysed == a.shared_pattern() && block_rows == a.block_rows() &&
          block_cols == a.block_cols() && structure.same(m))) {
      lu.analyzePattern(m);
      analysed = a.shared_pattern();
      structure.take(m);
      block_rows = a.block_rows();
      block_cols = a.block_cols();
    }
    lu.factorize(m);
    if (lu.info() != Eigen::Success) {
      analysed.reset();
      // Eigen says "STRUCTURALLY SINGULAR ... ZERO COLUMN AT k" for numerically singular
      // matrices too, k counting columns in its own ordering: no use to the user.
      if (lu.lastErrorMessage().starts_with("THE MATRIX IS STRUCTURALLY SINGULAR"))
        throw Fault(kSingularLu);
      throw Fault("LU factorisation failed: out of memory while factorising a " +
                  std::to_string(n) + "x" + std::to_string(n) + " matrix");
    }
  }
};

LuFactor::LuFactor(const SystemMatrix& a) : impl_(std::make_unique<Impl>()) { impl_->factorize(a); }
LuFactor::LuFactor(LuFactor&&) noexcept = default;
LuFactor& LuFactor::operator=(LuFactor&&) noexcept = default;
LuFactor::~LuFactor() = default;

void LuFactor::refactor(const SystemMatrix& a) { impl_->factorize(a); }

int64_t LuFactor::size() const { return impl_->n; }

void LuFactor::solve(std::span<const double> b, std::span<double> x) const {
  check_rhs(b.size(), x.size(), size());
  if (!impl_->analysed) throw Fault("solve with a failed LU factorisation");
  if (size() == 0) return;
  Eigen::Map<const Eigen::VectorXd> bm(b.data(), size());
  Eigen::VectorXd result = impl_->lu.solve(bm);  // a temporary: x may alias b
  std::copy(result.data(), result.data() + size(), x.begin());
}

std::vector<double> LuFactor::solve(std::span<const double> b) const {
  std::vector<double> x(b.size());
  solve(b, x);
  return x;
}

SystemMatrix LuFactor::solve(const SystemMatrix& b) const {
  return solve_columns(b, size(),
                       [this](std::span<const double> r, std::span<double> x) { solve(r, x); });
}

// ---------------------------------------------------------------------------
// Forward substitution and `\`

void lower_triangular_solve(const SystemMatrix& a, std::span<const double> b, std::span<double> x) {
  check_square(a, "triangularSolve");
  check_rhs(b.size(), x.size(), a.scalar_rows());
  const int br = a.block_rows(), bc = a.block_cols();
  const MatrixPattern& p = a.pattern();
  for (int r = 0; r < a.rows(); ++r)
    for (int i = 0; i < br; ++i) {
      const int64_t row = static_cast<int64_t>(r) * br + i;
      double sum = b[row], diagonal = 0.0;
      for (int32_t k = p.row_ptr()[r]; k < p.row_ptr()[r + 1]; ++k) {
        const double* blk = a.block(k) + i * bc;
        for (int j = 0; j < bc; ++j) {
          const int64_t col = static_cast<int64_t>(p.col_idx()[k]) * bc + j;
          if (col < row) sum -= blk[j] * x[col];
          if (col == row) diagonal += blk[j];
        }
      }
      if (diagonal == 0.0)
        throw Fault("triangularSolve: the diagonal entry of " + row_str(row, a) + " is zero");
      x[row] = sum / diagonal;
    }
}

bool is_symmetric(const SystemMatrix& a) {
  if (!a.is_float()) return false;
  if (a.rows() != a.cols() || a.block_rows() != a.block_cols()) return false;
  if (!a.pattern().canonical()) {
    const EigenSparse m = to_eigen(a);
    return EigenSparse(m - EigenSparse(m.transpose())).norm() == 0.0;
  }
  const MatrixPattern& p = a.pattern();
  const int b = a.block_rows();
  for (int r = 0; r < a.rows(); ++r)
    for (int32_t k = p.row_ptr()[r]; k < p.row_ptr()[r + 1]; ++k) {
      const int32_t t = p.find(p.col_idx()[k], r);
      const double* x = a.block(k);
      for (int i = 0; i < b; ++i)
        for (int j = 0; j < b; ++j) {
          const double mirrored = t < 0 ? 0.0 : a.block(t)[j * b + i];
          if (x[i * b + j] != mirrored) return false;
        }
    }
  return true;
}

std::vector<double> solve(const SystemMatrix& a, std::span<const double> b) {
  if (is_symmetric(a)) {
    try {
      return CholeskyFactor(a).solve(b);
    } catch (const Fault&) {
      // Not positive definite (or a size error that LU reports the same way): use LU.
    }
  }
  return LuFactor(a).solve(b);
}

}  // namespace simit::runtime
