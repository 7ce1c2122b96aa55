// The decomposition intrinsics through the interpreter: several results into new and
// existing variables, float32 rounding and the finite check applied to every result, and
// located errors for a non-symmetric argument.
#include <cmath>
#include <limits>

#include "interp/runtime_error.h"
#include "test_util.h"

namespace simit::interp {
namespace {

using testing::compile;
using testing::func;

constexpr const char* kProgram =
    R"(func parts(A : matrix[3,3](float)) -> (U : matrix[3,3](float), s : vector[3](float), V : matrix[3,3](float))
  U, s, V = svd(A);
end
func into_existing(A : matrix[2,2](float)) -> (w : vector[2](float), R : matrix[2,2](float))
  var S : matrix[2,2](float);
  R, S = polar(A);
  w, S = eig(S);
end
func discard(A : matrix[2,2](float)) -> r : float
  svd(A);
  r = 1.0;
end
func proj(A : matrix[2,2](float)) -> P : matrix[2,2](float)
  P = project_spd(A);
end
)";

TEST(DecompositionCalls, SeveralResultsIntoNewVariables) {
  auto c = compile(kProgram);
  Interpreter in(*c->program);
  auto r = in.call(func(*c, "parts"),
                   {testing::matrix(3, 3, {3.0, 0.0, 0.0, 0.0, -2.0, 0.0, 0.0, 0.0, 5.0})});
  ASSERT_EQ(r.size(), 3u);
  const double* s = r[1].tensor().floats();
  EXPECT_EQ(s[0], 5.0);
  EXPECT_EQ(s[1], 3.0);
  EXPECT_EQ(s[2], -2.0);
  EXPECT_EQ(r[0].tensor().shape(), (Shape{3, 3}));
  EXPECT_EQ(r[2].tensor().shape(), (Shape{3, 3}));
}

TEST(DecompositionCalls, SeveralResultsIntoExistingVariables) {
  auto c = compile(kProgram);
  Interpreter in(*c->program);
  // [0 -2; 1 0] = quarter turn * diag(1, 2).
  auto r = in.call(func(*c, "into_existing"), {testing::matrix(2, 2, {0.0, -2.0, 1.0, 0.0})});
  const double* w = r[0].tensor().floats();
  EXPECT_NEAR(w[0], 1.0, 1e-15);
  EXPECT_NEAR(w[1], 2.0, 1e-15);
  const double* rot = r[1].tensor().floats();
  const double quarter[4] = {0.0, -1.0, 1.0, 0.0};
  for (int i = 0; i < 4; ++i) EXPECT_NEAR(rot[i], quarter[i], 1e-15) << i;
}

TEST(DecompositionCalls, AsAStatementOnItsOwn) {
  auto c = compile(kProgram);
  Interpreter in(*c->program);
  auto r = in.call(func(*c, "discard"), {testing::matrix(2, 2, {1.0, 2.0, 3.0, 4.0})});
  EXPECT_EQ(r[0].as_float(), 1.0);
}

TEST(DecompositionCalls, Float32RoundsEveryResult) {
  auto c = compile(kProgram);
  Options o;
  o.float32 = true;
  Interpreter in(*c->program, o);
  auto r = in.call(func(*c, "parts"),
                   {testing::matrix(3, 3, {0.3, -0.7, 0.2, 0.9, 0.1, -0.4, -0.5, 0.6, 0.8})});
  for (const Value& v : r)
    for (size_t i = 0; i < v.tensor().size(); ++i) {
      const double x = v.tensor().floats()[i];
      EXPECT_EQ(x, static_cast<double>(static_cast<float>(x)));
    }
}

TEST(DecompositionCalls, CheckFiniteReportsANaNResultAtTheCall) {
  auto c = compile(kProgram, "decomp.sim");
  Options o;
  o.check_finite = true;
  Interpreter in(*c->program, o);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  try {
    in.call(func(*c, "parts"),
            {testing::matrix(3, 3, {1.0, 0.0, 0.0, 0.0, nan, 0.0, 0.0, 0.0, 1.0})});
    FAIL() << "expected a run-time error";
  } catch (const RuntimeError& e) {
    EXPECT_EQ(e.message(), "the operation produced a NaN or an infinity");
    EXPECT_EQ(e.line(), 2);
    EXPECT_EQ(e.where().start().column, 13);
  }
  Interpreter quiet(*c->program);
  auto r = quiet.call(func(*c, "parts"),
                      {testing::matrix(3, 3, {1.0, 0.0, 0.0, 0.0, nan, 0.0, 0.0, 0.0, 1.0})});
  EXPECT_TRUE(std::isnan(r[1].tensor().floats()[0]));
}

TEST(DecompositionCalls, NonSymmetricArgumentIsALocatedError) {
  auto c = compile(kProgram, "decomp.sim");
  Interpreter in(*c->program);
  try {
    in.call(func(*c, "proj"), {testing::matrix(2, 2, {1.0, 1.0, 0.5, 1.0})});
    FAIL() << "expected a run-time error";
  } catch (const RuntimeError& e) {
    EXPECT_EQ(e.message(),
              "project_spd needs a symmetric matrix: component (0, 1) is 1 but component (1, 0) "
              "is 0.5");
    EXPECT_EQ(e.line(), 14);
    EXPECT_EQ(e.where().start().column, 7);
  }
  // An asymmetry of float32 rounding size passes in float32 and fails in float64.
  const Value a = testing::matrix(2, 2, {1.0, 2.0, 2.0 * (1.0 + 1e-6), 1.0});
  Options o;
  o.float32 = true;
  Interpreter narrow(*c->program, o);
  EXPECT_NO_THROW(narrow.call(func(*c, "proj"), {a}));
  EXPECT_THROW(in.call(func(*c, "proj"), {a}), RuntimeError);
}

}  // namespace
}  // namespace simit::interp
