// A compiled solver loop under --float32 (docs/jit.md): its matrix and the vectors that only
// hold binary32 values are binary32 arrays in the kernel, a vector copied from a binary64
// field stays binary64, and a vector the host bound with wider values leaves the call to the
// interpreter; the interpreter's bits every time.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <sstream>

#include "api/engine.h"

namespace simit::jit {
namespace {

using api::CompiledProgram;
using api::Engine;
using api::EngineOptions;
using api::ExecutorKind;
using interp::Value;

const char* kProgram = R"(
element Point
  b : float;
  d : float;
end
element Link
  k : float;
end
extern points : set{Point};
extern links : set{Link}(points, points);
extern guess : vector[points](float);

func stiffness(l : Link, p : (Point * 2)) -> A : matrix[points,points](float)
  A(p(0), p(0)) = l.k;
  A(p(1), p(1)) = l.k;
  A(p(0), p(1)) = -0.5 * l.k;
  A(p(1), p(0)) = -0.5 * l.k;
end

func diagonal(q : Point) -> D : matrix[points,points](float)
  D(q, q) = q.d;
end

func cg(A : matrix[points,points](float), b : vector[points](float),
        x0 : vector[points](float)) -> (x : vector[points](float), iterations : int)
  x = x0;
  var r = b - A * x;
  var p = r;
  var rr = r' * r;
  while (rr > 1e-12) and (iterations < 30)
    Ap = A * p;
    alpha = rr / (p' * Ap);
    x = x + alpha * p;
    r = r - alpha * Ap;
    rr_new = r' * r;
    p = r + (rr_new / rr) * p;
    rr = rr_new;
    iterations = iterations + 1;
  end
end

export func solve() -> (x : vector[points](float), iterations : int)
  A = (map stiffness to links reduce +) + (map diagonal to points reduce +);
  x, iterations = cg(A, points.b, 0.25 * points.b);
end

export func solve_from_guess() -> (x : vector[points](float), iterations : int)
  A = (map stiffness to links reduce +) + (map diagonal to points reduce +);
  var r = points.b - A * guess;
  var p = r;
  var rr = r' * r;
  while (rr > 1e-12) and (iterations < 30)
    Ap = A * p;
    alpha = rr / (p' * Ap);
    guess = guess + alpha * p;
    r = r - alpha * Ap;
    rr_new = r' * r;
    p = r + (rr_new / rr) * p;
    rr = rr_new;
    iterations = iterations + 1;
  end
  x = guess;
end
)";

struct Solved {
  std::vector<Value> results;
  std::string stats, dump;
};

// The points' fields in binary64 storage, whose values (sin(0.3 i)) are not binary32 values:
// the program reads them without rounding them. `guess`: 0.1 per point (binary64).
Solved solve(ExecutorKind kind, bool check, const char* func) {
  auto compiled = CompiledProgram::from_source("float32_cg.sim", kProgram);
  EXPECT_TRUE(compiled->ok());
  runtime::Set points("points");
  runtime::Set links("links", {&points, &points});
  const int n = 30;
  points.add_many(n);
  for (const char* f : {"b", "d"})
    points.add_field(f, runtime::FieldType{runtime::ComponentKind::Float, {}, false});
  for (int i = 0; i < n; ++i) {
    points.field(0).at<double>(i)[0] = std::sin(0.3 * i);
    points.field(1).at<double>(i)[0] = 0.1 + 0.01 * i;
    if (i + 1 < n) links.add({i, i + 1});
  }
  links.add_field("k", runtime::FieldType{runtime::ComponentKind::Float, {}, false});
  for (int e = 0; e < links.size(); ++e) links.field(0).at<double>(e)[0] = 1.0 + 0.5 * std::cos(e);
  EngineOptions o;
  o.executor.kind = kind;
  o.float32 = true;
  o.executor.threshold = 0;
  o.executor.check = check;
  std::ostringstream dump;
  o.dump = &dump;
  o.executor.dump_loop_ir = true;
  Engine engine(compiled, o);
  engine.bind_set(*compiled->find_extern("points"), points);
  engine.bind_set(*compiled->find_extern("links"), links);
  runtime::Tensor guess(runtime::ComponentKind::Float, runtime::Shape{n});
  for (int i = 0; i < n; ++i) guess.mutable_floats()[i] = 0.1;
  engine.set_global(*compiled->find_extern("guess"), Value::of_tensor(guess));
  Solved out;
  for (int call = 0; call < 2; ++call) out.results = engine.call(*compiled->find_func(func), {});
  std::ostringstream os;
  engine.print_jit_stats(os);
  out.stats = os.str();
  out.dump = dump.str();
  return out;
}

void expect_same_bits(const Solved& a, const Solved& b) {
  ASSERT_EQ(a.results.size(), b.results.size());
  const runtime::Tensor &x = a.results[0].tensor(), &y = b.results[0].tensor();
  ASSERT_EQ(x.size(), y.size());
  EXPECT_EQ(std::memcmp(x.floats(), y.floats(), x.size() * sizeof(double)), 0);
  EXPECT_EQ(a.results[1].as_int(), b.results[1].as_int());
}

TEST(Float32Solver, BinaryThirtyTwoArraysWhereEveryValueIsOne) {
  if (!api::jit_available()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  const Solved in = solve(ExecutorKind::Interpreter, false, "solve");
  const Solved jit = solve(ExecutorKind::Jit, false, "solve");
  const Solved checked = solve(ExecutorKind::Jit, true, "solve");
  expect_same_bits(in, jit);
  expect_same_bits(in, checked);
  EXPECT_GT(in.results[1].as_int(), 3);
  // Every value the loop stores is rounded: x, r, Ap and the matrix are binary32; b and x0,
  // which it only reads, are the binary64 field `points.b` as it is (the interpreter does not
  // round a read either) and 0.25 * b, as the caller made them. p, which the loop's product
  // multiplies, is binary32 too: the product's sums are binary32 steps.
  for (const char* a : {"A.values f32", " x f32", " r f32", " p f32", " Ap f32", " b f64"})
    EXPECT_NE(jit.dump.find(a), std::string::npos) << a << "\n" << jit.dump;
  // One iteration's bytes (jit/loop_traffic.h): the product reads the matrix's copy (88
  // binary32 values, 88 column indices, 31 row starts: 828 bytes) and p (30 binary32
  // values, 120 bytes) and writes Ap (120); the next pass reads x, p, r and Ap and writes x
  // and r (720); the last reads r and p and writes p (360). The loop ran `iterations` times
  // in each of the two calls.
  EXPECT_NE(jit.stats.find("an iteration moves 2148 bytes (its matrices 828 bytes); " +
                           std::to_string(2 * in.results[1].as_int()) + " iterations at "),
            std::string::npos)
      << jit.stats << jit.dump;
  // Each component of the result is a binary32 value.
  const runtime::Tensor& x = jit.results[0].tensor();
  for (size_t i = 0; i < x.size(); ++i)
    EXPECT_EQ(static_cast<double>(static_cast<float>(x.floats()[i])), x.floats()[i]) << i;
}

TEST(Float32Solver, AWiderVectorTheHostBoundRunsInterpreted) {
  if (!api::jit_available()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  const Solved in = solve(ExecutorKind::Interpreter, false, "solve_from_guess");
  const Solved jit = solve(ExecutorKind::Jit, false, "solve_from_guess");
  expect_same_bits(in, jit);
  // The loop writes `guess`, whose values (0.1 in binary64) it reads first: a binary32 copy
  // could not hold them. That call ran interpreted; the next found binary32 values there.
  EXPECT_NE(jit.stats.find("1 call ran interpreted: a matrix or vector held values that are not "
                           "binary32"),
            std::string::npos)
      << jit.stats;
}

}  // namespace
}  // namespace simit::jit
