// Acceptance: Neo-Hookean stress and its differential for one element, computed by a .sim
// program in the interpreter, agree with an independent Eigen computation to 1e-12.
#include <Eigen/Dense>
#include <fstream>
#include <sstream>

#include "test_util.h"

namespace simit::interp {
namespace {

using Mat3 = Eigen::Matrix3d;
using Vec3 = Eigen::Vector3d;

std::string read_program() {
  std::ifstream in(SIMIT_SOURCE_DIR "/tests/interp/programs/neohookean.sim");
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

Mat3 to_eigen(const Value& v) {
  EXPECT_TRUE(v.is_tensor());
  Mat3 m;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) m(i, j) = v.tensor().floats()[i * 3 + j];
  return m;
}

Value to_value(const Vec3& v) { return testing::vector({v(0), v(1), v(2)}); }

Mat3 edges(const Vec3 x[4]) {
  Mat3 d;
  d << x[1] - x[0], x[2] - x[0], x[3] - x[0];
  return d;
}

Mat3 stress(const Mat3& F, double mu, double lambda) {
  Mat3 FinvT = F.inverse().transpose();
  return mu * (F - FinvT) + lambda * std::log(F.determinant()) * FinvT;
}

Mat3 differential(const Mat3& F, const Mat3& dF, double mu, double lambda) {
  Mat3 Finv = F.inverse(), FinvT = Finv.transpose();
  double logJ = std::log(F.determinant());
  return mu * dF + (mu - lambda * logJ) * FinvT * dF.transpose() * FinvT +
         lambda * (Finv * dF).trace() * FinvT;
}

void expect_close(const Mat3& actual, const Mat3& expected) {
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      double scale = std::max(std::abs(expected(i, j)), expected.cwiseAbs().maxCoeff() * 1e-3);
      EXPECT_LE(std::abs(actual(i, j) - expected(i, j)), 1e-12 * scale)
          << "component (" << i << ", " << j << "): " << actual(i, j) << " vs " << expected(i, j);
    }
}

TEST(NeoHookean, ElementStressAndDifferentialMatchEigen) {
  auto c = testing::compile(read_program(), "neohookean.sim");
  Interpreter interp(*c->program);
  const Vec3 X[4] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  const Vec3 x[4] = {{0.1, -0.05, 0.02}, {1.2, 0.1, -0.03}, {-0.04, 0.95, 0.11}, {0.07, 0.02, 1.3}};
  const Vec3 dx[4] = {
      {0.01, 0.0, -0.02}, {0.03, -0.01, 0.0}, {0.0, 0.02, 0.01}, {-0.01, 0.0, 0.04}};
  const double mu = 3.5e5, lambda = 1.2e6;
  std::vector<Value> args;
  for (const auto* group : {X, x, dx})
    for (int k = 0; k < 4; ++k) args.push_back(to_value(group[k]));
  args.push_back(Value::of_float(mu));
  args.push_back(Value::of_float(lambda));
  std::vector<Value> results = interp.call(testing::func(*c, "element_stress"), args);
  ASSERT_EQ(results.size(), 2u);

  Mat3 DmInv = edges(X).inverse();
  Mat3 F = edges(x) * DmInv, dF = edges(dx) * DmInv;
  expect_close(to_eigen(results[0]), stress(F, mu, lambda));
  expect_close(to_eigen(results[1]), differential(F, dF, mu, lambda));
}

TEST(NeoHookean, StressOfIdentityIsZero) {
  auto c = testing::compile(read_program(), "neohookean.sim");
  Interpreter interp(*c->program);
  Value I = testing::matrix(3, 3, {1, 0, 0, 0, 1, 0, 0, 0, 1});
  Value P = interp.call(testing::func(*c, "neohookean_stress"),
                        {I, Value::of_float(2.0), Value::of_float(3.0)})[0];
  for (int i = 0; i < 9; ++i) EXPECT_EQ(P.tensor().floats()[i], 0.0);
}

TEST(NeoHookean, StressMatchesEigenForSeveralGradients) {
  auto c = testing::compile(read_program(), "neohookean.sim");
  Interpreter interp(*c->program);
  std::srand(7);
  for (int n = 0; n < 20; ++n) {
    Mat3 F = Mat3::Identity() + 0.3 * Mat3::Random();
    if (F.determinant() <= 0.1) continue;
    Mat3 dF = Mat3::Random();
    std::vector<double> f(F.data(), F.data() + 9), d(dF.data(), dF.data() + 9);
    // Eigen is column-major; the values are passed transposed and compared transposed.
    Value Fv = testing::matrix(3, 3, f), dFv = testing::matrix(3, 3, d);
    Mat3 Ft = F.transpose(), dFt = dF.transpose();
    Value P = interp.call(testing::func(*c, "neohookean_stress"),
                          {Fv, Value::of_float(1.5), Value::of_float(4.0)})[0];
    Value dP = interp.call(testing::func(*c, "neohookean_differential"),
                           {Fv, dFv, Value::of_float(1.5), Value::of_float(4.0)})[0];
    expect_close(to_eigen(P), stress(Ft, 1.5, 4.0));
    expect_close(to_eigen(dP), differential(Ft, dFt, 1.5, 4.0));
  }
}

}  // namespace
}  // namespace simit::interp
