// Linear algebra on system matrices and global vectors, as loops over the block arrays.
#include "runtime/system_ops.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <type_traits>

#include "runtime/blocked_sum.h"
#include "runtime/dense_linalg.h"
#include "runtime/lazy_sum.h"
#include "runtime/sum_rounding.h"

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

// The type int components are accumulated in: unsigned, so that sums and products wrap
// (LANGUAGE.md §5.1) without undefined behaviour.
template <class T>
using Acc = std::conditional_t<std::is_same_v<T, int32_t>, uint32_t, T>;

// The component type that stores matrices of kind k.
template <class T>
bool stores(ComponentKind k) {
  if constexpr (std::is_same_v<T, double>) return k == ComponentKind::Float;
  if constexpr (std::is_same_v<T, Complex>) return k == ComponentKind::Complex;
  return k == ComponentKind::Int || k == ComponentKind::Bool;
}

// f(T{}) with T the component type that stores matrices of kind k.
template <class F>
decltype(auto) by_kind(ComponentKind k, F&& f) {
  if (k == ComponentKind::Float) return f(double{});
  if (k == ComponentKind::Complex) return f(Complex{});
  return f(int32_t{});
}

template <class T>
void check_kind(const SystemMatrix& a, const char* what) {
  if (!stores<T>(a.kind()))
    throw Fault(std::string("cannot ") + what + " a matrix of " + component_name(a.kind()) +
                " components with vectors of another component type");
}

// Block kernels: compile-time sizes for the common blocks, run-time sizes (0) otherwise; R
// rounds each product and addition (runtime/sum_rounding.h).
template <class R, class T, int BR, int BC>
void matvec_rows(const SystemMatrix& a, const T* x, T* y) {
  const int br = BR ? BR : a.block_rows(), bc = BC ? BC : a.block_cols();
  const int32_t* row_ptr = a.pattern().row_ptr().data();
  const int32_t* col_idx = a.pattern().col_idx().data();
  const T* v = a.data<T>();
  Acc<T> fixed[BR ? BR : 1];
  std::vector<Acc<T>> sized(BR ? 0 : static_cast<size_t>(br));
  Acc<T>* sum = BR ? fixed : sized.data();
  for (int r = 0; r < a.rows(); ++r) {
    T* yr = y + static_cast<size_t>(r) * br;
    for (int i = 0; i < br; ++i) sum[i] = 0;
    for (int32_t k = row_ptr[r]; k < row_ptr[r + 1]; ++k) {
      const T* blk = v + static_cast<size_t>(k) * br * bc;
      const T* xc = x + static_cast<size_t>(col_idx[k]) * bc;
      // Each block's row is summed from zero before it joins the row's sum: the additions
      // into sum[i] then form a chain one block long, not one component long.
      for (int i = 0; i < br; ++i) {
        Acc<T> part = 0;
        for (int j = 0; j < bc; ++j)
          part =
              R::r(part + R::r(static_cast<Acc<T>>(blk[i * bc + j]) * static_cast<Acc<T>>(xc[j])));
        sum[i] = R::r(sum[i] + part);
      }
    }
    for (int i = 0; i < br; ++i) yr[i] = static_cast<T>(sum[i]);
  }
}

// y must start at zero.
template <class R, class T, int BR, int BC>
void matvec_transposed_rows(const SystemMatrix& a, const T* x, T* y) {
  const int br = BR ? BR : a.block_rows(), bc = BC ? BC : a.block_cols();
  const int32_t* row_ptr = a.pattern().row_ptr().data();
  const int32_t* col_idx = a.pattern().col_idx().data();
  const T* v = a.data<T>();
  for (int r = 0; r < a.rows(); ++r) {
    const T* xr = x + static_cast<size_t>(r) * br;
    for (int32_t k = row_ptr[r]; k < row_ptr[r + 1]; ++k) {
      const T* blk = v + static_cast<size_t>(k) * br * bc;
      T* yc = y + static_cast<size_t>(col_idx[k]) * bc;
      for (int i = 0; i < br; ++i)
        for (int j = 0; j < bc; ++j)
          yc[j] = static_cast<T>(
              R::r(static_cast<Acc<T>>(yc[j]) +
                   R::r(static_cast<Acc<T>>(blk[i * bc + j]) * static_cast<Acc<T>>(xr[i]))));
    }
  }
}

template <template <class, class, int, int> class Kernel, class R, class T>
void dispatch_blocks(const SystemMatrix& a, const T* x, T* y) {
  const int br = a.block_rows(), bc = a.block_cols();
  if (br == 1 && bc == 1) return Kernel<R, T, 1, 1>::run(a, x, y);
  if (br == 2 && bc == 2) return Kernel<R, T, 2, 2>::run(a, x, y);
  if (br == 3 && bc == 3) return Kernel<R, T, 3, 3>::run(a, x, y);
  if (br == 4 && bc == 4) return Kernel<R, T, 4, 4>::run(a, x, y);
  Kernel<R, T, 0, 0>::run(a, x, y);
}

template <class R, class T, int BR, int BC>
struct Matvec {
  static void run(const SystemMatrix& a, const T* x, T* y) { matvec_rows<R, T, BR, BC>(a, x, y); }
};

template <class R, class T, int BR, int BC>
struct MatvecTransposed {
  static void run(const SystemMatrix& a, const T* x, T* y) {
    matvec_transposed_rows<R, T, BR, BC>(a, x, y);
  }
};

template <class T>
void multiply_into(const SystemMatrix& a, std::span<const T> x, std::span<T> y, bool float32) {
  check_kind<T>(a, "multiply");
  check_length(x.size(), a.scalar_cols(), "the vector multiplied by the matrix");
  check_length(y.size(), a.scalar_rows(), "the result of the matrix-vector product");
  with_sums(float32, [&]<class R>(R) { dispatch_blocks<Matvec, R>(a, x.data(), y.data()); });
}

template <class T>
void multiply_transposed_into(const SystemMatrix& a, std::span<const T> x, std::span<T> y,
                              bool float32) {
  check_kind<T>(a, "multiply");
  check_length(x.size(), a.scalar_rows(), "the vector multiplied by the transposed matrix");
  check_length(y.size(), a.scalar_cols(), "the result of the transposed product");
  std::fill(y.begin(), y.end(), T(0));
  with_sums(float32,
            [&]<class R>(R) { dispatch_blocks<MatvecTransposed, R>(a, x.data(), y.data()); });
}

void check_block_match(const SystemMatrix& a, const SystemMatrix& b, const char* op) {
  if (a.block_rows() != b.block_rows() || a.block_cols() != b.block_cols() ||
      a.rows() != b.rows() || a.cols() != b.cols())
    throw Fault(std::string("cannot ") + op + " a " + dims(a.rows(), a.cols()) + " matrix of " +
                dims(a.block_rows(), a.block_cols()) + " blocks and a " + dims(b.rows(), b.cols()) +
                " matrix of " + dims(b.block_rows(), b.block_cols()) + " blocks");
  if (a.kind() != b.kind())
    throw Fault(std::string("cannot ") + op + " a matrix of " + component_name(a.kind()) +
                " components and one of " + component_name(b.kind()) + " components");
}

// A scale factor for an int matrix: it must be an int32 (a double holds every one exactly).
int32_t int_factor(double s) {
  if (!(s == std::trunc(s) && s >= INT32_MIN && s <= INT32_MAX))
    throw Fault("an int matrix can only be scaled by an integer, not " + std::to_string(s));
  return static_cast<int32_t>(s);
}

// A factor in the component type T; only complex matrices take complex factors.
template <class T>
Acc<T> factor(Complex s) {
  if constexpr (std::is_same_v<T, Complex>) return s;
  if (s.imag() != 0.0) throw Fault("only a complex matrix can be scaled by a complex number");
  if constexpr (std::is_same_v<T, int32_t>)
    return static_cast<Acc<T>>(int_factor(s.real()));
  else
    return s.real();
}

// out[i] = alpha a[i] + beta b[i] over `n` components.
template <class T>
void combine(double alpha, const T* a, double beta, const T* b, T* out, size_t n) {
  const Acc<T> x = factor<T>(alpha), y = factor<T>(beta);
  for (size_t i = 0; i < n; ++i)
    out[i] = static_cast<T>(x * static_cast<Acc<T>>(a[i]) + y * static_cast<Acc<T>>(b[i]));
}

// Scatters s * (blocks of m) into out, block k going to position to[k].
template <class T>
void scatter_scaled(Complex s, const SystemMatrix& m, const std::vector<int32_t>& to,
                    SystemMatrix& out) {
  const int bs = m.block_size();
  const Acc<T> f = factor<T>(s);
  const T* v = m.data<T>();
  T* o = out.data<T>();
  for (size_t k = 0; k < to.size(); ++k) {
    T* dst = o + static_cast<size_t>(to[k]) * bs;
    for (int i = 0; i < bs; ++i)
      dst[i] = static_cast<T>(static_cast<Acc<T>>(dst[i]) + f * static_cast<Acc<T>>(v[k * bs + i]));
  }
}

std::shared_ptr<const PatternUnion> union_of(const SystemMatrix& a, const SystemMatrix& b,
                                             PatternRegistry* registry) {
  return registry ? registry->united(a.shared_pattern(), b.shared_pattern())
                  : std::make_shared<const PatternUnion>(unite(a.pattern(), b.pattern()));
}

// m on a canonical pattern: the blocks that m's pattern repeats in a row (stencil offsets
// that wrap to one point) summed into one, as every product and sum reads them. For the
// operations that are not linear in each block: element-wise products and int division.
SystemMatrix merged(const SystemMatrix& m, PatternRegistry* registry) {
  std::shared_ptr<const PatternUnion> u = union_of(m, m, registry);
  SystemMatrix out(u->pattern, m.block_rows(), m.block_cols(), m.kind());
  by_kind(m.kind(), [&](auto t) { scatter_scaled<decltype(t)>(1.0, m, u->from_a, out); });
  return out;
}

// out = alpha a + beta b over the union, each block written once, with the bits of zeroing out
// and scattering alpha a, then beta b, into it: 0.0 + alpha a where a has the block (+0.0
// where it has none), then + beta b where b has it.
template <int N>
void sum_blocks_of(const SystemMatrix& a, const SystemMatrix& b, double alpha, double beta,
                   const PatternUnion& u, double* out, int n) {
  const int bs = N ? N : n;
  const double *va = a.values(), *vb = b.values();
  const int32_t *ta = u.to_a.data(), *tb = u.to_b.data();
  const size_t blocks = u.to_a.size();
  for (size_t k = 0; k < blocks; ++k) {
    double* o = out + k * static_cast<size_t>(bs);
    const int32_t ia = ta[k], ib = tb[k];
    if (ia >= 0) {
      const double* x = va + static_cast<size_t>(ia) * bs;
      for (int i = 0; i < bs; ++i) o[i] = 0.0 + alpha * x[i];
    } else {
      for (int i = 0; i < bs; ++i) o[i] = 0.0;
    }
    if (ib >= 0) {
      const double* y = vb + static_cast<size_t>(ib) * bs;
      for (int i = 0; i < bs; ++i) o[i] = o[i] + beta * y[i];
    }
  }
}

void sum_blocks(const SystemMatrix& a, const SystemMatrix& b, double alpha, double beta,
                const PatternUnion& u, double* out) {
  switch (a.block_size()) {
    case 1: return sum_blocks_of<1>(a, b, alpha, beta, u, out, 1);
    case 4: return sum_blocks_of<4>(a, b, alpha, beta, u, out, 4);
    case 9: return sum_blocks_of<9>(a, b, alpha, beta, u, out, 9);
    default: return sum_blocks_of<0>(a, b, alpha, beta, u, out, a.block_size());
  }
}

template <class T>
void scale_values(Complex s, SystemMatrix& a) {
  const Acc<T> f = factor<T>(s);
  T* v = a.data<T>();
  for (size_t i = 0; i < a.value_count(); ++i) v[i] = static_cast<T>(f * static_cast<Acc<T>>(v[i]));
}

template <class T>
void transpose_blocks(const SystemMatrix& a, const PatternTranspose& t, SystemMatrix& out) {
  const int br = a.block_rows(), bc = a.block_cols(), bs = a.block_size();
  const T* v = a.data<T>();
  T* o = out.data<T>();
  for (size_t k = 0; k < t.position.size(); ++k) {
    const T* src = v + k * bs;
    T* dst = o + static_cast<size_t>(t.position[k]) * bs;
    for (int i = 0; i < br; ++i)
      for (int j = 0; j < bc; ++j) dst[j * br + i] = src[i * bc + j];
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
  return MatrixPattern::from_csr(a.rows(), b.cols(), std::move(row_ptr), std::move(col_idx),
                                 a.row_axis(), b.col_axis());
}

// out += A B, block by block, out having the product pattern; R rounds each product and
// addition.
template <class R, class T>
void product_values(const SystemMatrix& a, const SystemMatrix& b, SystemMatrix& out) {
  const MatrixPattern &pa = a.pattern(), &pb = b.pattern(), &po = out.pattern();
  const int br = a.block_rows(), bm = a.block_cols(), bc = b.block_cols();
  const T *va = a.data<T>(), *vb = b.data<T>();
  T* vo = out.data<T>();
  std::vector<int32_t> slot(static_cast<size_t>(b.cols()), -1);  // column -> position in out
  for (int r = 0; r < a.rows(); ++r) {
    for (int32_t k = po.row_ptr()[r]; k < po.row_ptr()[r + 1]; ++k) slot[po.col_idx()[k]] = k;
    for (int32_t k = pa.row_ptr()[r]; k < pa.row_ptr()[r + 1]; ++k) {
      const T* x = va + static_cast<size_t>(k) * br * bm;
      for (int32_t l = pb.row_ptr()[pa.col_idx()[k]]; l < pb.row_ptr()[pa.col_idx()[k] + 1]; ++l) {
        const T* y = vb + static_cast<size_t>(l) * bm * bc;
        T* z = vo + static_cast<size_t>(slot[pb.col_idx()[l]]) * br * bc;
        for (int i = 0; i < br; ++i)
          for (int m = 0; m < bm; ++m)
            for (int j = 0; j < bc; ++j)
              z[i * bc + j] = static_cast<T>(R::r(
                  static_cast<Acc<T>>(z[i * bc + j]) +
                  R::r(static_cast<Acc<T>>(x[i * bm + m]) * static_cast<Acc<T>>(y[m * bc + j]))));
      }
    }
  }
}

}  // namespace

// ---------------------------------------------------------------------------
// Matrix-vector products

void multiply(const SystemMatrix& a, std::span<const double> x, std::span<double> y, bool float32) {
  multiply_into(a, x, y, float32);
}
void multiply(const SystemMatrix& a, std::span<const int32_t> x, std::span<int32_t> y) {
  multiply_into(a, x, y, false);
}

void multiply_transposed(const SystemMatrix& a, std::span<const double> x, std::span<double> y,
                         bool float32) {
  multiply_transposed_into(a, x, y, float32);
}
void multiply_transposed(const SystemMatrix& a, std::span<const int32_t> x, std::span<int32_t> y) {
  multiply_transposed_into(a, x, y, false);
}
void multiply(const SystemMatrix& a, std::span<const Complex> x, std::span<Complex> y,
              bool float32) {
  multiply_into(a, x, y, float32);
}
void multiply_transposed(const SystemMatrix& a, std::span<const Complex> x, std::span<Complex> y,
                         bool float32) {
  multiply_transposed_into(a, x, y, float32);
}

// ---------------------------------------------------------------------------
// Matrix arithmetic

SystemMatrix add(const SystemMatrix& a, const SystemMatrix& b, double alpha, double beta,
                 PatternRegistry* registry) {
  check_block_match(a, b, "add");
  if (a.shared_pattern() == b.shared_pattern()) {
    SystemMatrix out(a.shared_pattern(), a.block_rows(), a.block_cols(), a.kind());
    by_kind(a.kind(), [&](auto t) {
      using T = decltype(t);
      combine(alpha, a.data<T>(), beta, b.data<T>(), out.data<T>(), out.value_count());
    });
    return out;
  }
  std::shared_ptr<const PatternUnion> u = union_of(a, b, registry);
  // sum_blocks reads one operand block per union block (to_a, to_b); a pattern that repeats a
  // column (a stencil whose offsets wrap to one point) has several, which must all be summed,
  // so such operands are scattered block by block instead.
  if (a.is_float() && a.pattern().canonical() && b.pattern().canonical()) {
    SystemMatrix out(SystemMatrix::Unset{}, u->pattern, a.block_rows(), a.block_cols());
    sum_blocks(a, b, alpha, beta, *u, out.values());
    return out;
  }
  SystemMatrix out(u->pattern, a.block_rows(), a.block_cols(), a.kind());
  by_kind(a.kind(), [&](auto t) {
    scatter_scaled<decltype(t)>(alpha, a, u->from_a, out);
    scatter_scaled<decltype(t)>(beta, b, u->from_b, out);
  });
  return out;
}

namespace {

template <bool F32>
void add_into_values(const SystemMatrix& a, double alpha, SystemMatrix& b, double beta,
                     const ForEachTask& for_each) {
  const int bs = b.block_size();
  double* vb = b.values();
  const double* va = a.values();
  // Tasks of this many rows (or values): far more work than handing a task out.
  constexpr int64_t kRowsPerTask = 1024, kValuesPerTask = 65536;
  auto run = [&for_each](int64_t tasks, const std::function<void(int64_t)>& task) {
    if (for_each && tasks > 1) {
      for_each(tasks, task);
    } else {
      for (int64_t t = 0; t < tasks; ++t) task(t);
    }
  };
  if (a.shared_pattern() == b.shared_pattern()) {  // add()'s combine: no zero to add into
    const int64_t n = static_cast<int64_t>(b.value_count());
    run((n + kValuesPerTask - 1) / kValuesPerTask, [&](int64_t t) {
      const int64_t end = std::min(n, (t + 1) * kValuesPerTask);
      for (int64_t i = t * kValuesPerTask; i < end; ++i)
        vb[i] = sum_component<F32>(alpha * va[i], beta, vb[i]);
    });
    return;
  }
  // add()'s sum over the union, whose blocks are b's (runtime::sum_row), in place.
  const MatrixPattern &pa = a.pattern(), &pb = b.pattern();
  const int64_t rows = pb.rows();
  run((rows + kRowsPerTask - 1) / kRowsPerTask, [&](int64_t t) {
    const int end = static_cast<int>(std::min(rows, (t + 1) * kRowsPerTask));
    for (int r = static_cast<int>(t * kRowsPerTask); r < end; ++r)
      sum_row<F32, 0>(
          pa, va, alpha, pb, vb, beta, bs, false, r,
          [&](int32_t k) { return vb + static_cast<size_t>(k) * bs; },
          [](int32_t, const double*) {});
  });
}

}  // namespace

bool add_into(const SystemMatrix& a, double alpha, SystemMatrix& b, double beta,
              const ForEachTask& for_each, bool float32) {
  if (!fits_into(a, b)) return false;
  if (float32)
    add_into_values<true>(a, alpha, b, beta, for_each);
  else
    add_into_values<false>(a, alpha, b, beta, for_each);
  return true;
}

SystemMatrix multiply_elementwise(const SystemMatrix& a, const SystemMatrix& b,
                                  PatternRegistry* registry) {
  check_block_match(a, b, "multiply element-wise");
  // A component is the product of the operands' components, each the sum of the blocks its
  // pattern holds there: repeated blocks are summed before they are multiplied.
  if (!a.pattern().canonical() || !b.pattern().canonical())
    return multiply_elementwise(a.pattern().canonical() ? a : merged(a, registry),
                                b.pattern().canonical() ? b : merged(b, registry), registry);
  // Both operands on the union pattern (zero where absent), then the component products.
  SystemMatrix x = add(a, b, 1.0, 0.0, registry), y = add(a, b, 0.0, 1.0, registry);
  by_kind(x.kind(), [&](auto t) {
    using T = decltype(t);
    T* v = x.data<T>();
    const T* w = y.data<T>();
    for (size_t i = 0; i < x.value_count(); ++i)
      v[i] = static_cast<T>(static_cast<Acc<T>>(v[i]) * static_cast<Acc<T>>(w[i]));
  });
  return x;
}

SystemMatrix scaled(double s, const SystemMatrix& a) { return scaled(Complex(s), a); }

SystemMatrix scaled(Complex s, const SystemMatrix& a) {
  SystemMatrix out = a;
  by_kind(a.kind(), [&](auto t) { scale_values<decltype(t)>(s, out); });
  return out;
}

void scale(double s, SystemMatrix& a) {
  by_kind(a.kind(), [&](auto t) { scale_values<decltype(t)>(s, a); });
}

SystemMatrix divided(const SystemMatrix& a, double s) { return divided(a, Complex(s)); }

SystemMatrix divided(const SystemMatrix& a, Complex s) {
  SystemMatrix out = a;
  if (a.kind() == ComponentKind::Complex) {
    Complex* v = out.complexes();
    for (size_t i = 0; i < out.value_count(); ++i) v[i] /= s;
    return out;
  }
  const double r = factor<double>(s);
  if (a.is_float()) {
    double* v = out.values();
    for (size_t i = 0; i < out.value_count(); ++i) v[i] /= r;
    return out;
  }
  const int32_t d = int_factor(r);
  if (d == 0) throw Fault("integer division by zero");
  // Truncation does not distribute over a sum: blocks that a stencil pattern repeats are
  // summed first ((1 + 1) / 2 is 1, 1 / 2 + 1 / 2 is 0).
  if (!a.pattern().canonical()) out = merged(a, nullptr);
  int32_t* v = out.ints();
  // INT32_MIN / -1 wraps like the other int operations instead of trapping.
  for (size_t i = 0; i < out.value_count(); ++i)
    v[i] = d == -1 ? static_cast<int32_t>(0u - static_cast<uint32_t>(v[i])) : v[i] / d;
  return out;
}

SystemMatrix transposed(const SystemMatrix& a, PatternRegistry* registry) {
  std::shared_ptr<const PatternTranspose> t =
      registry ? registry->transposed(a.shared_pattern())
               : std::make_shared<const PatternTranspose>(transpose(a.pattern()));
  SystemMatrix out(t->pattern, a.block_cols(), a.block_rows(), a.kind());
  by_kind(a.kind(), [&](auto k) { transpose_blocks<decltype(k)>(a, *t, out); });
  return out;
}

SystemMatrix multiply(const SystemMatrix& a, const SystemMatrix& b, bool float32) {
  if (a.cols() != b.rows() || a.block_cols() != b.block_rows())
    throw Fault("cannot multiply a " + dims(a.scalar_rows(), a.scalar_cols()) + " matrix by a " +
                dims(b.scalar_rows(), b.scalar_cols()) + " matrix (blocks " +
                dims(a.block_rows(), a.block_cols()) + " and " +
                dims(b.block_rows(), b.block_cols()) + ")");
  if (a.kind() != b.kind())
    throw Fault(std::string("cannot multiply a matrix of ") + component_name(a.kind()) +
                " components by one of " + component_name(b.kind()) + " components");
  SystemMatrix out(product_pattern(a.pattern(), b.pattern()), a.block_rows(), b.block_cols(),
                   a.kind());
  with_sums(float32, [&]<class R>(R) {
    by_kind(a.kind(), [&](auto t) { product_values<R, decltype(t)>(a, b, out); });
  });
  return out;
}

// ---------------------------------------------------------------------------
// Blocks of blocks

std::vector<int32_t> nested_positions(const Shape& block) {
  if (!block.uniform()) throw Fault("a matrix block " + block.str() + " has no unblocked form");
  Tensor index(ComponentKind::Int, block);
  int32_t* at = index.mutable_ints();
  for (size_t i = 0; i < index.size(); ++i) at[i] = static_cast<int32_t>(i);
  Tensor flat = unblock(index);
  return std::vector<int32_t>(flat.ints(), flat.ints() + flat.size());
}

void unnest_blocks(SystemMatrix& m, const Shape& block) {
  if (block.levels() < 2) return;
  const std::vector<int32_t> from = nested_positions(block);
  if (from.size() != static_cast<size_t>(m.block_size()))
    throw Fault("a block of shape " + block.str() + " in a matrix of " +
                dims(m.block_rows(), m.block_cols()) + " blocks");
  by_kind(m.kind(), [&](auto t) {
    using T = decltype(t);
    T* v = m.data<T>();
    std::vector<T> tmp(from.size());
    for (size_t k = 0; k < m.value_count(); k += from.size()) {
      for (size_t i = 0; i < from.size(); ++i) tmp[i] = v[k + from[i]];
      std::copy(tmp.begin(), tmp.end(), v + k);
    }
  });
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

double dot(std::span<const double> x, std::span<const double> y, size_t group) {
  check_same(x.size(), y.size());
  if (group == 0 || x.size() % group != 0) throw Fault("dot of vectors not made of whole blocks");
  return blocked_dot(x.data(), y.data(), x.size(), group);
}

double norm(std::span<const double> x, size_t group) { return std::sqrt(dot(x, x, group)); }

}  // namespace simit::runtime
