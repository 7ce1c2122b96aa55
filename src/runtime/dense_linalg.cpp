// Small dense linear algebra on runtime tensors, as plain loops in the order that
// docs/arithmetic.md states (no Eigen here: its kernels' order depends on the vector ISA).
#include "runtime/dense_linalg.h"

#include <array>
#include <cmath>
#include <limits>
#include <vector>

#include "runtime/blocked_sum.h"
#include "runtime/fault.h"
#include "runtime/sum_rounding.h"

namespace simit::runtime {

namespace {

// Calls f(blocked offset, logical offset) for every component of a uniform blocked shape.
template <class F>
void for_each_component(const Shape& s, F f) {
  const Shape logical = s.logical();
  const int order = s.order(), rank = s.rank();
  std::array<size_t, Shape::kMaxRank> lstride{};
  size_t stride = 1;
  for (int k = order - 1; k >= 0; --k) {
    lstride[k] = stride;
    stride *= static_cast<size_t>(logical.dim(k));
  }
  // Position p (level p / order, dimension p % order) moves the logical index of its
  // dimension by the product of the same dimension's sizes in deeper levels.
  std::array<size_t, Shape::kMaxRank> contrib{};
  for (int p = 0; p < rank; ++p) {
    size_t scale = 1;
    for (int q = p + order; q < rank; q += order) scale *= static_cast<size_t>(s.dim(q));
    contrib[p] = scale * lstride[p % order];
  }
  std::array<int, Shape::kMaxRank> idx{};
  const size_t n = s.size();
  size_t loff = 0;
  for (size_t off = 0; off < n; ++off) {
    f(off, loff);
    for (int p = rank - 1; p >= 0; --p) {
      loff += contrib[p];
      if (++idx[p] < s.dim(p)) break;
      loff -= contrib[p] * static_cast<size_t>(idx[p]);
      idx[p] = 0;
    }
  }
}

template <class T>
void permute(const T* src, T* dst, const Shape& blocked, bool to_logical) {
  for_each_component(blocked, [&](size_t off, size_t loff) {
    if (to_logical)
      dst[loff] = src[off];
    else
      dst[off] = src[loff];
  });
}

void permute_tensor(const Tensor& src, Tensor& dst, const Shape& blocked, bool to_logical) {
  switch (src.kind()) {
    case ComponentKind::Int: return permute(src.ints(), dst.mutable_ints(), blocked, to_logical);
    case ComponentKind::Float:
      return permute(src.floats(), dst.mutable_floats(), blocked, to_logical);
    case ComponentKind::Bool: return permute(src.bools(), dst.mutable_bools(), blocked, to_logical);
    case ComponentKind::Complex:
      return permute(src.complexes(), dst.mutable_complexes(), blocked, to_logical);
    case ComponentKind::String:
      return permute(src.strings(), dst.mutable_strings(), blocked, to_logical);
  }
}

void require(bool ok, const char* what) {
  if (!ok) throw Fault(what);
}

int32_t wrap(uint32_t v) { return static_cast<int32_t>(v); }

// C = A (m x k) * B (k x n), all row-major: each entry sums from zero over l in order, each
// product and addition rounded by R.
template <class R, class T>
void gemm_loops(const T* a, const T* b, T* c, int m, int k, int n) {
  for (int i = 0; i < m; ++i)
    for (int j = 0; j < n; ++j) {
      T s{};
      for (int l = 0; l < k; ++l) s = R::r(s + R::r(a[i * k + l] * b[l * n + j]));
      c[i * n + j] = s;
    }
}

void gemm(const Tensor& a, const Tensor& b, Tensor& c, int m, int k, int n, bool float32) {
  switch (a.kind()) {
    case ComponentKind::Float:
      return with_sums(float32, [&]<class R>(R) {
        gemm_loops<R>(a.floats(), b.floats(), c.mutable_floats(), m, k, n);
      });
    case ComponentKind::Complex:
      return with_sums(float32, [&]<class R>(R) {
        gemm_loops<R>(a.complexes(), b.complexes(), c.mutable_complexes(), m, k, n);
      });
    case ComponentKind::Int: {
      // Integer arithmetic wraps (LANGUAGE.md §5.1); unsigned arithmetic makes that defined.
      int32_t* out = c.mutable_ints();
      for (int i = 0; i < m; ++i)
        for (int j = 0; j < n; ++j) {
          uint32_t s = 0;
          for (int l = 0; l < k; ++l)
            s += static_cast<uint32_t>(a.ints()[i * k + l]) *
                 static_cast<uint32_t>(b.ints()[l * n + j]);
          out[i * n + j] = wrap(s);
        }
      return;
    }
    default: throw Fault("product of non-numeric tensors");
  }
}

void check_product(const Tensor& a, const Tensor& b) {
  require(a.kind() == b.kind(), "product of tensors of different component kinds");
  require(!a.shape().is_blocked() && !b.shape().is_blocked(), "product of blocked tensors");
}

// The determinant of the n x n matrix a (row stride `stride`) restricted to the given rows
// and columns, by cofactor expansion along its first row: the terms a(r0, c_j) * C(r0, c_j)
// summed from zero in column order, each cofactor the signed determinant of its minor.
double minor_determinant(const double* a, int stride, const int* rows, const int* cols, int n) {
  if (n == 1) return a[rows[0] * stride + cols[0]];
  std::array<int, 3> sub{};
  double sum = 0.0;
  for (int j = 0; j < n; ++j) {
    for (int c = 0, t = 0; c < n; ++c)
      if (c != j) sub[t++] = cols[c];
    const double minor = minor_determinant(a, stride, rows + 1, sub.data(), n - 1);
    sum += a[rows[0] * stride + cols[j]] * (j % 2 == 0 ? minor : -minor);
  }
  return sum;
}

// The cofactor C(i, j) of the n x n row-major matrix a.
double cofactor(const double* a, int n, int i, int j) {
  std::array<int, 3> rows{}, cols{};
  for (int r = 0, t = 0; r < n; ++r)
    if (r != i) rows[t++] = r;
  for (int c = 0, t = 0; c < n; ++c)
    if (c != j) cols[t++] = c;
  const double minor = minor_determinant(a, n, rows.data(), cols.data(), n - 1);
  return (i + j) % 2 == 0 ? minor : -minor;
}

double determinant_of(const double* a, int n) {
  const std::array<int, 4> all{0, 1, 2, 3};
  return minor_determinant(a, n, all.data(), all.data(), n);
}

// inv(A)(j, i) = C(i, j) / det(A), det(A) computed as determinant() does.
Tensor inverse_of(const Tensor& m, int n) {
  const double* a = m.floats();
  const double det = determinant_of(a, n);
  if (det == 0.0) throw Fault("inverse of a singular matrix (determinant is 0)");
  Tensor out(ComponentKind::Float, m.shape());
  double* o = out.mutable_floats();
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) o[j * n + i] = cofactor(a, n, i, j) / det;
  return out;
}

int square_size(const Tensor& m) {
  const Shape& s = m.shape();
  require(s.levels() == 1 && s.order() == 2 && s.dim(0) == s.dim(1), "expected a square matrix");
  return s.dim(0);
}

double magnitude(double x) { return std::fabs(x); }
double magnitude(const Complex& x) { return std::abs(x); }

// Gaussian elimination with partial pivoting (the first row of largest magnitude), then back
// substitution; a pivot at or below n * epsilon * max |a_ij| means the matrix is singular.
template <class T>
Tensor solve_typed(const Tensor& a, const Tensor& b, const T* ad, const T* bd,
                   T* (Tensor::*out)()) {
  const int n = square_size(a);
  require(b.size() == static_cast<size_t>(n), "solve: vector length does not match the matrix");
  std::vector<T> m(ad, ad + static_cast<size_t>(n) * n), r(bd, bd + n);
  double largest = 0.0;
  for (const T& v : m) largest = std::fmax(largest, magnitude(v));
  const double tiny = n * std::numeric_limits<double>::epsilon() * largest;
  for (int k = 0; k < n; ++k) {
    int p = k;
    for (int i = k + 1; i < n; ++i)
      if (magnitude(m[i * n + k]) > magnitude(m[p * n + k])) p = i;
    if (!(magnitude(m[p * n + k]) > tiny)) throw Fault("solve with a singular matrix");
    if (p != k) {
      for (int j = 0; j < n; ++j) std::swap(m[k * n + j], m[p * n + j]);
      std::swap(r[k], r[p]);
    }
    for (int i = k + 1; i < n; ++i) {
      const T f = m[i * n + k] / m[k * n + k];
      for (int j = k + 1; j < n; ++j) m[i * n + j] -= f * m[k * n + j];
      r[i] -= f * r[k];
    }
  }
  Tensor x(a.kind(), Shape{n});
  T* xs = (x.*out)();
  for (int i = n - 1; i >= 0; --i) {
    T s = r[i];
    for (int j = i + 1; j < n; ++j) s -= m[i * n + j] * xs[j];
    xs[i] = s / m[i * n + i];
  }
  return x;
}

}  // namespace

Tensor unblock(const Tensor& t) {
  if (!t.shape().is_blocked()) return t;
  Tensor out(t.kind(), t.shape().logical());
  permute_tensor(t, out, t.shape(), true);
  return out;
}

Tensor reblock(const Tensor& logical, const Shape& blocked) {
  if (!blocked.is_blocked()) {
    Tensor out = logical;
    out.reshape(blocked);
    return out;
  }
  require(logical.size() == blocked.size(), "reblock: sizes differ");
  Tensor out(logical.kind(), blocked);
  permute_tensor(logical, out, blocked, false);
  return out;
}

Tensor matrix_product(const Tensor& a, const Tensor& b, bool float32) {
  check_product(a, b);
  const Shape &sa = a.shape(), &sb = b.shape();
  require(sa.order() == 2 && sb.order() == 2 && sa.dim(1) == sb.dim(0),
          "matrix product: dimensions do not match");
  Tensor c(a.kind(), Shape{sa.dim(0), sb.dim(1)});
  gemm(a, b, c, sa.dim(0), sa.dim(1), sb.dim(1), float32);
  return c;
}

Tensor matrix_vector_product(const Tensor& a, const Tensor& x, bool float32) {
  check_product(a, x);
  const Shape& sa = a.shape();
  require(sa.order() == 2 && x.shape().order() == 1 && sa.dim(1) == x.shape().dim(0),
          "matrix-vector product: dimensions do not match");
  Tensor c(a.kind(), Shape{sa.dim(0)});
  gemm(a, x, c, sa.dim(0), sa.dim(1), 1, float32);
  return c;
}

Tensor vector_matrix_product(const Tensor& x, const Tensor& a, bool float32) {
  check_product(x, a);
  const Shape& sa = a.shape();
  require(sa.order() == 2 && x.shape().order() == 1 && sa.dim(0) == x.shape().dim(0),
          "vector-matrix product: dimensions do not match");
  Tensor c(a.kind(), Shape{sa.dim(1)});
  gemm(x, a, c, 1, sa.dim(0), sa.dim(1), float32);
  return c;
}

Tensor outer_product(const Tensor& u, const Tensor& v) {
  check_product(u, v);
  int m = static_cast<int>(u.size()), n = static_cast<int>(v.size());
  Tensor c(u.kind(), Shape{m, n});
  gemm(u, v, c, m, 1, n, false);  // one product per component, rounded by the caller
  return c;
}

size_t inner_product_group(const Shape& s) {
  if (!s.is_blocked() || s.size() == 0) return 1;
  return s.block().size();
}

namespace {

template <class R, class T>
T grouped_sum_of_products(const T* x, const T* y, size_t n, size_t group) {
  T sum{};
  if (group <= 1) {
    for (size_t k = 0; k < n; ++k) sum = R::r(sum + R::r(x[k] * y[k]));
    return sum;
  }
  for (size_t k = 0; k < n; k += group) {
    T part{};
    for (size_t c = 0; c < group; ++c) part = R::r(part + R::r(x[k + c] * y[k + c]));
    sum = R::r(sum + part);
  }
  return sum;
}

}  // namespace

double grouped_dot(const double* x, const double* y, size_t n, size_t group, bool float32) {
  return with_sums(float32, [&]<class R>(R) { return grouped_sum_of_products<R>(x, y, n, group); });
}

Tensor inner_product(const Tensor& u, const Tensor& v, bool float32) {
  require(u.kind() == v.kind() && u.size() == v.size(), "inner product: sizes do not match");
  const size_t group = inner_product_group(u.shape());
  Tensor c(u.kind(), Shape{1});
  switch (u.kind()) {
    case ComponentKind::Float:
      c.mutable_floats()[0] = grouped_dot(u.floats(), v.floats(), u.size(), group, float32);
      return c;
    case ComponentKind::Complex:
      c.mutable_complexes()[0] = with_sums(float32, [&]<class R>(R) {
        return grouped_sum_of_products<R>(u.complexes(), v.complexes(), u.size(), group);
      });
      return c;
    default: {
      // Integer sums wrap, so their order does not matter.
      int n = static_cast<int>(u.size());
      gemm(u, v, c, 1, n, 1, false);
      return c;
    }
  }
}

Tensor set_inner_product(const Tensor& u, const Tensor& v) {
  require(u.kind() == v.kind() && u.size() == v.size(), "inner product: sizes do not match");
  const size_t group = inner_product_group(u.shape());
  Tensor c(u.kind(), Shape{1});
  switch (u.kind()) {
    case ComponentKind::Float:
      c.mutable_floats()[0] = blocked_dot(u.floats(), v.floats(), u.size(), group);
      return c;
    case ComponentKind::Complex:
      c.mutable_complexes()[0] = blocked_dot(u.complexes(), v.complexes(), u.size(), group);
      return c;
    default: return inner_product(u, v, false);  // integer sums wrap: any order gives the same
  }
}

Tensor transpose(const Tensor& m) {
  const Shape& s = m.shape();
  require(s.order() == 2 && s.uniform(), "transpose of a tensor that is not a matrix");
  Tensor logical = unblock(m);
  int r = logical.shape().dim(0), c = logical.shape().dim(1);
  Tensor t(m.kind(), Shape{c, r});
  for (int i = 0; i < r; ++i)
    for (int j = 0; j < c; ++j) {
      size_t from = static_cast<size_t>(i) * c + j, to = static_cast<size_t>(j) * r + i;
      switch (m.kind()) {
        case ComponentKind::Int: t.mutable_ints()[to] = logical.ints()[from]; break;
        case ComponentKind::Float: t.mutable_floats()[to] = logical.floats()[from]; break;
        case ComponentKind::Bool: t.mutable_bools()[to] = logical.bools()[from]; break;
        case ComponentKind::Complex: t.mutable_complexes()[to] = logical.complexes()[from]; break;
        case ComponentKind::String: t.mutable_strings()[to] = logical.strings()[from]; break;
      }
    }
  if (!s.is_blocked()) return t;
  // Each level's two dimensions swap places.
  Shape swapped;
  std::vector<Shape> levels;
  for (Shape cur = s; !cur.is_scalar(); cur = cur.block()) levels.push_back(cur);
  for (auto it = levels.rbegin(); it != levels.rend(); ++it)
    swapped = Shape::blocked({it->dim(1), it->dim(0)}, swapped);
  return reblock(t, swapped);
}

double determinant(const Tensor& m) {
  require(m.kind() == ComponentKind::Float, "determinant of a non-float matrix");
  const int n = square_size(m);
  if (n < 2 || n > 4) throw Fault("determinant of a matrix that is not 2x2, 3x3 or 4x4");
  return determinant_of(m.floats(), n);
}

Tensor inverse(const Tensor& m) {
  require(m.kind() == ComponentKind::Float, "inverse of a non-float matrix");
  const int n = square_size(m);
  if (n < 2 || n > 4) throw Fault("inverse of a matrix that is not 2x2, 3x3 or 4x4");
  return inverse_of(m, n);
}

Tensor solve(const Tensor& a, const Tensor& b) {
  require(a.kind() == b.kind(), "solve with operands of different component kinds");
  if (a.kind() == ComponentKind::Float)
    return solve_typed<double>(a, b, a.floats(), b.floats(), &Tensor::mutable_floats);
  if (a.kind() == ComponentKind::Complex)
    return solve_typed<Complex>(a, b, a.complexes(), b.complexes(), &Tensor::mutable_complexes);
  throw Fault(std::string("solve with ") + component_name(a.kind()) +
              " components is not supported (use float)");
}

Tensor lower_triangular_solve(const Tensor& a, const Tensor& b) {
  require(a.kind() == ComponentKind::Float && b.kind() == ComponentKind::Float,
          "triangular solve of non-float tensors");
  int n = square_size(a);
  require(b.size() == static_cast<size_t>(n), "triangular solve: vector length does not match");
  Tensor x(ComponentKind::Float, Shape{n});
  const double* l = a.floats();
  double* xs = x.mutable_floats();
  for (int i = 0; i < n; ++i) {
    double s = b.floats()[i];
    for (int j = 0; j < i; ++j) s -= l[i * n + j] * xs[j];
    if (l[i * n + i] == 0.0) throw Fault("triangular solve with a zero on the diagonal");
    xs[i] = s / l[i * n + i];
  }
  return x;
}

void round_to_float32(Tensor& t) {
  // The size read once: the stores could alias the shape as far as the compiler knows, and
  // recomputing it per component kept the loop from vectorising (8.6% of a float32 cloth).
  const size_t n = t.size();
  if (t.kind() == ComponentKind::Float) {
    double* d = t.mutable_floats();
    for (size_t i = 0; i < n; ++i) d[i] = static_cast<float>(d[i]);
  } else if (t.kind() == ComponentKind::Complex) {
    Complex* c = t.mutable_complexes();
    for (size_t i = 0; i < n; ++i)
      c[i] = Complex(static_cast<float>(c[i].real()), static_cast<float>(c[i].imag()));
  }
}

bool all_finite(const Tensor& t) {
  if (t.kind() == ComponentKind::Float) {
    for (size_t i = 0; i < t.size(); ++i)
      if (!std::isfinite(t.floats()[i])) return false;
  } else if (t.kind() == ComponentKind::Complex) {
    for (size_t i = 0; i < t.size(); ++i)
      if (!std::isfinite(t.complexes()[i].real()) || !std::isfinite(t.complexes()[i].imag()))
        return false;
  }
  return true;
}

}  // namespace simit::runtime
