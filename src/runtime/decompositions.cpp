// Small dense decompositions: one-sided Jacobi for the SVD, cyclic Jacobi for symmetric
// eigenproblems, both on a copy scaled by a power of two (exact) so that no square
// overflows or underflows. Plain loops in a fixed order: the same bits on every target.
#include "runtime/decompositions.h"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numeric>
#include <string>
#include <vector>

#include "runtime/dense_linalg.h"
#include "runtime/fault.h"

namespace simit::runtime {

namespace {

// Sweeps are cheap and Jacobi converges quadratically (a handful of sweeps for n <= 12);
// the cap only stops a loop that rounding keeps alive.
constexpr int kMaxSweeps = 100;
// Two vectors count as orthogonal (and an off-diagonal entry as zero) below this cosine.
constexpr double kTolerance = 4 * DBL_EPSILON;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// A row-major n x n matrix of doubles.
struct Square {
  int n = 0;
  std::vector<double> m;
  explicit Square(int size) : n(size), m(static_cast<size_t>(size) * size, 0.0) {}
  double& operator()(int i, int j) { return m[static_cast<size_t>(i) * n + j]; }
  double operator()(int i, int j) const { return m[static_cast<size_t>(i) * n + j]; }
  static Square identity(int n) {
    Square s(n);
    for (int i = 0; i < n; ++i) s(i, i) = 1.0;
    return s;
  }
};

std::string shape_text(const Shape& s) { return s.str(); }

std::string number(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.9g", x);
  return buf;
}

// The n of an unblocked n x n float matrix, or a Fault naming what was expected.
int square_size(const Tensor& a, const char* what) {
  const Shape& s = a.shape();
  if (a.kind() != ComponentKind::Float || s.order() != 2 || s.is_blocked() || s.dim(0) != s.dim(1))
    throw Fault(std::string(what) + " needs a square matrix of float components, not " +
                component_name(a.kind()) + " components of shape " + shape_text(s));
  return s.dim(0);
}

Square square_of(const Tensor& a, int n) {
  Square s(n);
  std::copy(a.floats(), a.floats() + s.m.size(), s.m.begin());
  return s;
}

bool all_finite(const Square& a) {
  for (double x : a.m)
    if (!std::isfinite(x)) return false;
  return true;
}

// The exponent e with max |a_ij| in [2^(e-1), 2^e); 0 for the zero matrix.
int scale_exponent(const Square& a) {
  double m = 0.0;
  for (double x : a.m) m = std::max(m, std::fabs(x));
  int e = 0;
  if (m > 0.0) std::frexp(m, &e);
  return e;
}

void scale(Square& a, int e) {
  for (double& x : a.m) x = std::ldexp(x, e);
}

// tan of the Jacobi angle that zeroes the off-diagonal term: the smaller root of
// t^2 + 2 zeta t - 1 = 0 (so |angle| <= pi/4), without overflow for large zeta.
double jacobi_tangent(double zeta) {
  if (std::fabs(zeta) > 1e150) return 0.5 / zeta;
  return std::copysign(1.0, zeta) / (std::fabs(zeta) + std::sqrt(1.0 + zeta * zeta));
}

double column_dot(const Square& a, int p, int q) {
  double s = 0.0;
  for (int i = 0; i < a.n; ++i) s += a(i, p) * a(i, q);
  return s;
}

// Rotates columns p and q of `a` by (c, s): p' = c p - s q, q' = s p + c q.
void rotate_columns(Square& a, int p, int q, double c, double s) {
  for (int i = 0; i < a.n; ++i) {
    const double x = a(i, p), y = a(i, q);
    a(i, p) = c * x - s * y;
    a(i, q) = s * x + c * y;
  }
}

// One-sided Jacobi: rotates the columns of w (and v with them) until every pair is
// orthogonal to kTolerance, so that w = A v with v orthogonal.
void orthogonalize_columns(Square& w, Square& v) {
  for (int sweep = 0; sweep < kMaxSweeps; ++sweep) {
    bool rotated = false;
    for (int p = 0; p < w.n; ++p)
      for (int q = p + 1; q < w.n; ++q) {
        const double alpha = column_dot(w, p, p), beta = column_dot(w, q, q);
        const double gamma = column_dot(w, p, q);
        if (gamma == 0.0 || std::fabs(gamma) <= kTolerance * std::sqrt(alpha) * std::sqrt(beta))
          continue;
        const double t = jacobi_tangent((beta - alpha) / (2.0 * gamma));
        const double c = 1.0 / std::sqrt(1.0 + t * t), s = c * t;
        rotate_columns(w, p, q, c, s);
        rotate_columns(v, p, q, c, s);
        rotated = true;
      }
    if (!rotated) return;
  }
}

// Reorders the columns of each matrix by `order` (new column k is old column order[k]).
void permute_columns(Square& a, const std::vector<int>& order) {
  Square b(a.n);
  for (int i = 0; i < a.n; ++i)
    for (int k = 0; k < a.n; ++k) b(i, k) = a(i, order[k]);
  a = std::move(b);
}

double determinant_of(const Square& a) {
  if (a.n == 2) return a(0, 0) * a(1, 1) - a(0, 1) * a(1, 0);
  return a(0, 0) * (a(1, 1) * a(2, 2) - a(1, 2) * a(2, 1)) -
         a(0, 1) * (a(1, 0) * a(2, 2) - a(1, 2) * a(2, 0)) +
         a(0, 2) * (a(1, 0) * a(2, 1) - a(1, 1) * a(2, 0));
}

// A unit vector orthogonal to unit u (3 components): the axis least aligned with u,
// made orthogonal to it (the first such axis on ties).
void orthogonal_axis(const double* u, double* out) {
  int k = 0;
  for (int i = 1; i < 3; ++i)
    if (std::fabs(u[i]) < std::fabs(u[k])) k = i;
  double norm2 = 0.0;
  for (int i = 0; i < 3; ++i) {
    out[i] = (i == k ? 1.0 : 0.0) - u[k] * u[i];
    norm2 += out[i] * out[i];
  }
  const double norm = std::sqrt(norm2);
  for (int i = 0; i < 3; ++i) out[i] /= norm;
}

// Column 1 of a 3x3 U: w1 / s1 made exactly orthogonal to u0, or any unit vector
// orthogonal to u0 when column 1 carries no direction (s1 zero).
void second_column(const double* u0, const Square& w, double s1, double* out) {
  if (s1 > 0.0) {
    double x[3], d = 0.0;
    for (int i = 0; i < 3; ++i) x[i] = w(i, 1) / s1;
    for (int i = 0; i < 3; ++i) d += u0[i] * x[i];
    double norm2 = 0.0;
    for (int i = 0; i < 3; ++i) {
      x[i] -= d * u0[i];
      norm2 += x[i] * x[i];
    }
    if (norm2 > 0.25) {
      const double norm = std::sqrt(norm2);
      for (int i = 0; i < 3; ++i) out[i] = x[i] / norm;
      return;
    }
  }
  orthogonal_axis(u0, out);
}

// The left factor of A V = W with the column norms s (descending): u_k = w_k / s_k for the
// leading columns, the last column completing a proper rotation.
Square left_rotation(const Square& w, const std::vector<double>& s) {
  const int n = w.n;
  Square u(n);
  double u0[3] = {1.0, 0.0, 0.0};
  if (s[0] > 0.0)
    for (int i = 0; i < n; ++i) u0[i] = w(i, 0) / s[0];
  if (n == 2) {
    u(0, 0) = u0[0], u(1, 0) = u0[1];
    u(0, 1) = -u0[1], u(1, 1) = u0[0];
    return u;
  }
  double u1[3];
  second_column(u0, w, s[1], u1);
  const double u2[3] = {u0[1] * u1[2] - u0[2] * u1[1], u0[2] * u1[0] - u0[0] * u1[2],
                        u0[0] * u1[1] - u0[1] * u1[0]};
  for (int i = 0; i < 3; ++i) u(i, 0) = u0[i], u(i, 1) = u1[i], u(i, 2) = u2[i];
  return u;
}

Tensor matrix_tensor(const Square& a) {
  Tensor t(ComponentKind::Float, Shape{a.n, a.n});
  std::copy(a.m.begin(), a.m.end(), t.mutable_floats());
  return t;
}

Tensor vector_tensor(const std::vector<double>& v) {
  Tensor t(ComponentKind::Float, Shape{static_cast<int>(v.size())});
  std::copy(v.begin(), v.end(), t.mutable_floats());
  return t;
}

Square filled(int n, double x) {
  Square s(n);
  std::fill(s.m.begin(), s.m.end(), x);
  return s;
}

struct SvdParts {
  Square u, v;
  std::vector<double> s;
};

SvdParts svd_parts(const Square& a_in) {
  const int n = a_in.n;
  if (!all_finite(a_in)) return {filled(n, kNaN), filled(n, kNaN), std::vector<double>(n, kNaN)};
  Square w = a_in, v = Square::identity(n);
  const int e = scale_exponent(w);
  scale(w, -e);
  orthogonalize_columns(w, v);
  std::vector<double> norms(n);
  for (int k = 0; k < n; ++k) norms[k] = std::sqrt(column_dot(w, k, k));
  std::vector<int> order(n);
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int x, int y) { return norms[x] > norms[y]; });
  permute_columns(w, order);
  permute_columns(v, order);
  std::vector<double> s(n);
  for (int k = 0; k < n; ++k) s[k] = norms[order[k]];
  if (determinant_of(v) < 0.0)
    for (int i = 0; i < n; ++i) v(i, n - 1) = -v(i, n - 1), w(i, n - 1) = -w(i, n - 1);
  Square u = left_rotation(w, s);
  // The reflection, if any, goes onto the smallest singular value: its sign is that of
  // w_last projected on u_last (A v_last = s_last u_last).
  double d = 0.0;
  for (int i = 0; i < n; ++i) d += u(i, n - 1) * w(i, n - 1);
  if (d < 0.0) s[n - 1] = -s[n - 1];
  for (double& x : s) x = std::ldexp(x, e);
  return {std::move(u), std::move(v), std::move(s)};
}

int svd_size(const Tensor& a, const char* what) {
  const int n = square_size(a, what);
  if (n != 2 && n != 3)
    throw Fault(std::string(what) + " needs a 2x2 or 3x3 matrix, not " + shape_text(a.shape()));
  return n;
}

// The symmetric part of `a` (bit-exact where a_ij == a_ji), after checking that the two
// triangles agree within `tolerance` relative to the largest component.
Square symmetric_part(const Square& a, double tolerance, const char* what) {
  double m = 0.0;
  for (double x : a.m) m = std::max(m, std::fabs(x));
  Square s(a.n);
  for (int i = 0; i < a.n; ++i)
    for (int j = 0; j < a.n; ++j) {
      const double x = a(i, j), y = a(j, i);
      if (std::fabs(x - y) > tolerance * m)
        throw Fault(std::string(what) + " needs a symmetric matrix: component (" +
                    std::to_string(std::min(i, j)) + ", " + std::to_string(std::max(i, j)) +
                    ") is " + number(i < j ? x : y) + " but component (" +
                    std::to_string(std::max(i, j)) + ", " + std::to_string(std::min(i, j)) +
                    ") is " + number(i < j ? y : x));
      s(i, j) = x == y ? x : 0.5 * x + 0.5 * y;
    }
  return s;
}

// Applies the Jacobi rotation (c, s, tau = s / (1 + c)) that zeroes a(p, q) to the rest of
// rows and columns p and q, keeping `a` symmetric.
void rotate_symmetric(Square& a, int p, int q, double t, double s, double tau) {
  const double apq = a(p, q);
  a(p, p) -= t * apq;
  a(q, q) += t * apq;
  a(p, q) = a(q, p) = 0.0;
  for (int r = 0; r < a.n; ++r) {
    if (r == p || r == q) continue;
    const double arp = a(r, p), arq = a(r, q);
    a(r, p) = a(p, r) = arp - s * (arq + tau * arp);
    a(r, q) = a(q, r) = arq + s * (arp - tau * arq);
  }
}

void rotate_vectors(Square& v, int p, int q, double s, double tau) {
  for (int r = 0; r < v.n; ++r) {
    const double vp = v(r, p), vq = v(r, q);
    v(r, p) = vp - s * (vq + tau * vp);
    v(r, q) = vq + s * (vp - tau * vq);
  }
}

bool negligible(double apq, double app, double aqq) {
  const double scale = std::max(std::sqrt(std::fabs(app)) * std::sqrt(std::fabs(aqq)), 1e-290);
  return std::fabs(apq) <= kTolerance * scale;
}

// Cyclic Jacobi on a symmetric matrix: a becomes diagonal, v collects the rotations.
void diagonalize(Square& a, Square& v) {
  for (int sweep = 0; sweep < kMaxSweeps; ++sweep) {
    bool rotated = false;
    for (int p = 0; p < a.n; ++p)
      for (int q = p + 1; q < a.n; ++q) {
        const double apq = a(p, q);
        if (apq == 0.0 || negligible(apq, a(p, p), a(q, q))) continue;
        const double t = jacobi_tangent((a(q, q) - a(p, p)) / (2.0 * apq));
        const double c = 1.0 / std::sqrt(t * t + 1.0), s = t * c, tau = s / (1.0 + c);
        rotate_symmetric(a, p, q, t, s, tau);
        rotate_vectors(v, p, q, s, tau);
        rotated = true;
      }
    if (!rotated) return;
  }
  throw Fault("the Jacobi eigenvalue iteration did not converge");
}

struct EigParts {
  std::vector<double> w;
  Square q;
};

// Eigenvalues ascending and eigenvectors (largest-magnitude component positive) of a
// symmetric matrix.
EigParts eig_parts(const Square& sym) {
  const int n = sym.n;
  if (!all_finite(sym)) return {std::vector<double>(n, kNaN), filled(n, kNaN)};
  Square a = sym, v = Square::identity(n);
  const int e = scale_exponent(a);
  scale(a, -e);
  diagonalize(a, v);
  std::vector<int> order(n);
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int x, int y) { return a(x, x) < a(y, y); });
  permute_columns(v, order);
  std::vector<double> w(n);
  for (int k = 0; k < n; ++k) w[k] = std::ldexp(a(order[k], order[k]), e);
  for (int k = 0; k < n; ++k) {
    int big = 0;
    for (int i = 1; i < n; ++i)
      if (std::fabs(v(i, k)) > std::fabs(v(big, k))) big = i;
    if (v(big, k) < 0.0)
      for (int i = 0; i < n; ++i) v(i, k) = -v(i, k);
  }
  return {std::move(w), std::move(v)};
}

// sum over k of d_k (x_ik x_jk), k ascending: symmetric to the bit.
Square weighted_gram(const Square& x, const std::vector<double>& d) {
  Square r(x.n);
  for (int i = 0; i < x.n; ++i)
    for (int j = 0; j < x.n; ++j) {
      double sum = 0.0;
      for (int k = 0; k < x.n; ++k) sum += d[k] * (x(i, k) * x(j, k));
      r(i, j) = sum;
    }
  return r;
}

}  // namespace

RotationSvd rotation_svd(const Tensor& a) {
  const int n = svd_size(a, "svd");
  SvdParts p = svd_parts(square_of(a, n));
  return {matrix_tensor(p.u), vector_tensor(p.s), matrix_tensor(p.v)};
}

SymmetricEig symmetric_eig(const Tensor& a, double symmetry_tolerance) {
  const int n = square_size(a, "eig");
  EigParts p = eig_parts(symmetric_part(square_of(a, n), symmetry_tolerance, "eig"));
  return {vector_tensor(p.w), matrix_tensor(p.q)};
}

PolarDecomposition polar_decomposition(const Tensor& f) {
  const int n = svd_size(f, "polar");
  SvdParts p = svd_parts(square_of(f, n));
  Square r(n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      double sum = 0.0;
      for (int k = 0; k < n; ++k) sum += p.u(i, k) * p.v(j, k);
      r(i, j) = sum;
    }
  return {matrix_tensor(r), matrix_tensor(weighted_gram(p.v, p.s))};
}

Tensor project_spd(const Tensor& a, SpdProjection mode, double symmetry_tolerance) {
  const char* what = mode == SpdProjection::Clamp ? "project_spd" : "project_spd_abs";
  const Shape& shape = a.shape();
  if (shape.order() != 2 || !shape.uniform())
    throw Fault(std::string(what) + " needs a square matrix, not " + shape_text(shape));
  const Tensor logical = unblock(a);
  const int n = square_size(logical, what);
  const Square sym = symmetric_part(square_of(logical, n), symmetry_tolerance, what);
  EigParts p = eig_parts(sym);
  Square result = sym;
  // Eigenvalues this close to zero are rounding noise, not evidence of indefiniteness: a
  // singular positive semi-definite matrix comes back unchanged too.
  double largest = 0.0;
  for (double x : p.w) largest = std::max(largest, std::fabs(x));
  const double noise = 4.0 * n * DBL_EPSILON * largest;
  if (!(p.w[0] >= -noise)) {  // NaN eigenvalues fall through to a NaN result
    for (double& x : p.w) x = mode == SpdProjection::Clamp ? std::max(x, 0.0) : std::fabs(x);
    result = weighted_gram(p.q, p.w);
  }
  return shape.is_blocked() ? reblock(matrix_tensor(result), shape) : matrix_tensor(result);
}

}  // namespace simit::runtime
