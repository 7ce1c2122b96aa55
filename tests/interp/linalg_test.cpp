// System matrices of int components and of blocks of blocks through the interpreter, on
// host-built sets: products, transposed products, sums, scaling and sparse products, each
// checked against a dense matrix assembled here in C++ from the same element data.
#include <Eigen/Dense>
#include <cmath>
#include <cstring>
#include <utility>

#include "interp/set_binding.h"
#include "runtime/set.h"
#include "test_util.h"

namespace simit::interp {
namespace {

namespace ast = frontend::ast;
using Eigen::MatrixXd;
using Eigen::VectorXd;

// A compiled program, its interpreter, and binding of host sets by extern name.
class Harness {
 public:
  explicit Harness(const std::string& text) : c_(testing::compile(text, "linalg.sim")) {
    if (c_->ok()) in_ = std::make_unique<Interpreter>(*c_->program);
  }
  bool ok() const { return in_ != nullptr; }
  // Adds every field of the extern's element type (zero) and binds the set.
  void bind(const std::string& name, runtime::Set& s) {
    for (const ast::Variable* v : c_->program->globals) {
      if (!v || v->name != name || v->kind != ast::Variable::Kind::Extern) continue;
      for (const ast::FieldDecl& f : v->type->element->fields)
        if (s.field_index(f.name) < 0) s.add_field(f.name, field_type_of(*f.type));
      in_->bind_set(*v, s);
      return;
    }
    FAIL() << "no extern " << name;
  }
  std::vector<Value> run(const std::string& f) { return in_->call(testing::func(*c_, f), {}); }

 private:
  std::unique_ptr<frontend::Compilation> c_;
  std::unique_ptr<Interpreter> in_;
};

// A ring with a chord and a repeated edge (whose contributions add).
struct Graph {
  static constexpr int n = 6;
  std::vector<std::pair<int, int>> edges = {{0, 1}, {1, 2}, {2, 3}, {3, 4},
                                            {4, 5}, {5, 0}, {0, 3}, {1, 2}};
  runtime::Set nodes{"nodes"};
  runtime::Set springs{"springs", {&nodes, &nodes}};
  Graph() {
    nodes.add_many(n);
    for (auto [a, b] : edges) springs.add({a, b});
  }
  static int x(int i) { return 3 - 2 * i; }
  static int k(int e) { return 1 + e % 4; }
  static double u(int i) { return 0.5 - 0.3 * i + 0.05 * i * i; }
};

// A result vector's components as doubles (int results are small, so exact).
VectorXd vec(const Value& v) {
  EXPECT_TRUE(v.is_tensor());
  const Tensor& t = v.tensor();
  VectorXd out(static_cast<Eigen::Index>(t.size()));
  for (size_t i = 0; i < t.size(); ++i)
    out[static_cast<Eigen::Index>(i)] =
        t.kind() == ComponentKind::Int ? t.ints()[i] : t.floats()[i];
  return out;
}

TEST(IntSystemMatrices, ProductsSumsAndScalingMatchDenseReferences) {
  Harness h(R"(
element N  x : int; end
element S  k : int; end
extern nodes : set{N};
extern springs : set{S}(nodes, nodes);
func asym(s : S, e : (N * 2)) -> (A : matrix[nodes,nodes](int),
                                  B : matrix[nodes,nodes](matrix[2,2](int)))
  A(e(0), e(1)) = s.k;
  A(e(1), e(1)) = 2 * s.k - e(0).x;
  var M : matrix[2,2](int);
  M(0, 0) = s.k;  M(0, 1) = e(1).x;  M(1, 0) = -1;  M(1, 1) = 3;
  B(e(0), e(1)) = M;
  B(e(0), e(0)) = s.k * [1, 2; 0, -1];
end
export func main() -> (Ax : vector[nodes](int), Atx : vector[nodes](int),
                       AAx : vector[nodes](int), Sx : vector[nodes](int),
                       Bv : vector[nodes](vector[2](int)), Btv : vector[nodes](vector[2](int)),
                       xAx : int)
  A, B = map asym to springs reduce +;
  var v : vector[nodes](vector[2](int));
  for p in nodes
    v(p)(0) = p.x;
    v(p)(1) = 1 - p.x;
  end
  Ax = A * nodes.x;
  Atx = A' * nodes.x;
  AAx = (A * A') * nodes.x;
  Sx = (3 * A - A' / 2 + -A) * nodes.x;
  Bv = B * v;
  Btv = B' * v;
  xAx = nodes.x' * (A * nodes.x);
end
)");
  ASSERT_TRUE(h.ok());
  Graph g;
  h.bind("nodes", g.nodes);
  h.bind("springs", g.springs);
  for (int i = 0; i < g.n; ++i) g.nodes.field("x").data<int32_t>()[i] = Graph::x(i);
  for (int e = 0; e < g.springs.size(); ++e) g.springs.field("k").data<int32_t>()[e] = Graph::k(e);
  auto r = h.run("main");
  ASSERT_EQ(r.size(), 7u);
  const int n = g.n;
  MatrixXd A = MatrixXd::Zero(n, n), B = MatrixXd::Zero(2 * n, 2 * n);
  VectorXd x(n), v(2 * n);
  for (int i = 0; i < n; ++i) {
    x(i) = Graph::x(i);
    v(2 * i) = Graph::x(i);
    v(2 * i + 1) = 1 - Graph::x(i);
  }
  for (size_t e = 0; e < g.edges.size(); ++e) {
    auto [a, b] = g.edges[e];
    const int k = Graph::k(static_cast<int>(e));
    A(a, b) += k;
    A(b, b) += 2 * k - Graph::x(a);
    Eigen::Matrix2d M, D;
    M << k, Graph::x(b), -1, 3;
    D << k, 2 * k, 0, -k;
    B.block<2, 2>(2 * a, 2 * b) += M;
    B.block<2, 2>(2 * a, 2 * a) += D;
  }
  // A' / 2 truncates component by component.
  const MatrixXd half = A.transpose().unaryExpr([](double c) { return std::trunc(c / 2); });
  EXPECT_EQ(r[0].tensor().kind(), ComponentKind::Int);
  EXPECT_EQ(vec(r[0]), A * x);
  EXPECT_EQ(vec(r[1]), A.transpose() * x);
  EXPECT_EQ(vec(r[2]), A * A.transpose() * x);
  EXPECT_EQ(vec(r[3]), (3 * A - half - A) * x);
  EXPECT_EQ(vec(r[4]), B * v);
  EXPECT_EQ(vec(r[5]), B.transpose() * v);
  ASSERT_EQ(r[6].kind(), Value::Kind::Int);
  EXPECT_EQ(r[6].as_int(), x.dot(A * x));
}

// `M - s * K` is computed as one sum over the union pattern (A + (-s) K); it must give the
// bits of the product taken first, and of the dense reference M - (s K) entry by entry.
TEST(FloatSystemMatrices, AScaledDifferenceIsTheProductThenTheDifference) {
  Harness h(R"(
element N  m : float; end
element S  k : float; end
extern nodes : set{N};
extern springs : set{S}(nodes, nodes);
func stiff(s : S, e : (N * 2)) -> K : matrix[nodes,nodes](matrix[2,2](float))
  K(e(0), e(1)) = s.k * [1.0, 0.3; -0.7, 2.0];
  K(e(1), e(1)) = s.k * [1.0, 0.0; 0.0, -1.0] + [0.0, 0.1; 0.0, 0.0];
end
func mass(p : N) -> M : matrix[nodes,nodes](matrix[2,2](float))
  M(p, p) = p.m * [1.0, 0.0; 0.0, 1.0];
end
export func main() -> (A1 : matrix[nodes,nodes](matrix[2,2](float)),
                       A2 : matrix[nodes,nodes](matrix[2,2](float)),
                       A3 : matrix[nodes,nodes](matrix[2,2](float)))
  K = map stiff to springs reduce +;
  M = map mass to nodes reduce +;
  h = 0.013;
  A1 = M - (h * h) * K;
  A3 = M + K * (h * 7.0);
  S = (h * h) * K;
  A2 = M - S;
end
)");
  ASSERT_TRUE(h.ok());
  Graph g;
  h.bind("nodes", g.nodes);
  h.bind("springs", g.springs);
  for (int i = 0; i < g.n; ++i) g.nodes.field("m").data<double>()[i] = 0.37 + 0.11 * i;
  for (int e = 0; e < g.springs.size(); ++e) g.springs.field("k").data<double>()[e] = 1.3 + 0.7 * e;
  auto r = h.run("main");
  ASSERT_EQ(r.size(), 3u);
  const runtime::SystemMatrix &a1 = *r[0].matrix(), &a2 = *r[1].matrix(), &a3 = *r[2].matrix();
  ASSERT_EQ(a1.value_count(), a2.value_count());
  for (size_t i = 0; i < a1.value_count(); ++i)
    EXPECT_EQ(std::memcmp(&a1.values()[i], &a2.values()[i], sizeof(double)), 0) << i;
  // The dense reference, each entry rounded as the contract says: m + (-1) * (s * k).
  const double s = 0.013 * 0.013, t = 0.013 * 7.0;
  MatrixXd M = MatrixXd::Zero(2 * g.n, 2 * g.n), K = M;
  for (int i = 0; i < g.n; ++i)
    M.block<2, 2>(2 * i, 2 * i) = (0.37 + 0.11 * i) * Eigen::Matrix2d::Identity();
  for (size_t e = 0; e < g.edges.size(); ++e) {
    auto [a, b] = g.edges[e];
    const double k = 1.3 + 0.7 * static_cast<double>(e);
    Eigen::Matrix2d blk, diag;
    blk << k * 1.0, k * 0.3, k * -0.7, k * 2.0;
    diag << k, 0.1, 0.0, -k;
    K.block<2, 2>(2 * a, 2 * b) += blk;
    K.block<2, 2>(2 * b, 2 * b) += diag;
  }
  const MatrixXd want1 = M - (s * K), want3 = M + (t * K);
  for (int i = 0; i < 2 * g.n; ++i)
    for (int j = 0; j < 2 * g.n; ++j) {
      EXPECT_EQ(a1.component(i, j), want1(i, j)) << i << "," << j;
      EXPECT_EQ(a3.component(i, j), want3(i, j)) << i << "," << j;
    }
}

TEST(NestedBlockMatrices, ProductsMatchTheLogicalDenseMatrix) {
  Harness h(R"(
element N  u : float; end
element S  k : float; end
extern nodes : set{N};
extern springs : set{S}(nodes, nodes);
func blocks(s : S, e : (N * 2))
    -> K : matrix[nodes,nodes](matrix[2,3](matrix[2,2](float)))
  var m : matrix[2,3](matrix[2,2](float));
  var fI = 0.0;
  for I in 0:2
    var fJ = 0.0;
    for J in 0:3
      var fi = 0.0;
      for i in 0:2
        var fj = 0.0;
        for j in 0:2
          m(I, J)(i, j) = s.k * ((6.0 * fI + 2.0 * fJ) + 0.5 * fi - 0.25 * fj) + e(1).u;
          fj = fj + 1.0;
        end
        fi = fi + 1.0;
      end
      fJ = fJ + 1.0;
    end
    fI = fI + 1.0;
  end
  K(e(0), e(1)) = m;
  K(e(1), e(1)) = 2.0 * m;
end
export func main() -> (Ku : vector[nodes](vector[2](vector[2](float))),
                       Ktw : vector[nodes](vector[3](vector[2](float))),
                       Su : vector[nodes](vector[2](vector[2](float))))
  K = map blocks to springs reduce +;
  var u : vector[nodes](vector[3](vector[2](float)));
  var w : vector[nodes](vector[2](vector[2](float)));
  for p in nodes
    var factor = 1.0;
    for J in 0:3
      u(p)(J)(0) = p.u * factor;
      u(p)(J)(1) = 1.0 - p.u;
      factor = factor + 1.0;
    end
    w(p)(1)(0) = p.u;
    w(p)(0)(1) = 2.0;
  end
  Ku = K * u;
  Ktw = K' * w;
  Su = (K + 0.5 * K - K) * u;
end
)");
  ASSERT_TRUE(h.ok());
  Graph g;
  h.bind("nodes", g.nodes);
  h.bind("springs", g.springs);
  for (int i = 0; i < g.n; ++i) g.nodes.field("u").data<double>()[i] = Graph::u(i);
  for (int e = 0; e < g.springs.size(); ++e) g.springs.field("k").data<double>()[e] = Graph::k(e);
  auto r = h.run("main");
  ASSERT_EQ(r.size(), 3u);
  const int n = g.n;
  // Logical blocks are 4 x 6: row 2I + i, column 2J + j.
  MatrixXd K = MatrixXd::Zero(4 * n, 6 * n);
  for (size_t e = 0; e < g.edges.size(); ++e) {
    auto [a, b] = g.edges[e];
    MatrixXd m(4, 6);
    for (int I = 0; I < 2; ++I)
      for (int J = 0; J < 3; ++J)
        for (int i = 0; i < 2; ++i)
          for (int j = 0; j < 2; ++j)
            m(2 * I + i, 2 * J + j) =
                Graph::k(static_cast<int>(e)) * ((6.0 * I + 2.0 * J) + 0.5 * i - 0.25 * j) +
                Graph::u(b);
    K.block(4 * a, 6 * b, 4, 6) += m;
    K.block(4 * b, 6 * b, 4, 6) += 2.0 * m;
  }
  VectorXd u(6 * n), w = VectorXd::Zero(4 * n);
  for (int p = 0; p < n; ++p) {
    for (int J = 0; J < 3; ++J) {
      u(6 * p + 2 * J) = Graph::u(p) * (J + 1.0);
      u(6 * p + 2 * J + 1) = 1.0 - Graph::u(p);
    }
    w(4 * p + 2) = Graph::u(p);
    w(4 * p + 1) = 2.0;
  }
  const VectorXd ku = K * u, ktw = K.transpose() * w;
  EXPECT_LE((vec(r[0]) - ku).cwiseAbs().maxCoeff(), 1e-12 * ku.cwiseAbs().maxCoeff());
  EXPECT_LE((vec(r[1]) - ktw).cwiseAbs().maxCoeff(), 1e-12 * ktw.cwiseAbs().maxCoeff());
  EXPECT_LE((vec(r[2]) - 0.5 * ku).cwiseAbs().maxCoeff(), 1e-12 * ku.cwiseAbs().maxCoeff());
}

}  // namespace
}  // namespace simit::interp
