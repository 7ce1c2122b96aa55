// Assembly through the interpreter on host-built sets (runtime::Set bound with
// Interpreter::bind_set): vectors and matrices from vertex sets and from binary, ternary and
// 4-ary edge sets, heterogeneous endpoints, blocked and unblocked, several results, extra map
// arguments, `apply` with inout, and products with the assembled matrices and their
// transposes (the errors: assembly_errors_test.cpp; the CG loop: conjugate_gradient_test.cpp).
// Every expected value is computed here in C++ from the same element data, never from the
// interpreter's matrices.
#include <Eigen/Dense>
#include <Eigen/SparseCore>
#include <cmath>
#include <cstdio>
#include <set>
#include <utility>

#include "assembly_support.h"

namespace simit::interp {
namespace {

using namespace assembly_support;

// ------------------------------------------------------------------------------------------
// Vertex sets: block-diagonal matrices and per-element vectors.

constexpr const char* kVertexProgram = R"(
element N  m : float; a : vector[2](float); end
extern nodes : set{N};
func diag(n : N) -> (K : matrix[nodes,nodes](float),
                     B : matrix[nodes,nodes](matrix[2,2](float)),
                     f : vector[nodes](vector[2](float)))
  K(n, n) = n.m;
  B(n, n) = n.m * [1.0, 2.0; 3.0, 4.0];
  f(n) = 2.0 * n.a;
  f(n) = n.a;
end
export func main() -> (K : matrix[nodes,nodes](float),
                       B : matrix[nodes,nodes](matrix[2,2](float)),
                       f : vector[nodes](vector[2](float)))
  K, B, f = map diag to nodes reduce +;
end
)";

TEST(Assembly, VertexSetGivesBlockDiagonalMatricesAndVectors) {
  Harness h(kVertexProgram);
  ASSERT_TRUE(h.ok());
  const int n = 5;
  runtime::Set nodes("nodes");
  nodes.add_many(n);
  h.bind("nodes", nodes);
  for (int i = 0; i < n; ++i) {
    field(nodes, "m")[i] = 1.5 + i;
    field(nodes, "a")[2 * i] = 0.25 * i;
    field(nodes, "a")[2 * i + 1] = -1.0 + i;
  }
  auto r = h.run("main");
  ASSERT_EQ(r.size(), 3u);
  MatrixXd K = MatrixXd::Zero(n, n), B = MatrixXd::Zero(2 * n, 2 * n);
  VectorXd f(2 * n);
  Eigen::Matrix2d C;
  C << 1, 2, 3, 4;
  for (int i = 0; i < n; ++i) {
    const double m = 1.5 + i;
    K(i, i) = m;
    B.block(2 * i, 2 * i, 2, 2) = m * C;
    f(2 * i) = 3.0 * 0.25 * i;  // two writes under reduce + add
    f(2 * i + 1) = 3.0 * (-1.0 + i);
  }
  EXPECT_MATRIX_NEAR(dense(r[0]), K, 0.0);
  EXPECT_MATRIX_NEAR(dense(r[1]), B, 0.0);
  EXPECT_MATRIX_NEAR(vec(r[2]), f, 0.0);
  // Block diagonal: one block per element; both matrices share one pattern.
  EXPECT_EQ(r[0].matrix()->pattern().nnz(), n);
  EXPECT_EQ(r[1].matrix()->block_rows(), 2);
  EXPECT_EQ(r[0].matrix()->shared_pattern(), r[1].matrix()->shared_pattern());
  EXPECT_EQ(r[1].matrix()->value_count(), static_cast<size_t>(4 * n));
  // A second run reuses the pattern.
  const int builds = h.interp().patterns().builds();
  auto again = h.run("main");
  EXPECT_EQ(h.interp().patterns().builds(), builds);
  EXPECT_EQ(again[0].matrix()->shared_pattern(), r[0].matrix()->shared_pattern());
}

TEST(Assembly, EmptySetGivesZeroResults) {
  Harness h(kVertexProgram);
  ASSERT_TRUE(h.ok());
  runtime::Set nodes("nodes");
  h.bind("nodes", nodes);
  auto r = h.run("main");
  ASSERT_EQ(r.size(), 3u);
  EXPECT_EQ(r[0].matrix()->rows(), 0);
  EXPECT_EQ(r[0].matrix()->pattern().nnz(), 0);
  EXPECT_EQ(r[2].tensor().size(), 0u);
}

// ------------------------------------------------------------------------------------------
// Binary edges: an unblocked Laplacian, a blocked spring stiffness and a force, one map.

constexpr const char* kSpringProgram = R"(
element N  x : vector[2](float); u : float; end
element S  k : float; end
extern nodes : set{N};
extern springs : set{S}(nodes, nodes);
func spring(s : S, e : (N * 2)) -> (L : matrix[nodes,nodes](float),
                                    K : matrix[nodes,nodes](matrix[2,2](float)),
                                    f : vector[nodes](vector[2](float)))
  L(e(0), e(0)) = s.k;   L(e(0), e(1)) = -s.k;
  L(e(1), e(0)) = -s.k;  L(e(1), e(1)) = s.k;
  d = e(1).x - e(0).x;
  P = s.k * (d * d') / (d' * d);
  K(e(0), e(0)) = P;   K(e(0), e(1)) = -P;
  K(e(1), e(0)) = -P;  K(e(1), e(1)) = P;
  f(e(0)) = s.k * d;
  f(e(1)) = -s.k * d;
end
export func main() -> (L : matrix[nodes,nodes](float),
                       K : matrix[nodes,nodes](matrix[2,2](float)),
                       f : vector[nodes](vector[2](float)),
                       Lu : vector[nodes](float), Kx : vector[nodes](vector[2](float)))
  L, K, f = map spring to springs reduce +;
  Lu = L * nodes.u;
  Kx = K * nodes.x;
end
)";

struct SpringGraph {
  static constexpr int n = 7;
  // A ring, two chords, and a repeated edge (its contributions add).
  std::vector<std::pair<int, int>> edges = {{0, 1}, {1, 2}, {2, 3}, {3, 4}, {4, 5},
                                            {5, 6}, {6, 0}, {0, 3}, {5, 2}, {1, 0}};
  runtime::Set nodes{"nodes"};
  runtime::Set springs{"springs", {&nodes, &nodes}};
  SpringGraph() {
    nodes.add_many(n);
    for (auto [a, b] : edges) springs.add({a, b});
  }
  Eigen::Vector2d x(int i) const { return {std::cos(0.9 * i) + 0.1 * i, std::sin(1.3 * i)}; }
  double u(int i) const { return 0.5 - 0.3 * i + 0.05 * i * i; }
  double k(int e) const { return 1.0 + 0.25 * e; }
  void fill() {
    for (int i = 0; i < n; ++i) {
      field(nodes, "x")[2 * i] = x(i)(0);
      field(nodes, "x")[2 * i + 1] = x(i)(1);
      field(nodes, "u")[i] = u(i);
    }
    for (int e = 0; e < springs.size(); ++e) field(springs, "k")[e] = k(e);
  }
};

TEST(Assembly, BinaryEdgesBlockedAndUnblockedInOneMap) {
  Harness h(kSpringProgram);
  ASSERT_TRUE(h.ok());
  SpringGraph g;
  h.bind("nodes", g.nodes);
  h.bind("springs", g.springs);
  g.fill();
  auto r = h.run("main");
  ASSERT_EQ(r.size(), 5u);

  const int n = g.n;
  MatrixXd L = MatrixXd::Zero(n, n), K = MatrixXd::Zero(2 * n, 2 * n);
  VectorXd f = VectorXd::Zero(2 * n), u(n), x(2 * n);
  Pairs pattern;
  for (int i = 0; i < n; ++i) {
    u(i) = g.u(i);
    x.segment<2>(2 * i) = g.x(i);
  }
  for (size_t e = 0; e < g.edges.size(); ++e) {
    auto [a, b] = g.edges[e];
    const double k = g.k(static_cast<int>(e));
    L(a, a) += k;
    L(a, b) -= k;
    L(b, a) -= k;
    L(b, b) += k;
    Eigen::Vector2d d = g.x(b) - g.x(a);
    Eigen::Matrix2d P = k * d * d.transpose() / d.squaredNorm();
    K.block<2, 2>(2 * a, 2 * a) += P;
    K.block<2, 2>(2 * a, 2 * b) -= P;
    K.block<2, 2>(2 * b, 2 * a) -= P;
    K.block<2, 2>(2 * b, 2 * b) += P;
    f.segment<2>(2 * a) += k * d;
    f.segment<2>(2 * b) -= k * d;
    for (int p : {a, b})
      for (int q : {a, b}) pattern.insert({p, q});
  }
  EXPECT_MATRIX_NEAR(dense(r[0]), L, 1e-14);
  EXPECT_MATRIX_NEAR(dense(r[1]), K, 1e-14);
  EXPECT_MATRIX_NEAR(vec(r[2]), f, 1e-14);
  EXPECT_MATRIX_NEAR(vec(r[3]), L * u, 1e-13);
  EXPECT_MATRIX_NEAR(vec(r[4]), K * x, 1e-13);
  // The pattern is "shares an edge", built once for both matrices.
  EXPECT_EQ(r[0].matrix()->pattern().nnz(), static_cast<int64_t>(pattern.size()));
  EXPECT_EQ(r[0].matrix()->shared_pattern(), r[1].matrix()->shared_pattern());
  for (auto [p, q] : pattern) EXPECT_GE(r[0].matrix()->pattern().find(p, q), 0);
  EXPECT_EQ(r[1].matrix()->value_bytes(), pattern.size() * 4 * sizeof(double));
}

// A non-symmetric matrix, blocked and unblocked, in products with vectors and transposes.
TEST(Assembly, ProductsAndTransposedProductsMatchDenseEigen) {
  Harness h(R"(
element N  x : vector[2](float); u : float; end
element S  k : float; end
extern nodes : set{N};
extern springs : set{S}(nodes, nodes);
func asym(s : S, e : (N * 2)) -> (A : matrix[nodes,nodes](float),
                                  B : matrix[nodes,nodes](matrix[2,2](float)))
  A(e(0), e(0)) = 3.0 * s.k;  A(e(0), e(1)) = s.k;
  A(e(1), e(0)) = -2.0 * s.k + e(1).u;
  B(e(0), e(1)) = s.k * [1.0, 2.0; 0.0, -1.0];
  var M : matrix[2,2](float);
  M(0, 0) = s.k;  M(0, 1) = 0.5;  M(1, 0) = e(0).u;  M(1, 1) = 1.0;
  B(e(1), e(1)) = M;
end
export func main() -> (Au : vector[nodes](float), Atu : vector[nodes](float),
                       uA : vector[nodes](float), Bx : vector[nodes](vector[2](float)),
                       Btx : vector[nodes](vector[2](float)), uAu : float)
  A, B = map asym to springs reduce +;
  Au = A * nodes.u;
  Atu = A' * nodes.u;
  uA = (nodes.u' * A)';
  Bx = B * nodes.x;
  Btx = B' * nodes.x;
  uAu = nodes.u' * (A * nodes.u);
end
)");
  ASSERT_TRUE(h.ok());
  SpringGraph g;
  h.bind("nodes", g.nodes);
  h.bind("springs", g.springs);
  g.fill();
  auto r = h.run("main");
  ASSERT_EQ(r.size(), 6u);
  const int n = g.n;
  MatrixXd A = MatrixXd::Zero(n, n), B = MatrixXd::Zero(2 * n, 2 * n);
  VectorXd u(n), x(2 * n);
  for (int i = 0; i < n; ++i) {
    u(i) = g.u(i);
    x.segment<2>(2 * i) = g.x(i);
  }
  for (size_t e = 0; e < g.edges.size(); ++e) {
    auto [a, b] = g.edges[e];
    const double k = g.k(static_cast<int>(e));
    A(a, a) += 3.0 * k;
    A(a, b) += k;
    A(b, a) += -2.0 * k + g.u(b);
    Eigen::Matrix2d B1, B2;
    B1 << 1.0, 2.0, 0.0, -1.0;
    B2 << k, 0.5, g.u(a), 1.0;
    B.block<2, 2>(2 * a, 2 * b) += k * B1;
    B.block<2, 2>(2 * b, 2 * b) += B2;
  }
  EXPECT_MATRIX_NEAR(vec(r[0]), A * u, 1e-13);
  EXPECT_MATRIX_NEAR(vec(r[1]), A.transpose() * u, 1e-13);
  EXPECT_MATRIX_NEAR(vec(r[2]), A.transpose() * u, 1e-13);
  EXPECT_MATRIX_NEAR(vec(r[3]), B * x, 1e-13);
  EXPECT_MATRIX_NEAR(vec(r[4]), B.transpose() * x, 1e-13);
  ASSERT_EQ(r[5].kind(), Value::Kind::Float);
  EXPECT_NEAR(r[5].as_float(), u.dot(A * u), 1e-12 * std::abs(u.dot(A * u)));
}

// ------------------------------------------------------------------------------------------
// Ternary edges (triangles), unblocked, with a vector result.

TEST(Assembly, TernaryEdges) {
  Harness h(R"(
element V  c : float; end
element T  w : float; end
extern verts : set{V};
extern tris : set{T}(verts, verts, verts);
const W = [1.0, 2.0, 3.0; 4.0, 5.0, 6.0; 7.0, 8.0, 9.5];
func tri(t : T, v : (V * 3)) -> (K : matrix[verts,verts](float), g : vector[verts](float))
  for i in 0:3
    for j in 0:3
      K(v(i), v(j)) = t.w * W(i, j);
    end
    g(v(i)) = t.w * v(mod(i + 1, 3)).c;
  end
end
export func main() -> (K : matrix[verts,verts](float), g : vector[verts](float))
  K, g = map tri to tris reduce +;
end
)");
  ASSERT_TRUE(h.ok());
  const int n = 6;
  const std::vector<std::array<int, 3>> tris = {
      {0, 1, 2}, {2, 1, 3}, {3, 4, 2}, {5, 4, 3}, {0, 2, 5}};
  runtime::Set verts("verts"), t("tris", {&verts, &verts, &verts});
  verts.add_many(n);
  for (auto& c : tris) t.add({c[0], c[1], c[2]});
  h.bind("verts", verts);
  h.bind("tris", t);
  for (int i = 0; i < n; ++i) field(verts, "c")[i] = 0.5 * i - 1.0;
  for (int e = 0; e < t.size(); ++e) field(t, "w")[e] = 1.0 + e;
  auto r = h.run("main");
  ASSERT_EQ(r.size(), 2u);
  Eigen::Matrix3d W;
  W << 1, 2, 3, 4, 5, 6, 7, 8, 9.5;
  MatrixXd K = MatrixXd::Zero(n, n);
  VectorXd g = VectorXd::Zero(n);
  Pairs pattern;
  for (size_t e = 0; e < tris.size(); ++e) {
    const double w = 1.0 + static_cast<double>(e);
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) {
        K(tris[e][i], tris[e][j]) += w * W(i, j);
        pattern.insert({tris[e][i], tris[e][j]});
      }
      g(tris[e][i]) += w * (0.5 * tris[e][(i + 1) % 3] - 1.0);
    }
  }
  EXPECT_MATRIX_NEAR(dense(r[0]), K, 1e-14);
  EXPECT_MATRIX_NEAR(vec(r[1]), g, 1e-14);
  EXPECT_EQ(r[0].matrix()->pattern().nnz(), static_cast<int64_t>(pattern.size()));
}

// ------------------------------------------------------------------------------------------
// 4-ary edges (tetrahedra): 3x3 blocks, and an edge-by-vertex matrix.

TEST(Assembly, QuaternaryEdgesBlockedAndEdgeByVertex) {
  Harness h(R"(
element V  p : vector[3](float); s : float; end
element T  w : float; end
extern verts : set{V};
extern tets : set{T}(verts * 4);
const C = [1.0, 0.0, 0.5; 0.0, 2.0, 0.0; 0.5, 0.0, 3.0];
func tet(t : T, v : (V * 4)) -> (K : matrix[verts,verts](matrix[3,3](float)),
                                 G : matrix[tets,verts](float),
                                 f : vector[verts](vector[3](float)))
  for i in 0:4
    for j in 0:4
      K(v(i), v(j)) = (t.w * dot(v(i).p, v(j).p)) * C;
    end
    G(t, v(i)) = t.w * v(i).s + 1.0;
    f(v(i)) = t.w * (v(mod(i + 1, 4)).p - v(i).p);
  end
end
export func main() -> (K : matrix[verts,verts](matrix[3,3](float)), G : matrix[tets,verts](float),
                       f : vector[verts](vector[3](float)),
                       Gs : vector[tets](float), Gtw : vector[verts](float),
                       Kp : vector[verts](vector[3](float)))
  K, G, f = map tet to tets reduce +;
  Gs = G * verts.s;
  Gtw = G' * tets.w;
  Kp = K * verts.p;
end
)");
  ASSERT_TRUE(h.ok());
  const int n = 7;
  const std::vector<std::array<int, 4>> tets = {
      {0, 1, 2, 3}, {1, 2, 3, 4}, {4, 3, 2, 5}, {6, 5, 0, 1}};
  runtime::Set verts("verts"), t("tets", {&verts, &verts, &verts, &verts});
  verts.add_many(n);
  for (auto& c : tets) t.add({c[0], c[1], c[2], c[3]});
  h.bind("verts", verts);
  h.bind("tets", t);
  auto p = [](int i) { return Eigen::Vector3d(0.1 * i, 1.0 - 0.2 * i, 0.3 * i * i - 1.0); };
  auto s = [](int i) { return 2.0 - 0.7 * i; };
  for (int i = 0; i < n; ++i) {
    for (int k = 0; k < 3; ++k) field(verts, "p")[3 * i + k] = p(i)(k);
    field(verts, "s")[i] = s(i);
  }
  for (int e = 0; e < t.size(); ++e) field(t, "w")[e] = 0.5 + e;
  auto r = h.run("main");
  ASSERT_EQ(r.size(), 6u);
  Eigen::Matrix3d C;
  C << 1, 0, 0.5, 0, 2, 0, 0.5, 0, 3;
  const int m = static_cast<int>(tets.size());
  MatrixXd K = MatrixXd::Zero(3 * n, 3 * n), G = MatrixXd::Zero(m, n);
  VectorXd f = VectorXd::Zero(3 * n), sv(n), w(m), pv(3 * n);
  Pairs pattern;
  for (int i = 0; i < n; ++i) {
    sv(i) = s(i);
    pv.segment<3>(3 * i) = p(i);
  }
  for (int e = 0; e < m; ++e) {
    const double we = 0.5 + e;
    w(e) = we;
    for (int i = 0; i < 4; ++i) {
      const int a = tets[e][i];
      for (int j = 0; j < 4; ++j) {
        const int b = tets[e][j];
        K.block<3, 3>(3 * a, 3 * b) += we * p(a).dot(p(b)) * C;
        pattern.insert({a, b});
      }
      G(e, a) += we * s(a) + 1.0;
      f.segment<3>(3 * a) += we * (p(tets[e][(i + 1) % 4]) - p(a));
    }
  }
  EXPECT_MATRIX_NEAR(dense(r[0]), K, 1e-14);
  EXPECT_MATRIX_NEAR(dense(r[1]), G, 1e-14);
  EXPECT_MATRIX_NEAR(vec(r[2]), f, 1e-14);
  EXPECT_MATRIX_NEAR(vec(r[3]), G * sv, 1e-13);
  EXPECT_MATRIX_NEAR(vec(r[4]), G.transpose() * w, 1e-13);
  EXPECT_MATRIX_NEAR(vec(r[5]), K * pv, 1e-13);
  EXPECT_EQ(r[0].matrix()->pattern().nnz(), static_cast<int64_t>(pattern.size()));
  // Edge by vertex: one block per (tet, corner).
  EXPECT_EQ(r[1].matrix()->pattern().nnz(), 4 * m);
  EXPECT_EQ(r[1].matrix()->rows(), m);
  EXPECT_EQ(r[1].matrix()->cols(), n);
}

// ------------------------------------------------------------------------------------------
// Heterogeneous endpoints: probes join a sensor and a cell.

TEST(Assembly, HeterogeneousEndpointsRectangularBlocks) {
  Harness h(R"(
element Sensor  reading : float; r2 : vector[2](float); end
element Cell    value : float; v3 : vector[3](float); end
element Probe   gain : float; end
extern sensors : set{Sensor};
extern cells   : set{Cell};
extern probes  : set{Probe}(sensors, cells);
func sample(p : Probe, ends : (s : Sensor, c : Cell))
    -> (y : vector[sensors](float), z : vector[cells](vector[3](float)),
        B : matrix[sensors,cells](float), Bb : matrix[sensors,cells](matrix[2,3](float)),
        P : matrix[probes,cells](float))
  y(ends.s) = p.gain * ends.c.value;
  z(ends.c) = p.gain * ends.s.reading * ends.c.v3;
  B(ends.s, ends.c) = p.gain;
  var M : matrix[2,3](float) = p.gain * [1.0, 2.0, 3.0; 4.0, 5.0, 0.0];
  M(1, 2) = p.gain * ends.c.value;
  Bb(ends.s, ends.c) = M;
  P(p, ends.c) = ends.s.reading;
end
export func main() -> (y : vector[sensors](float), z : vector[cells](vector[3](float)),
                       B : matrix[sensors,cells](float), Bb : matrix[sensors,cells](matrix[2,3](float)),
                       P : matrix[probes,cells](float),
                       Bv : vector[sensors](float), Btr : vector[cells](float),
                       Bbv : vector[sensors](vector[2](float)),
                       Bbtr : vector[cells](vector[3](float)), Pv : vector[probes](float))
  y, z, B, Bb, P = map sample to probes reduce +;
  Bv = B * cells.value;
  Btr = B' * sensors.reading;
  Bbv = Bb * cells.v3;
  Bbtr = Bb' * sensors.r2;
  Pv = P * cells.value;
end
)");
  ASSERT_TRUE(h.ok());
  const int ns = 4, nc = 5;
  const std::vector<std::pair<int, int>> probes = {{0, 0}, {0, 3}, {1, 1}, {2, 1}, {3, 4}, {0, 0}};
  runtime::Set sensors("sensors"), cells("cells"), pr("probes", {&sensors, &cells});
  sensors.add_many(ns);
  cells.add_many(nc);
  for (auto [a, b] : probes) pr.add({a, b});
  h.bind("sensors", sensors);
  h.bind("cells", cells);
  h.bind("probes", pr);
  auto reading = [](int i) { return 1.0 + 0.5 * i; };
  auto r2 = [](int i) { return Eigen::Vector2d(i - 1.0, 0.25 * i); };
  auto value = [](int i) { return 2.0 - 0.3 * i; };
  auto v3 = [](int i) { return Eigen::Vector3d(i, 1.0, -0.5 * i); };
  auto gain = [](int e) { return 0.5 + e; };
  for (int i = 0; i < ns; ++i) {
    field(sensors, "reading")[i] = reading(i);
    for (int k = 0; k < 2; ++k) field(sensors, "r2")[2 * i + k] = r2(i)(k);
  }
  for (int i = 0; i < nc; ++i) {
    field(cells, "value")[i] = value(i);
    for (int k = 0; k < 3; ++k) field(cells, "v3")[3 * i + k] = v3(i)(k);
  }
  for (int e = 0; e < pr.size(); ++e) field(pr, "gain")[e] = gain(e);
  auto r = h.run("main");
  ASSERT_EQ(r.size(), 10u);

  const int np = static_cast<int>(probes.size());
  VectorXd y = VectorXd::Zero(ns), z = VectorXd::Zero(3 * nc);
  MatrixXd B = MatrixXd::Zero(ns, nc), Bb = MatrixXd::Zero(2 * ns, 3 * nc),
           P = MatrixXd::Zero(np, nc);
  VectorXd rv(ns), r2v(2 * ns), cv(nc), v3v(3 * nc);
  for (int i = 0; i < ns; ++i) {
    rv(i) = reading(i);
    r2v.segment<2>(2 * i) = r2(i);
  }
  for (int i = 0; i < nc; ++i) {
    cv(i) = value(i);
    v3v.segment<3>(3 * i) = v3(i);
  }
  Pairs pattern;
  for (int e = 0; e < np; ++e) {
    auto [s, c] = probes[e];
    const double g = gain(e);
    y(s) += g * value(c);
    z.segment<3>(3 * c) += g * reading(s) * v3(c);
    B(s, c) += g;
    Eigen::Matrix<double, 2, 3> blk;
    blk << 1, 2, 3, 4, 5, value(c);
    Bb.block<2, 3>(2 * s, 3 * c) += g * blk;
    P(e, c) += reading(s);
    pattern.insert({s, c});
  }
  EXPECT_MATRIX_NEAR(vec(r[0]), y, 1e-14);
  EXPECT_MATRIX_NEAR(vec(r[1]), z, 1e-14);
  EXPECT_MATRIX_NEAR(dense(r[2]), B, 1e-14);
  EXPECT_MATRIX_NEAR(dense(r[3]), Bb, 1e-14);
  EXPECT_MATRIX_NEAR(dense(r[4]), P, 1e-14);
  EXPECT_MATRIX_NEAR(vec(r[5]), B * cv, 1e-13);
  EXPECT_MATRIX_NEAR(vec(r[6]), B.transpose() * rv, 1e-13);
  EXPECT_MATRIX_NEAR(vec(r[7]), Bb * v3v, 1e-13);
  EXPECT_MATRIX_NEAR(vec(r[8]), Bb.transpose() * r2v, 1e-13);
  EXPECT_MATRIX_NEAR(vec(r[9]), P * cv, 1e-13);
  EXPECT_EQ(r[2].matrix()->pattern().nnz(), static_cast<int64_t>(pattern.size()));
  EXPECT_EQ(r[3].matrix()->block_rows(), 2);
  EXPECT_EQ(r[3].matrix()->block_cols(), 3);
  EXPECT_EQ(r[4].matrix()->pattern().nnz(), np);
}

// ------------------------------------------------------------------------------------------
// Extra map arguments (evaluated once), maps without reduce, and apply with inout.

TEST(Assembly, ExtraArgumentsAndStoreWithoutReduce) {
  Harness h(R"(
element N  u : float; end
element S  k : float; end
extern nodes : set{N};
extern springs : set{S}(nodes, nodes);
func scaled(a : float, u : vector[nodes](float), M : matrix[2,2](float), s : S, e : (N * 2))
    -> (r : vector[nodes](float), K : matrix[nodes,nodes](float))
  r(e(0)) = a * u(e(1));
  r(e(1)) = a * s.k * u(e(0));
  K(e(0), e(1)) = M(0, 1) * s.k;
  K(e(1), e(0)) = M(1, 0) * s.k;
end
func last(s : S, e : (N * 2)) -> r : vector[nodes](float)
  r(e(0)) = s.k;
end
export func main(a : float) -> (r : vector[nodes](float), K : matrix[nodes,nodes](float),
                               l : vector[nodes](float))
  r, K = map scaled(2.0 * a, nodes.u, [1.0, 2.0; 3.0, 4.0]) to springs reduce +;
  l = map last to springs;
end
)");
  ASSERT_TRUE(h.ok());
  SpringGraph g;
  h.bind("nodes", g.nodes);
  h.bind("springs", g.springs);
  for (int i = 0; i < g.n; ++i) field(g.nodes, "u")[i] = g.u(i);
  for (int e = 0; e < g.springs.size(); ++e) field(g.springs, "k")[e] = g.k(e);
  auto r = h.run("main", {Value::of_float(1.25)});
  ASSERT_EQ(r.size(), 3u);
  const int n = g.n;
  const double a = 2.5;
  VectorXd rv = VectorXd::Zero(n), l = VectorXd::Zero(n);
  MatrixXd K = MatrixXd::Zero(n, n);
  for (size_t e = 0; e < g.edges.size(); ++e) {
    auto [p, q] = g.edges[e];
    const double k = g.k(static_cast<int>(e));
    rv(p) += a * g.u(q);
    rv(q) += a * k * g.u(p);
    K(p, q) += 2.0 * k;
    K(q, p) += 3.0 * k;
    l(p) = k;  // without reduce the last write wins
  }
  EXPECT_MATRIX_NEAR(vec(r[0]), rv, 1e-14);
  EXPECT_MATRIX_NEAR(dense(r[1]), K, 1e-14);
  EXPECT_MATRIX_NEAR(vec(r[2]), l, 0.0);
}

TEST(Assembly, ApplyWithInoutElementAndEndpoints) {
  Harness h(R"(
element N  x : float; acc : float; end
element S  k : float; seen : float; end
extern nodes : set{N};
extern springs : set{S}(nodes, nodes);
func tag(inout n : N)
  n.x = 2.0 * n.x + 1.0;
end
func push(h : float, inout s : S, inout e : (N * 2))
  e(0).acc = e(0).acc + h * s.k * e(1).x;
  e(1).acc = e(1).acc - h * s.k;
  s.seen = e(0).acc;
  t = e(0).x;
  e(0).x = e(1).x;
  e(1).x = t;
end
export func main()
  apply tag to nodes;
  apply push(0.5) to springs;
end
)");
  ASSERT_TRUE(h.ok());
  SpringGraph g;
  h.bind("nodes", g.nodes);
  h.bind("springs", g.springs);
  for (int i = 0; i < g.n; ++i) field(g.nodes, "x")[i] = g.u(i);
  for (int e = 0; e < g.springs.size(); ++e) field(g.springs, "k")[e] = g.k(e);
  h.run("main");
  // Sequential semantics: each call sees the effects of earlier ones.
  std::vector<double> x(g.n), acc(g.n, 0.0), seen(g.edges.size());
  for (int i = 0; i < g.n; ++i) x[i] = 2.0 * g.u(i) + 1.0;
  for (size_t e = 0; e < g.edges.size(); ++e) {
    auto [p, q] = g.edges[e];
    const double k = g.k(static_cast<int>(e));
    acc[p] += 0.5 * k * x[q];
    acc[q] -= 0.5 * k;
    seen[e] = acc[p];
    std::swap(x[p], x[q]);
  }
  // The accumulations cancel, and the compiler may contract a*b+c differently in the two
  // computations, so agreement is to rounding, not to the last bit.
  for (int i = 0; i < g.n; ++i) {
    EXPECT_DOUBLE_EQ(field(g.nodes, "x")[i], x[i]) << "node " << i;
    EXPECT_NEAR(field(g.nodes, "acc")[i], acc[i], 1e-12) << "node " << i;
  }
  for (size_t e = 0; e < g.edges.size(); ++e)
    EXPECT_NEAR(field(g.springs, "seen")[e], seen[e], 1e-12) << "spring " << e;
}

}  // namespace
}  // namespace simit::interp
