// Sparse solvers against dense Eigen solves, failure reports, and the CG loop of
// LANGUAGE.md §14.3 over the runtime's operations against Eigen's ConjugateGradient.
#include "runtime/solvers.h"

#include <gtest/gtest.h>

#include <Eigen/IterativeLinearSolvers>
#include <algorithm>
#include <cstring>

#include "runtime/sparse_convert.h"
#include "runtime/system_ops.h"
#include "runtime_fixtures.h"

namespace simit::runtime {
namespace {

using namespace simit::runtime::testing;

constexpr double kTol = 1e-10;

double max_abs(const Eigen::VectorXd& v) { return v.cwiseAbs().maxCoeff(); }

template <class F>
std::string fault_message(F f) {
  try {
    f();
  } catch (const Fault& e) {
    return e.what();
  }
  return "(no fault)";
}

class Systems : public ::testing::Test {
 protected:
  Systems() : tets("tets", {&verts, &verts, &verts, &verts}) { build_cube_tets(2, verts, tets); }

  // Σ Gᵀ G over the tets plus `mass` on the diagonal: symmetric positive definite.
  SystemMatrix spd(int block, double mass, unsigned seed) {
    SystemMatrix k(registry.assembled(tets, verts, verts), block, block);
    assemble(k, tets, gram_locals(tets.size(), 4 * block, seed));
    SystemMatrix m(registry.assembled(verts, verts, verts), block, block);
    assemble(m, verts, [block, mass](int) {
      return Eigen::MatrixXd(mass * Eigen::MatrixXd::Identity(block, block));
    });
    return add(k, m, 1.0, 1.0, &registry);
  }
  // A non-symmetric, diagonally dominated matrix on the same pattern.
  SystemMatrix general(int block, unsigned seed) {
    SystemMatrix k(registry.assembled(tets, verts, verts), block, block);
    assemble(k, tets, random_locals(tets.size(), 4 * block, 4 * block, seed));
    for (int r = 0; r < k.rows(); ++r) {
      double* d = k.block(k.pattern().find(r, r));
      for (int i = 0; i < block; ++i) d[i * block + i] += 40.0;
    }
    return k;
  }

  Set verts{"verts"};
  Set tets;
  PatternRegistry registry;
};

TEST_F(Systems, CholeskyMatchesDenseSolve) {
  SystemMatrix a = spd(3, 1.0, 1);
  const Eigen::MatrixXd dense = to_dense(a);
  const std::vector<double> b = random_vector(a.scalar_rows(), 2);
  CholeskyFactor chol(a);
  EXPECT_EQ(chol.size(), a.scalar_rows());
  const std::vector<double> x = chol.solve(b);
  const Eigen::VectorXd expected = dense.llt().solve(as_eigen(b));
  EXPECT_LT(max_abs(as_eigen(x) - expected), kTol);
  // Repeated solves with the same factor.
  const std::vector<double> b2 = random_vector(a.scalar_rows(), 3);
  EXPECT_LT(max_abs(as_eigen(chol.solve(b2)) - dense.llt().solve(as_eigen(b2))), kTol);
}

TEST_F(Systems, CholeskyRefactorReusesTheAnalysis) {
  SystemMatrix a = spd(3, 1.0, 4);
  CholeskyFactor chol(a);
  SystemMatrix twice = scaled(2.0, a);
  chol.refactor(twice);
  const std::vector<double> b = random_vector(a.scalar_rows(), 5);
  const Eigen::VectorXd expected = to_dense(a).llt().solve(as_eigen(b)) / 2.0;
  EXPECT_LT(max_abs(as_eigen(chol.solve(b)) - expected), kTol);
}

TEST_F(Systems, CholeskyWithMatrixRightHandSide) {
  SystemMatrix a = spd(1, 2.0, 6);
  SystemMatrix rhs(registry.assembled(tets, verts, tets));  // vertices × tets
  assemble(rhs, tets, random_locals(tets.size(), 4, 1, 7));
  CholeskyFactor chol(a);
  SystemMatrix x = chol.solve(rhs);
  EXPECT_EQ(x.rows(), verts.size());
  EXPECT_EQ(x.cols(), tets.size());
  const Eigen::MatrixXd expected = to_dense(a).llt().solve(to_dense(rhs));
  EXPECT_LT((to_dense(x) - expected).cwiseAbs().maxCoeff(), kTol);
}

TEST_F(Systems, NotPositiveDefiniteIsAFault) {
  SystemMatrix a = scaled(-1.0, spd(3, 1.0, 8));
  const std::string msg = fault_message([&] { CholeskyFactor chol(a); });
  EXPECT_NE(msg.find("not positive definite"), std::string::npos) << msg;
  EXPECT_NE(msg.find("element"), std::string::npos) << msg;
  // Indefinite: positive except one negative diagonal entry.
  SystemMatrix b = spd(1, 1.0, 9);
  b.block(b.pattern().find(7, 7))[0] = -1e3;
  EXPECT_THROW(CholeskyFactor{b}, Fault);
  // A factor whose refactorisation failed refuses to solve, then recovers.
  CholeskyFactor chol(spd(1, 1.0, 10));
  EXPECT_THROW(chol.refactor(b), Fault);
  EXPECT_THROW(chol.solve(std::vector<double>(b.scalar_rows())), Fault);
  chol.refactor(spd(1, 1.0, 10));
  EXPECT_NO_THROW(chol.solve(std::vector<double>(b.scalar_rows())));
}

TEST_F(Systems, LuMatchesDenseSolve) {
  SystemMatrix a = general(3, 11);
  const Eigen::MatrixXd dense = to_dense(a);
  const std::vector<double> b = random_vector(a.scalar_rows(), 12);
  LuFactor lu(a);
  const Eigen::VectorXd expected = dense.partialPivLu().solve(as_eigen(b));
  EXPECT_LT(max_abs(as_eigen(lu.solve(b)) - expected), kTol);
  std::vector<double> in_place = b;
  lu.solve(in_place, in_place);
  EXPECT_LT(max_abs(as_eigen(in_place) - expected), kTol);
  SystemMatrix a2 = general(3, 13);  // same pattern: refactor
  lu.refactor(a2);
  EXPECT_LT(max_abs(as_eigen(lu.solve(b)) - to_dense(a2).partialPivLu().solve(as_eigen(b))), kTol);
}

TEST_F(Systems, LuWithMatrixRightHandSide) {
  SystemMatrix a = general(1, 14);
  SystemMatrix rhs(registry.assembled(tets, verts, tets));
  assemble(rhs, tets, random_locals(tets.size(), 4, 1, 15));
  SystemMatrix x = LuFactor(a).solve(rhs);
  const Eigen::MatrixXd expected = to_dense(a).partialPivLu().solve(to_dense(rhs));
  EXPECT_LT((to_dense(x) - expected).cwiseAbs().maxCoeff(), kTol);
}

// The same matrix on a pattern without its zero blocks (a JIT-specialised pattern holds only
// the blocks a map writes): the copy of `a` without the blocks whose every value is zero.
SystemMatrix without_zero_blocks(const SystemMatrix& a) {
  const MatrixPattern& p = a.pattern();
  const int bs = a.block_size();
  std::vector<int32_t> row_ptr{0}, cols;
  std::vector<double> values;
  for (int r = 0; r < p.rows(); ++r) {
    for (int32_t k = p.row_ptr()[r]; k < p.row_ptr()[r + 1]; ++k) {
      const double* b = a.block(k);
      if (std::all_of(b, b + bs, [](double v) { return v == 0.0; })) continue;
      cols.push_back(p.col_idx()[k]);
      values.insert(values.end(), b, b + bs);
    }
    row_ptr.push_back(static_cast<int32_t>(cols.size()));
  }
  SystemMatrix out(MatrixPattern::from_csr(p.rows(), p.cols(), std::move(row_ptr), std::move(cols)),
                   a.block_rows(), a.block_cols());
  std::copy(values.begin(), values.end(), out.values());
  return out;
}

// Vertex 0 decoupled: every block of its row and column but the diagonal one is zero.
void decouple_first(SystemMatrix& a) {
  const MatrixPattern& p = a.pattern();
  for (int r = 0; r < p.rows(); ++r)
    for (int32_t k = p.row_ptr()[r]; k < p.row_ptr()[r + 1]; ++k)
      if ((r == 0) != (p.col_idx()[k] == 0))
        std::fill(a.block(k), a.block(k) + a.block_size(), 0.0);
}

// A direct solve does not depend on the zero blocks a pattern holds: the same bits on the
// full pattern and without them, by Cholesky and by LU, and after a refactorisation whose
// zeros moved (the analysis is made again).
TEST_F(Systems, SolvesDoNotDependOnZeroBlocksOfThePattern) {
  for (bool symmetric : {true, false}) {
    SystemMatrix a = symmetric ? spd(3, 1.0, 21) : general(3, 22);
    decouple_first(a);
    const SystemMatrix b = without_zero_blocks(a);
    ASSERT_LT(b.pattern().nnz(), a.pattern().nnz());
    const std::vector<double> rhs = random_vector(a.scalar_rows(), 23);
    const std::vector<double> x = solve(a, rhs), y = solve(b, rhs);
    ASSERT_EQ(x.size(), y.size());
    for (size_t i = 0; i < x.size(); ++i)
      EXPECT_EQ(std::memcmp(&x[i], &y[i], sizeof(double)), 0) << symmetric << " " << i;
    const Eigen::VectorXd expected = to_dense(a).lu().solve(as_eigen(rhs));
    EXPECT_LT(max_abs(as_eigen(x) - expected), kTol);
  }
  // One factor refactored with the zeros elsewhere gives a fresh factor's bits.
  SystemMatrix a = spd(3, 1.0, 24), c = a;
  decouple_first(c);
  CholeskyFactor chol(a);
  chol.refactor(c);
  const std::vector<double> rhs = random_vector(a.scalar_rows(), 25);
  const std::vector<double> x = chol.solve(rhs), y = CholeskyFactor(c).solve(rhs);
  for (size_t i = 0; i < x.size(); ++i)
    EXPECT_EQ(std::memcmp(&x[i], &y[i], sizeof(double)), 0) << i;
}

TEST_F(Systems, SingularLuIsAFault) {
  SystemMatrix a(registry.assembled(tets, verts, verts));  // all zero
  // Eigen's own text ("STRUCTURALLY SINGULAR ... ZERO COLUMN AT k", k in its ordering) is
  // not passed on.
  EXPECT_EQ(fault_message([&] { LuFactor lu(a); }),
            "LU factorisation failed: the matrix is singular (elimination found no nonzero pivot "
            "for one of its columns)");
}

TEST_F(Systems, NumericallySingularLuIsAFault) {
  // Every 2x2 diagonal block is [1 1; 1 1]: no zero column, but singular.
  SystemMatrix m(registry.assembled(verts, verts, verts), 2, 2);
  assemble(m, verts, [](int) { return Eigen::MatrixXd(Eigen::MatrixXd::Ones(2, 2)); });
  EXPECT_EQ(fault_message([&] { LuFactor lu(m); }),
            "LU factorisation failed: the matrix is singular (elimination found no nonzero pivot "
            "for one of its columns)");
}

TEST_F(Systems, SizeMismatchesFault) {
  LuFactor lu(general(1, 16));
  EXPECT_THROW(lu.solve(std::vector<double>(3)), Fault);
  SystemMatrix rect(registry.assembled(tets, tets, verts));
  EXPECT_THROW(LuFactor{rect}, Fault);
  EXPECT_THROW(CholeskyFactor{rect}, Fault);
}

TEST_F(Systems, LowerTriangularSolve) {
  SystemMatrix a = general(3, 17);
  const Eigen::MatrixXd dense = to_dense(a);
  const std::vector<double> b = random_vector(a.scalar_rows(), 18);
  std::vector<double> x(b.size());
  lower_triangular_solve(a, b, x);
  const Eigen::VectorXd expected = dense.triangularView<Eigen::Lower>().solve(as_eigen(b));
  EXPECT_LT(max_abs(as_eigen(x) - expected), kTol);
  SystemMatrix zero_diagonal = a;
  zero_diagonal.block(a.pattern().find(2, 2))[4] = 0.0;  // scalar row 7
  const std::string msg = fault_message([&] { lower_triangular_solve(zero_diagonal, b, x); });
  EXPECT_NE(msg.find("row 7 (element 2, component 1)"), std::string::npos) << msg;
}

TEST_F(Systems, BackslashPicksASolver) {
  SystemMatrix s = spd(3, 1.0, 19);
  SystemMatrix g = general(3, 20);
  EXPECT_TRUE(is_symmetric(s));
  EXPECT_FALSE(is_symmetric(g));
  const std::vector<double> b = random_vector(s.scalar_rows(), 21);
  EXPECT_LT(max_abs(as_eigen(solve(s, b)) - to_dense(s).llt().solve(as_eigen(b))), kTol);
  EXPECT_LT(max_abs(as_eigen(solve(g, b)) - to_dense(g).partialPivLu().solve(as_eigen(b))), kTol);
  SystemMatrix indefinite = scaled(-1.0, s);  // symmetric, not positive definite: LU
  EXPECT_LT(max_abs(as_eigen(solve(indefinite, b)) + to_dense(s).llt().solve(as_eigen(b))), kTol);
}

TEST(EmptySystems, SolveNothing) {
  Set none("none");
  PatternRegistry registry;
  SystemMatrix a(registry.assembled(none, none, none), 3, 3);
  const std::vector<double> b;
  std::vector<double> x;
  EXPECT_TRUE(CholeskyFactor(a).solve(b).empty());
  EXPECT_TRUE(LuFactor(a).solve(b).empty());
  EXPECT_TRUE(solve(a, b).empty());
  multiply(a, b, x);
  lower_triangular_solve(a, b, x);
}

// LANGUAGE.md §14.3, written over the runtime's operations.
std::vector<double> cg(const SystemMatrix& a, const std::vector<double>& b, int iters) {
  const size_t n = b.size();
  std::vector<double> x(n, 0.0), r(n), p(n), ap(n);
  multiply(a, x, ap);
  subtract(b, ap, r);  // r = b - A * x
  p = r;
  double rr = dot(r, r);
  int k = 0;
  while (k < iters && rr > 1e-20) {
    multiply(a, p, ap);
    const double alpha = rr / dot(p, ap);
    axpy(alpha, p, x);
    axpy(-alpha, ap, r);
    const double rr_new = dot(r, r);
    scale(rr_new / rr, std::span<double>(p));
    add(r, p, p);  // p = r + (rr_new / rr) * p
    rr = rr_new;
    ++k;
  }
  return x;
}

TEST_F(Systems, ConjugateGradientMatchesEigen) {
  SystemMatrix a = spd(3, 5.0, 22);
  const std::vector<double> b = random_vector(a.scalar_rows(), 23);
  const std::vector<double> ours = cg(a, b, 1000);
  Eigen::ConjugateGradient<EigenSparse, Eigen::Lower | Eigen::Upper, Eigen::IdentityPreconditioner>
      eigen_cg;
  eigen_cg.setTolerance(1e-14);
  eigen_cg.setMaxIterations(1000);
  const EigenSparse matrix = to_eigen(a);  // the solver keeps a reference to it
  eigen_cg.compute(matrix);
  const Eigen::VectorXd theirs = eigen_cg.solve(as_eigen(b));
  ASSERT_EQ(eigen_cg.info(), Eigen::Success);
  EXPECT_LT(max_abs(as_eigen(ours) - theirs), kTol);
  EXPECT_LT(max_abs(as_eigen(ours) - to_dense(a).llt().solve(as_eigen(b))), kTol);
}

// A set a scene renumbered: the solvers' messages name the element by its mesh number (and
// the set), never by the internal row.
class RenumberedSystems : public Systems {
 protected:
  RenumberedSystems() {
    // Mesh number of element e: (5 e + 3) mod n, a permutation (n = 27 is prime to 5).
    std::vector<int32_t> numbers(static_cast<size_t>(verts.size()));
    for (int e = 0; e < verts.size(); ++e) numbers[e] = (5 * e + 3) % verts.size();
    verts.set_mesh_numbers(numbers);
  }
  // "element M of set 'verts'", M worked out here from the permutation above.
  std::string element(int e) const {
    return "element " + std::to_string((5 * e + 3) % verts.size()) + " of set 'verts'";
  }
  // The identity with a b x b block per vertex, but `value` at component (c, c) of vertex v.
  SystemMatrix diagonal(int b, int v, int c, double value) {
    SystemMatrix m(registry.assembled(verts, verts, verts), b, b);
    assemble(m, verts, [b](int) { return Eigen::MatrixXd(Eigen::MatrixXd::Identity(b, b)); });
    m.block(m.pattern().find(v, v))[c * b + c] = value;
    return m;
  }
};

TEST_F(RenumberedSystems, TriangularSolveNamesTheElement) {
  ASSERT_EQ(verts.size(), 27);
  SystemMatrix a = general(3, 17);
  a.block(a.pattern().find(2, 2))[4] = 0.0;  // scalar row 7: component 1 of vertex 2
  const std::vector<double> b = random_vector(a.scalar_rows(), 18);
  std::vector<double> x(b.size());
  EXPECT_EQ(fault_message([&] { lower_triangular_solve(a, b, x); }),
            "triangularSolve: the diagonal entry of the row of component 1 of " + element(2) +
                " is zero");
  // Unblocked: the row is the element's.
  SystemMatrix u = general(1, 19);
  u.block(u.pattern().find(11, 11))[0] = 0.0;
  x.resize(static_cast<size_t>(u.scalar_rows()));
  EXPECT_EQ(
      fault_message([&] { lower_triangular_solve(u, std::vector<double>(x.size(), 1.0), x); }),
      "triangularSolve: the diagonal entry of the row of " + element(11) + " is zero");
}

TEST_F(RenumberedSystems, CholeskyNamesTheElementWhosePivotFails) {
  // One negative diagonal entry: whatever the ordering, the pivot that fails is that row's.
  EXPECT_EQ(fault_message([&] { CholeskyFactor chol(diagonal(2, 13, 1, -4.0)); }),
            "Cholesky factorisation failed: the matrix is not positive definite (the pivot of the "
            "row of component 1 of " +
                element(13) + " is not positive)");
  // A zero diagonal entry leaves its column empty.
  EXPECT_EQ(fault_message([&] { CholeskyFactor chol(diagonal(1, 20, 0, 0.0)); }),
            "Cholesky factorisation failed: the matrix is not positive definite (the pivot of the "
            "row of " +
                element(20) + " is not positive)");
  // Through a sum (the union of two patterns keeps the rows' set): spd() adds two matrices.
  SystemMatrix s = spd(1, 1.0, 9);
  ASSERT_NE(s.pattern().row_axis(), nullptr);
  s.block(s.pattern().find(7, 7))[0] = -1e3;
  const std::string msg = fault_message([&] { CholeskyFactor chol(s); });
  EXPECT_NE(msg.find("of set 'verts'"), std::string::npos) << msg;
}

TEST_F(RenumberedSystems, SingularLuNamesTheEmptyColumn) {
  EXPECT_EQ(fault_message([&] { LuFactor lu(diagonal(3, 4, 2, 0.0)); }),
            "LU factorisation failed: the matrix is singular (the column of component 2 of " +
                element(4) + " has no nonzero entry)");
  // `A \ b`: symmetric, so Cholesky first; LU's message is the one reported.
  EXPECT_EQ(fault_message([&] {
              solve(diagonal(1, 0, 0, 0.0), std::vector<double>(static_cast<size_t>(27), 1.0));
            }),
            "LU factorisation failed: the matrix is singular (the column of " + element(0) +
                " has no nonzero entry)");
}

// Rows that are not a renumbered set keep the plain row numbers, also next to columns that are.
TEST(PlainSystems, KeepTheirRowNumbers) {
  Set verts("verts"), tets("tets", {&verts, &verts, &verts, &verts});
  build_cube_tets(2, verts, tets);
  PatternRegistry registry;
  SystemMatrix m(registry.assembled(verts, verts, verts));
  assemble(m, verts, [](int) { return Eigen::MatrixXd(Eigen::MatrixXd::Identity(1, 1)); });
  m.block(m.pattern().find(5, 5))[0] = 0.0;
  std::vector<double> x(static_cast<size_t>(m.scalar_rows()));
  EXPECT_EQ(
      fault_message([&] { lower_triangular_solve(m, std::vector<double>(x.size(), 1.0), x); }),
      "triangularSolve: the diagonal entry of row 5 is zero");
  EXPECT_EQ(fault_message([&] { CholeskyFactor chol(m); }),
            "Cholesky factorisation failed: the matrix is not positive definite (the pivot of row "
            "5 is not positive)");
}

}  // namespace
}  // namespace simit::runtime
