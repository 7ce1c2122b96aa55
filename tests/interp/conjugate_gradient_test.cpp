// The conjugate-gradient loop of LANGUAGE.md §14.3 through the interpreter, on a matrix
// assembled from a spring network on host-built sets, against Eigen's ConjugateGradient on the
// same matrix (computed here in C++ from the same element data).
#include <Eigen/Dense>
#include <Eigen/IterativeLinearSolvers>
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
// The conjugate-gradient loop of LANGUAGE.md §14.3 on an assembled SPD matrix, against
// Eigen's ConjugateGradient on the same matrix.

constexpr const char* kCgProgram = R"(
element Node  m : float; b : float; end
element Spring  k : float; end
extern nodes : set{Node};
extern springs : set{Spring}(nodes, nodes);

func cg<S>(A : matrix[S,S](float), b : vector[S](float), iters : int)
    -> x : vector[S](float)
  var r = b - A * x;          % x starts at zero
  var p = r;
  var rr = r' * r;
  var k = 0;
  while (k < iters) and (rr > 1e-20)
    Ap = A * p;               % implicit locals: fresh each iteration
    alpha = rr / (p' * Ap);
    x = x + alpha * p;
    r = r - alpha * Ap;
    rr_new = r' * r;
    p = r + (rr_new / rr) * p;
    rr = rr_new;
    k = k + 1;
  end
end

func mass(n : Node) -> M : matrix[nodes,nodes](float)
  M(n, n) = n.m;
end

func laplacian(s : Spring, e : (Node * 2)) -> L : matrix[nodes,nodes](float)
  L(e(0), e(0)) = s.k;   L(e(0), e(1)) = -s.k;
  L(e(1), e(0)) = -s.k;  L(e(1), e(1)) = s.k;
end

export func solve(iters : int) -> (A : matrix[nodes,nodes](float), x : vector[nodes](float))
  M = map mass to nodes reduce +;
  L = map laplacian to springs reduce +;
  A = M + L;
  x = cg(A, nodes.b, iters);
end
)";

// A spring network on a jittered 2-D lattice: lattice links, diagonals and a few long links.
struct Network {
  runtime::Set nodes{"nodes"};
  runtime::Set springs{"springs", {&nodes, &nodes}};
  int n = 0;
  explicit Network(int side) {
    n = side * side;
    nodes.add_many(n);
    auto id = [&](int i, int j) { return i * side + j; };
    for (int i = 0; i < side; ++i)
      for (int j = 0; j < side; ++j) {
        if (j + 1 < side) springs.add({id(i, j), id(i, j + 1)});
        if (i + 1 < side) springs.add({id(i + 1, j), id(i, j)});
        if (i + 1 < side && j + 1 < side && (i + j) % 3 == 0)
          springs.add({id(i, j), id(i + 1, j + 1)});
      }
    for (int t = 0; t < side; ++t) springs.add({id(t, 0), id(side - 1 - t, side - 1)});
  }
  void fill() {
    for (int i = 0; i < n; ++i) {
      field(nodes, "m")[i] = 0.5 + 0.01 * (i % 17);
      field(nodes, "b")[i] = std::sin(0.37 * i) + 0.1 * (i % 5);
    }
    for (int e = 0; e < springs.size(); ++e)
      field(springs, "k")[e] = 1.0 + 0.5 * std::cos(0.11 * e) + 0.2 * (e % 3);
  }
  // The same matrix, assembled here from the element data with triplets.
  runtime::EigenSparse matrix() {
    std::vector<Eigen::Triplet<double>> t;
    for (int i = 0; i < n; ++i) t.emplace_back(i, i, field(nodes, "m")[i]);
    for (int e = 0; e < springs.size(); ++e) {
      const int a = springs.endpoint(e, 0), b = springs.endpoint(e, 1);
      const double k = field(springs, "k")[e];
      t.emplace_back(a, a, k);
      t.emplace_back(b, b, k);
      t.emplace_back(a, b, -k);
      t.emplace_back(b, a, -k);
    }
    runtime::EigenSparse A(n, n);
    A.setFromTriplets(t.begin(), t.end());
    return A;
  }
};

TEST(ConjugateGradient, ConvergedSolutionMatchesEigenCG) {
  Harness h(kCgProgram);
  ASSERT_TRUE(h.ok());
  Network net(18);  // 324 vertices
  h.bind("nodes", net.nodes);
  h.bind("springs", net.springs);
  net.fill();
  auto r = h.run("solve", {Value::of_int(2000)});
  ASSERT_EQ(r.size(), 2u);

  // The assembled matrix is the one built here independently.
  runtime::EigenSparse A = runtime::to_eigen(*r[0].matrix());
  runtime::EigenSparse expected = net.matrix();
  EXPECT_LE((MatrixXd(A) - MatrixXd(expected)).cwiseAbs().maxCoeff(), 1e-14);

  VectorXd b = vec(net.nodes, "b");
  Eigen::ConjugateGradient<runtime::EigenSparse, Eigen::Lower | Eigen::Upper> cg;
  cg.setTolerance(1e-15);
  cg.setMaxIterations(2000);
  cg.compute(A);
  VectorXd x = cg.solve(b);
  ASSERT_EQ(cg.info(), Eigen::Success);
  VectorXd xs = vec(r[1]);
  ASSERT_EQ(xs.size(), x.size());
  RecordProperty("max_abs_difference", [&] {
    char b[32];
    std::snprintf(b, sizeof b, "%.3e", (xs - x).cwiseAbs().maxCoeff());
    return std::string(b);
  }());
  RecordProperty("max_abs_x", std::to_string(x.cwiseAbs().maxCoeff()));
  RecordProperty("eigen_iterations", static_cast<int>(cg.iterations()));
  EXPECT_LE((xs - x).cwiseAbs().maxCoeff(), 1e-10 * x.cwiseAbs().maxCoeff())
      << "max |x| " << x.cwiseAbs().maxCoeff();
  EXPECT_LE((A * xs - b).norm(), 1e-9 * b.norm());
}

// With the identity preconditioner Eigen runs the same iteration; after a fixed number of
// steps (far from convergence) the iterates agree too.
TEST(ConjugateGradient, IteratesMatchUnpreconditionedEigenCG) {
  Harness h(kCgProgram);
  ASSERT_TRUE(h.ok());
  Network net(15);
  h.bind("nodes", net.nodes);
  h.bind("springs", net.springs);
  net.fill();
  runtime::EigenSparse A = net.matrix();
  VectorXd b = vec(net.nodes, "b");
  for (int iters : {1, 5, 20}) {
    auto r = h.run("solve", {Value::of_int(iters)});
    Eigen::ConjugateGradient<runtime::EigenSparse, Eigen::Lower | Eigen::Upper,
                             Eigen::IdentityPreconditioner>
        cg;
    cg.setTolerance(1e-30);
    cg.setMaxIterations(iters);
    cg.compute(A);
    VectorXd x = cg.solve(b);
    EXPECT_EQ(cg.iterations(), iters);
    VectorXd xs = vec(r[1]);
    EXPECT_LE((xs - x).cwiseAbs().maxCoeff(), 1e-10 * x.cwiseAbs().maxCoeff())
        << iters << " iterations";
  }
}

}  // namespace
}  // namespace simit::interp
