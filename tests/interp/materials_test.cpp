// The materials library (examples/materials/materials.sim) through the interpreter: each
// model's stress against central differences of its energy, its stress differential against
// central differences of its stress, on random deformations (inverted ones included where the
// model is defined there), its agreement with linear elasticity at rest, frame indifference,
// and the classic model's NaN on inverted elements reported by the finite check.
#include <Eigen/Dense>
#include <cmath>
#include <fstream>
#include <random>
#include <sstream>

#include "interp/runtime_error.h"
#include "test_util.h"

namespace simit::interp {
namespace {

using Eigen::Matrix3d;
using testing::func;

constexpr double kMu = 1.3, kLambda = 4.1;

std::string library_path() {
  return std::string(SIMIT_SOURCE_DIR) + "/examples/materials/materials.sim";
}

std::string library_text() {
  std::ifstream in(library_path());
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

Value value_of(const Matrix3d& m) {
  return testing::matrix(
      3, 3, {m(0, 0), m(0, 1), m(0, 2), m(1, 0), m(1, 1), m(1, 2), m(2, 0), m(2, 1), m(2, 2)});
}

Matrix3d matrix_of(const Value& v) {
  Matrix3d m;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) m(i, j) = v.tensor().floats()[i * 3 + j];
  return m;
}

Matrix3d random_rotation(std::mt19937& g) {
  std::normal_distribution<double> n;
  Eigen::Quaterniond q(n(g), n(g), n(g), n(g));
  return q.normalized().toRotationMatrix();
}

// U diag(s) V' with random rotations U, V and singular values in [0.5, 1.5], the last one
// negative when `inverted` (det F < 0): well away from the co-rotational model's singular
// set (two singular values summing to zero).
Matrix3d random_deformation(std::mt19937& g, bool inverted) {
  std::uniform_real_distribution<double> u(0.5, 1.5);
  Eigen::Vector3d s(u(g), u(g), u(g));
  if (inverted) s(2) = -s(2);
  return random_rotation(g) * s.asDiagonal() * random_rotation(g).transpose();
}

Matrix3d random_direction(std::mt19937& g) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Matrix3d d;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) d(i, j) = u(g);
  return d;
}

class Materials : public ::testing::Test {
 protected:
  void SetUp() override {
    c_ = testing::compile(library_text(), "materials.sim");
    ASSERT_TRUE(c_->ok());
    in_ = std::make_unique<Interpreter>(*c_->program);
  }
  double energy(const std::string& model, const Matrix3d& f) {
    return in_->call(func(*c_, model + "_energy"), {mu(), lambda(), value_of(f)})[0].as_float();
  }
  Matrix3d stress(const std::string& model, const Matrix3d& f) {
    return matrix_of(in_->call(func(*c_, model + "_stress"), {mu(), lambda(), value_of(f)})[0]);
  }
  Matrix3d differential(const std::string& model, const Matrix3d& f, const Matrix3d& df) {
    return matrix_of(in_->call(func(*c_, model + "_stress_differential"),
                               {mu(), lambda(), value_of(f), value_of(df)})[0]);
  }
  static Value mu() { return Value::of_float(kMu); }
  static Value lambda() { return Value::of_float(kLambda); }

  // P against the central difference of psi, component by component.
  void check_stress(const std::string& model, const Matrix3d& f) {
    const double h = 1e-6;
    const Matrix3d p = stress(model, f);
    Matrix3d fd;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) {
        Matrix3d e = Matrix3d::Zero();
        e(i, j) = h;
        fd(i, j) = (energy(model, f + e) - energy(model, f - e)) / (2 * h);
      }
    EXPECT_TRUE(p.allFinite()) << model << "\nF =\n" << f;
    EXPECT_LE((p - fd).cwiseAbs().maxCoeff(), 1e-6 * (kMu + kLambda)) << model << "\nF =\n"
                                                                      << f << "\nP =\n"
                                                                      << p << "\ndifferences =\n"
                                                                      << fd;
  }

  // dP(F; dF) against the central difference of P along dF.
  void check_differential(const std::string& model, const Matrix3d& f, const Matrix3d& df) {
    const double h = 1e-6;
    const Matrix3d dp = differential(model, f, df);
    const Matrix3d fd = (stress(model, f + h * df) - stress(model, f - h * df)) / (2 * h);
    EXPECT_TRUE(dp.allFinite()) << model << "\nF =\n" << f;
    EXPECT_LE((dp - fd).cwiseAbs().maxCoeff(), 1e-6 * (kMu + kLambda)) << model << "\nF =\n"
                                                                       << f << "\ndF =\n"
                                                                       << df << "\ndP =\n"
                                                                       << dp << "\ndifferences =\n"
                                                                       << fd;
  }

  std::unique_ptr<frontend::Compilation> c_;
  std::unique_ptr<Interpreter> in_;
};

const char* const kModels[] = {"neohookean", "stable_neohookean", "corotational", "stvk"};
// The models defined for inverted elements.
const char* const kInvertible[] = {"stable_neohookean", "corotational", "stvk"};

TEST_F(Materials, StressIsTheDerivativeOfTheEnergy) {
  std::mt19937 g(2018);
  for (const char* model : kModels)
    for (int k = 0; k < 20; ++k) check_stress(model, random_deformation(g, false));
  for (const char* model : kInvertible)
    for (int k = 0; k < 20; ++k) check_stress(model, random_deformation(g, true));
}

TEST_F(Materials, StressDifferentialIsTheDerivativeOfTheStress) {
  std::mt19937 g(2004);
  for (const char* model : kModels)
    for (int k = 0; k < 20; ++k)
      check_differential(model, random_deformation(g, false), random_direction(g));
  for (const char* model : kInvertible)
    for (int k = 0; k < 20; ++k)
      check_differential(model, random_deformation(g, true), random_direction(g));
}

TEST_F(Materials, AgreeWithLinearElasticityAtRest) {
  std::mt19937 g(7);
  const Matrix3d eye = Matrix3d::Identity();
  for (const char* model : kModels) {
    EXPECT_LE(stress(model, eye).cwiseAbs().maxCoeff(), 1e-14) << model;
    for (int k = 0; k < 5; ++k) {
      const Matrix3d df = random_direction(g);
      const Matrix3d linear = kMu * (df + df.transpose()) + kLambda * df.trace() * eye;
      EXPECT_LE((differential(model, eye, df) - linear).cwiseAbs().maxCoeff(), 1e-13) << model;
    }
  }
  EXPECT_EQ(energy("neohookean", eye), 0.0);
  EXPECT_EQ(energy("corotational", eye), 0.0);
  EXPECT_EQ(energy("stvk", eye), 0.0);
}

TEST_F(Materials, EnergiesAreFrameIndifferent) {
  std::mt19937 g(11);
  for (const char* model : kModels)
    for (int k = 0; k < 5; ++k) {
      const Matrix3d f = random_deformation(g, false), q = random_rotation(g);
      EXPECT_NEAR(energy(model, q * f), energy(model, f), 1e-12 * (kMu + kLambda)) << model;
    }
}

TEST_F(Materials, StableModelsStayFiniteWhenFlatOrInverted) {
  const Matrix3d flat = Eigen::Vector3d(1.0, 1.0, 0.0).asDiagonal();
  const Matrix3d inverted = Eigen::Vector3d(1.2, 0.8, -0.5).asDiagonal();
  for (const char* model : {"stable_neohookean", "stvk"})
    for (const Matrix3d& f : {flat, inverted, Matrix3d::Zero().eval()}) {
      EXPECT_TRUE(std::isfinite(energy(model, f))) << model << "\n" << f;
      EXPECT_TRUE(stress(model, f).allFinite()) << model << "\n" << f;
      EXPECT_TRUE(differential(model, f, Matrix3d::Identity()).allFinite()) << model;
    }
  // Stable Neo-Hookean pushes an inverted element back: the stress opposes the inversion
  // (P : dJ/dF < 0 while J < 0).
  const Matrix3d p = stress("stable_neohookean", inverted);
  const Matrix3d cof = inverted.determinant() * inverted.inverse().transpose();
  EXPECT_LT((p.array() * cof.array()).sum(), 0.0);
  EXPECT_TRUE(std::isfinite(energy("corotational", inverted)));
  EXPECT_TRUE(stress("corotational", inverted).allFinite());
}

// The line of `text` in the library, 1-based.
int line_of(const std::string& text) {
  std::istringstream in(library_text());
  std::string line;
  for (int n = 1; std::getline(in, line); ++n)
    if (line.find(text) != std::string::npos) return n;
  return -1;
}

TEST_F(Materials, ClassicModelOnAnInvertedElementIsNaNAndTheFiniteCheckReportsIt) {
  const Matrix3d inverted = Eigen::Vector3d(1.2, 0.8, -0.5).asDiagonal();
  EXPECT_TRUE(std::isnan(energy("neohookean", inverted)));
  EXPECT_TRUE(stress("neohookean", inverted).array().isNaN().any());
  Options o;
  o.check_finite = true;
  Interpreter checked(*c_->program, o);
  try {
    checked.call(func(*c_, "neohookean_energy"), {mu(), lambda(), value_of(inverted)});
    FAIL() << "expected a run-time error";
  } catch (const RuntimeError& e) {
    EXPECT_EQ(e.message(), "the operation produced NaN");
    EXPECT_EQ(e.line(), line_of("  logJ = log(det(F));"));
  }
  try {
    checked.call(func(*c_, "neohookean_stress"), {mu(), lambda(), value_of(inverted)});
    FAIL() << "expected a run-time error";
  } catch (const RuntimeError& e) {
    EXPECT_EQ(e.message(), "the operation produced NaN");
    EXPECT_EQ(e.line(), line_of("P = mu * (F - FinvT) + lambda * log(det(F)) * FinvT;"));
  }
}

}  // namespace
}  // namespace simit::interp
