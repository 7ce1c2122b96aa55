// A solver loop's products two rows at a time under --float32 (PrunedMatrix::pairs,
// jit/llvm/emit_spmv_pairs.cpp): for blocks of 2, 3 and 4 rows, an odd number of rows (the
// last pair has one row), rows of different lengths and rows that lost blocks to the zero
// blocks dropped, and a product of a binary64 vector, the loop gives the interpreter's bits on
// 1 and 3 threads and under --check-jit.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <sstream>
#include <string>

#include "api/engine.h"

namespace simit::jit {
namespace {

using api::CompiledProgram;
using api::Engine;
using api::EngineOptions;
using api::ExecutorKind;
using interp::Value;

// The program for blocks of n rows: `I` stands for the n x n identity, `N` for n.
std::string program(int n) {
  std::string eye = "[";
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j)
      eye += std::string(i == j ? "1.0" : "0.0") + (j + 1 < n ? ", " : "");
    eye += i + 1 < n ? "; " : "]";
  }
  std::string text = R"(
element Point
  x : vector[N](float);
  g : vector[N](float);
  m : float;
end
element Spring
  k : float;
end
extern points : set{Point};
extern springs : set{Spring}(points, points);

func stiffness(s : Spring, p : (Point * 2)) -> K : matrix[points,points](matrix[N,N](float))
  d = p(1).x - p(0).x;
  B = (s.k / (d' * d)) * (d * d') + (0.25 * s.k) * I;
  K(p(0), p(0)) = B;
  K(p(1), p(1)) = B;
  K(p(0), p(1)) = -B;
  K(p(1), p(0)) = -B;
end

func mass(q : Point) -> M : matrix[points,points](matrix[N,N](float))
  M(q, q) = q.m * I;
end

export func solve() -> (x : vector[points](vector[N](float)), iterations : int)
  A = (map mass to points reduce +) + 0.01 * (map stiffness to springs reduce +);
  g = points.g;
  var r = g - A * g;
  var p = r;
  var rr = dot(r, r);
  x = g;
  while (iterations < 9)
    Ap = A * p;
    alpha = rr / dot(p, Ap);
    x = x + alpha * p;
    r = r - alpha * Ap;
    rr_new = dot(r, r);
    p = r + (rr_new / rr) * p;
    rr = rr_new;
    iterations = iterations + 1;
  end
end
)";
  for (size_t at; (at = text.find('I')) != std::string::npos;) text.replace(at, 1, eye);
  for (size_t at; (at = text.find("N")) != std::string::npos;)
    text.replace(at, 1, std::to_string(n));
  return text;
}

struct Solved {
  runtime::Tensor x;
  std::string stats;
};

// 41 points, springs from i to i + 1 .. i + 3 but every fifth left out (rows of different
// lengths), every seventh with k = 0 (its blocks are zero and dropped, so some rows lose
// blocks); x binary32, g a binary64 field (its product is computed in binary64 and rounded).
Solved solve(int n, ExecutorKind kind, int threads, bool check) {
  auto compiled = CompiledProgram::from_source("pair_products.sim", program(n));
  EXPECT_TRUE(compiled->ok());
  runtime::Set points("points");
  runtime::Set springs("springs", {&points, &points});
  const int count = 41;
  points.add_many(count);
  points.add_field("x", runtime::FieldType{runtime::ComponentKind::Float, {n}, true});
  points.add_field("g", runtime::FieldType{runtime::ComponentKind::Float, {n}, false});
  points.add_field("m", runtime::FieldType{runtime::ComponentKind::Float, {}, true});
  for (int i = 0; i < count; ++i) {
    runtime::Tensor x(runtime::ComponentKind::Float, runtime::Shape{n});
    runtime::Tensor g(runtime::ComponentKind::Float, runtime::Shape{n});
    for (int c = 0; c < n; ++c) {
      x.mutable_floats()[c] = std::cos(0.7 * i + c) + 0.1 * i * (c + 1);
      g.mutable_floats()[c] = 0.1 * std::sin(1.3 * i + 0.5 * c);  // not binary32 values
    }
    points.set(0, i, x);
    points.set(1, i, g);
    runtime::Tensor m(runtime::ComponentKind::Float, runtime::Shape{});
    m.mutable_floats()[0] = 1.0 + 0.01 * i;
    points.set(2, i, m);
  }
  int spring = 0;
  for (int i = 0; i < count; ++i)
    for (int j = 1; j <= 3; ++j)
      if (i + j < count && (spring++ % 5) != 4) springs.add({i, i + j});
  springs.add_field("k", runtime::FieldType{runtime::ComponentKind::Float, {}, true});
  for (int e = 0; e < springs.size(); ++e) {
    runtime::Tensor k(runtime::ComponentKind::Float, runtime::Shape{});
    k.mutable_floats()[0] = e % 7 == 3 ? 0.0 : 10.0 + std::sin(0.3 * e);
    springs.set(0, e, k);
  }
  EngineOptions o;
  o.executor.kind = kind;
  o.executor.threads = threads;
  o.executor.threshold = 0;
  o.executor.check = check;
  o.executor.jit_cache = "off";
  o.float32 = true;
  Engine engine(compiled, o);
  engine.bind_set(*compiled->find_extern("points"), points);
  engine.bind_set(*compiled->find_extern("springs"), springs);
  Solved out;
  for (int call = 0; call < 2; ++call) {
    std::vector<Value> results = engine.call(*compiled->find_func("solve"), {});
    EXPECT_EQ(results.at(1).as_int(), 9);
    out.x = results.at(0).tensor();
  }
  std::ostringstream os;
  engine.print_jit_stats(os);
  out.stats = os.str();
  return out;
}

class PairProducts : public testing::TestWithParam<int> {};

TEST_P(PairProducts, GiveTheInterpretersBits) {
  if (!api::jit_available()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  const int n = GetParam();
  const Solved in = solve(n, ExecutorKind::Interpreter, 1, false);
  ASSERT_EQ(in.x.size(), static_cast<size_t>(41 * n));
  for (int threads : {1, 3}) {
    const Solved jit = solve(n, ExecutorKind::Jit, threads, false);
    ASSERT_EQ(jit.x.size(), in.x.size());
    EXPECT_EQ(std::memcmp(jit.x.floats(), in.x.floats(), in.x.size() * sizeof(double)), 0)
        << "blocks of " << n << ", " << threads << " threads";
    // The loop ran compiled, on a copy without the zero blocks.
    EXPECT_NE(jit.stats.find("zero blocks dropped"), std::string::npos) << jit.stats;
    EXPECT_EQ(jit.stats.find("products stream 100.0%"), std::string::npos) << jit.stats;
    EXPECT_EQ(jit.stats.find("interpreted"), std::string::npos) << jit.stats;
  }
  EXPECT_NO_THROW(solve(n, ExecutorKind::Jit, 3, true));
}

INSTANTIATE_TEST_SUITE_P(Blocks, PairProducts, testing::Values(2, 3, 4));

}  // namespace
}  // namespace simit::jit
