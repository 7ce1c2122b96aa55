// Linear algebra on system matrices and global vectors, as loops over the block arrays.
#include "runtime/system_ops.h"

#include <algorithm>
#include <cmath>
#include <string>

namespace simit::runtime {

namespace {

std::string dims(int64_t rows, int64_t cols) {
  return std::to_string(rows) + " x " + std::to_string(cols);
}

void check_length(size_t got, int64_t want, const char* what) {
  if (static_cast<int64_t>(got) != want)
    throw Fault(std::string(what) + " has " + std::to_string(got) + " components but " +
                std::to_string(want) + " are needed");
}

void check_same(size_t a, size_t b) {
  if (a != b)
    throw Fault("vectors of " + std::to_string(a) + " and " + std::to_string(b) +
                " components cannot be combined");
}

// Block kernels: compile-time sizes for the common blocks, run-time sizes (0) otherwise.
template <int BR, int BC>
void matvec_rows(const SystemMatrix& a, const double* x, double* y) {
  const int br = BR ? BR : a.block_rows(), bc = BC ? BC : a.block_cols();
  const int32_t* row_ptr = a.pattern().row_ptr().data();
  const int32_t* col_idx = a.pattern().col_idx().data();
  const double* v = a.values();
  for (int r = 0; r < a.rows(); ++r) {
    double* yr = y + static_cast<size_t>(r) * br;
    for (int i = 0; i < br; ++i) yr[i] = 0.0;
    for (int32_t k = row_ptr[r]; k < row_ptr[r + 1]; ++k) {
      const double* blk = v + static_cast<size_t>(k) * br * bc;
      const double* xc = x + static_cast<size_t>(col_idx[k]) * bc;
      for (int i = 0; i < br; ++i)
        for (int j = 0; j < bc; ++j) yr[i] += blk[i * bc + j] * xc[j];
    }
  }
}

template <int BR, int BC>
void matvec_transposed_rows(const SystemMatrix& a, const double* x, double* y) {
  const int br = BR ? BR : a.block_rows(), bc = BC ? BC : a.block_cols();
  const int32_t* row_ptr = a.pattern().row_ptr().data();
  const int32_t* col_idx = a.pattern().col_idx().data();
  const double* v = a.values();
  for (int r = 0; r < a.rows(); ++r) {
    const double* xr = x + static_cast<size_t>(r) * br;
    for (int32_t k = row_ptr[r]; k < row_ptr[r + 1]; ++k) {
      const double* blk = v + static_cast<size_t>(k) * br * bc;
      double* yc = y + static_cast<size_t>(col_idx[k]) * bc;
      for (int i = 0; i < br; ++i)
        for (int j = 0; j < bc; ++j) yc[j] += blk[i * bc + j] * xr[i];
    }
  }
}

template <template <int, int> class Kernel>
void dispatch_blocks(const SystemMatrix& a, const double* x, double* y) {
  const int br = a.block_rows(), bc = a.block_cols();
  if (br == 1 && bc == 1) return Kernel<1, 1>::run(a, x, y);
  if (br == 2 && bc == 2) return Kernel<2, 2>::run(a, x, y);
  if (br == 3 && bc == 3) return Kernel<3, 3>::run(a, x, y);
  if (br == 4 && bc == 4) return Kernel<4, 4>::run(a, x, y);
  Kernel<0, 0>::run(a, x, y);
}

template <int BR, int BC>
struct Matvec {
  static void run(const SystemMatrix& a, const double* x, double* y) {
    matvec_rows<BR, BC>(a, x, y);
  }
};

template <int BR, int BC>
struct MatvecTransposed {
  static void run(const SystemMatrix& a, const double* x, double* y) {
    matvec_transposed_rows<BR, BC>(a, x, y);
  }
};

void check_block_match(const SystemMatrix& a, const SystemMatrix& b, const char* op) {
  if (a.block_rows() != b.block_rows() || a.block_cols() != b.block_cols() ||
      a.rows() != b.rows() || a.cols() != b.cols())
    throw Fault(std::string("cannot ") + op + " a " + dims(a.rows(), a.cols()) + " matrix of " +
                dims(a.block_rows(), a.block_cols()) + " blocks and a " + dims(b.rows(), b.cols()) +
                " matrix of " + dims(b.block_rows(), b.block_cols()) + " blocks");
}

// Scatters s * (blocks of m) into out, block k going to position to[k].
void scatter_scaled(double s, const SystemMatrix& m, const std::vector<int32_t>& to,
                    SystemMatrix& out) {
  const int bs = m.block_size();
  const double* v = m.values();
  for (size_t k = 0; k < to.size(); ++k) {
    double* dst = out.block(to[k]);
    for (int i = 0; i < bs; ++i) dst[i] += s * v[k * bs + i];
  }
}

// Column structure of the product A B: for each row of A, the distinct columns reached.
PatternPtr product_pattern(const MatrixPattern& a, const MatrixPattern& b) {
  std::vector<int32_t> row_ptr(static_cast<size_t>(a.rows()) + 1, 0), col_idx;
  std::vector<int32_t> mark(static_cast<size_t>(b.cols()), -1);
  for (int r = 0; r < a.rows(); ++r) {
    const size_t row_start = col_idx.size();
    for (int32_t k = a.row_ptr()[r]; k < a.row_ptr()[r + 1]; ++k) {
      const int mid = a.col_idx()[k];
      for (int32_t l = b.row_ptr()[mid]; l < b.row_ptr()[mid + 1]; ++l) {
        const int32_t c = b.col_idx()[l];
        if (mark[c] != r) {
          mark[c] = r;
          col_idx.push_back(c);
        }
      }
    }
    std::sort(col_idx.begin() + static_cast<std::ptrdiff_t>(row_start), col_idx.end());
    if (col_idx.size() > static_cast<size_t>(INT32_MAX))
      throw Fault("a matrix product with more than 2^31 blocks");
    row_ptr[r + 1] = static_cast<int32_t>(col_idx.size());
  }
  return MatrixPattern::from_csr(a.rows(), b.cols(), std::move(row_ptr), std::move(col_idx));
}

}  // namespace

// ---------------------------------------------------------------------------
// Matrix-vector products

void multiply(const SystemMatrix& a, std::span<const double> x, std::span<double> y) {
  check_length(x.size(), a.scalar_cols(), "the vector multiplied by the matrix");
  check_length(y.size(), a.scalar_rows(), "the result of the matrix-vector product");
  dispatch_blocks<Matvec>(a, x.data(), y.data());
}

void multiply_transposed(const SystemMatrix& a, std::span<const double> x, std::span<double> y) {
  check_length(x.size(), a.scalar_rows(), "the vector multiplied by the transposed matrix");
  check_length(y.size(), a.scalar_cols(), "the result of the transposed product");
  std::fill(y.begin(), y.end(), 0.0);
  dispatch_blocks<MatvecTransposed>(a, x.data(), y.data());
}

// ---------------------------------------------------------------------------
// Matrix arithmetic

SystemMatrix add(const SystemMatrix& a, const SystemMatrix& b, double alpha, double beta,
                 PatternRegistry* registry) {
  check_block_match(a, b, "add");
  if (a.shared_pattern() == b.shared_pattern()) {
    SystemMatrix out(a.shared_pattern(), a.block_rows(), a.block_cols());
    double* o = out.values();
    const double *va = a.values(), *vb = b.values();
    for (size_t i = 0; i < out.value_count(); ++i) o[i] = alpha * va[i] + beta * vb[i];
    return out;
  }
  std::shared_ptr<const PatternUnion> u =
      registry ? registry->united(a.shared_pattern(), b.shared_pattern())
               : std::make_shared<const PatternUnion>(unite(a.pattern(), b.pattern()));
  SystemMatrix out(u->pattern, a.block_rows(), a.block_cols());
  scatter_scaled(alpha, a, u->from_a, out);
  scatter_scaled(beta, b, u->from_b, out);
  return out;
}

SystemMatrix scaled(double s, const SystemMatrix& a) {
  SystemMatrix out = a;
  scale(s, out);
  return out;
}

void scale(double s, SystemMatrix& a) {
  double* v = a.values();
  for (size_t i = 0; i < a.value_count(); ++i) v[i] *= s;
}

SystemMatrix transposed(const SystemMatrix& a, PatternRegistry* registry) {
  std::shared_ptr<const PatternTranspose> t =
      registry ? registry->transposed(a.shared_pattern())
               : std::make_shared<const PatternTranspose>(transpose(a.pattern()));
  const int br = a.block_rows(), bc = a.block_cols();
  SystemMatrix out(t->pattern, bc, br);
  for (size_t k = 0; k < t->position.size(); ++k) {
    const double* src = a.block(static_cast<int32_t>(k));
    double* dst = out.block(t->position[k]);
    for (int i = 0; i < br; ++i)
      for (int j = 0; j < bc; ++j) dst[j * br + i] = src[i * bc + j];
  }
  return out;
}

SystemMatrix multiply(const SystemMatrix& a, const SystemMatrix& b) {
  if (a.cols() != b.rows() || a.block_cols() != b.block_rows())
    throw Fault("cannot multiply a " + dims(a.scalar_rows(), a.scalar_cols()) + " matrix by a " +
                dims(b.scalar_rows(), b.scalar_cols()) + " matrix (blocks " +
                dims(a.block_rows(), a.block_cols()) + " and " +
                dims(b.block_rows(), b.block_cols()) + ")");
  SystemMatrix out(product_pattern(a.pattern(), b.pattern()), a.block_rows(), b.block_cols());
  const MatrixPattern &pa = a.pattern(), &pb = b.pattern(), &po = out.pattern();
  const int br = a.block_rows(), bm = a.block_cols(), bc = b.block_cols();
  std::vector<int32_t> slot(static_cast<size_t>(b.cols()), -1);  // column -> position in out
  for (int r = 0; r < a.rows(); ++r) {
    for (int32_t k = po.row_ptr()[r]; k < po.row_ptr()[r + 1]; ++k) slot[po.col_idx()[k]] = k;
    for (int32_t k = pa.row_ptr()[r]; k < pa.row_ptr()[r + 1]; ++k) {
      const int mid = pa.col_idx()[k];
      const double* x = a.block(k);
      for (int32_t l = pb.row_ptr()[mid]; l < pb.row_ptr()[mid + 1]; ++l) {
        const double* y = b.block(l);
        double* z = out.block(slot[pb.col_idx()[l]]);
        for (int i = 0; i < br; ++i)
          for (int m = 0; m < bm; ++m)
            for (int j = 0; j < bc; ++j) z[i * bc + j] += x[i * bm + m] * y[m * bc + j];
      }
    }
  }
  return out;
}

// ---------------------------------------------------------------------------
// Vectors

void axpy(double alpha, std::span<const double> x, std::span<double> y) {
  check_same(x.size(), y.size());
  for (size_t i = 0; i < x.size(); ++i) y[i] += alpha * x[i];
}

void scale(double s, std::span<double> x) {
  for (double& v : x) v *= s;
}

// Applies op component-wise; `out` may alias x or y.
template <class Op>
static void zip(std::span<const double> x, std::span<const double> y, std::span<double> out,
                Op op) {
  check_same(x.size(), y.size());
  check_same(x.size(), out.size());
  for (size_t i = 0; i < x.size(); ++i) out[i] = op(x[i], y[i]);
}

void add(std::span<const double> x, std::span<const double> y, std::span<double> out) {
  zip(x, y, out, [](double a, double b) { return a + b; });
}

void subtract(std::span<const double> x, std::span<const double> y, std::span<double> out) {
  zip(x, y, out, [](double a, double b) { return a - b; });
}

void multiply_elementwise(std::span<const double> x, std::span<const double> y,
                          std::span<double> out) {
  zip(x, y, out, [](double a, double b) { return a * b; });
}

void divide_elementwise(std::span<const double> x, std::span<const double> y,
                        std::span<double> out) {
  zip(x, y, out, [](double a, double b) { return a / b; });
}

double dot(std::span<const double> x, std::span<const double> y) {
  check_same(x.size(), y.size());
  double sum = 0.0;
  for (size_t i = 0; i < x.size(); ++i) sum += x[i] * y[i];
  return sum;
}

double norm(std::span<const double> x) { return std::sqrt(dot(x, x)); }

}  // namespace simit::runtime
