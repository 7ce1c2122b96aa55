// Sums under --float32 compiled (docs/arithmetic.md): a map's assembled blocks, its dense
// products and a solver loop's products of 3 x 3 blocks add in binary32 steps, in binary32
// instructions where the operands are binary32 values, and give the interpreter's bits on 1
// and 3 threads (the later chunks' contributions kept apart and rounded as they join).
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
  x : vector[3](float);
  m : float;
end
element Spring
  k : float;
end
extern points : set{Point};
extern springs : set{Spring}(points, points);

% A spring's 3 x 3 block k (d d') / (d' d), where d is the spring's direction.
func spring_block(s : Spring, p : (Point * 2)) -> B : matrix[3,3](float)
  d = p(1).x - p(0).x;
  B = (s.k / (d' * d)) * (d * d');
end

% The springs' blocks, and their forces B d.
func stiffness(s : Spring, p : (Point * 2)) -> (K : matrix[points,points](matrix[3,3](float)),
                                                f : vector[points](vector[3](float)))
  B = spring_block(s, p);
  K(p(0), p(0)) = B;
  K(p(1), p(1)) = B;
  K(p(0), p(1)) = -B;
  K(p(1), p(0)) = -B;
  f(p(0)) = B * (p(1).x - p(0).x);
  f(p(1)) = -(B * (p(1).x - p(0).x));
end

% The springs' blocks alone.
func spring_blocks(s : Spring, p : (Point * 2)) -> K : matrix[points,points](matrix[3,3](float))
  B = spring_block(s, p);
  K(p(0), p(0)) = B;
  K(p(1), p(1)) = B;
  K(p(0), p(1)) = -B;
  K(p(1), p(0)) = -B;
end

func mass(q : Point) -> M : matrix[points,points](matrix[3,3](float))
  M(q, q) = q.m * [1.0, 0.0, 0.0; 0.0, 1.0, 0.0; 0.0, 0.0, 1.0];
end

% Twelve iterations of unpreconditioned CG from zero.
func cg12(A : matrix[points,points](matrix[3,3](float)), f : vector[points](vector[3](float)))
    -> (x : vector[points](vector[3](float)), iterations : int)
  var r = f;
  var p = r;
  var rr = dot(r, r);
  x = 0.0 * f;
  while (iterations < 12)
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

export func solve() -> (x : vector[points](vector[3](float)), f : vector[points](vector[3](float)),
                        iterations : int)
  K, f = map stiffness to springs reduce +;
  A = (map mass to points reduce +) + 0.01 * K;
  x, iterations = cg12(A, f);
end

export func assemble() -> (K : matrix[points,points](matrix[3,3](float)),
                           f : vector[points](vector[3](float)))
  K, f = map stiffness to springs reduce +;
end

export func solve_and_keep() -> (x : vector[points](vector[3](float)),
                                 f : vector[points](vector[3](float)),
                                 A : matrix[points,points](matrix[3,3](float)))
  G, f = map stiffness to springs reduce +;
  K = map spring_blocks to springs reduce +;
  M = map mass to points reduce +;
  A = M + 0.01 * K;
  x, iterations = cg12(A, f);
end
)";

struct Solved {
  std::vector<Value> results;
  std::string stats;
};

// A chain of 40 points with three springs each (i to i + 1, i + 2, i + 3); binary32 fields.
Solved solve(ExecutorKind kind, int threads, bool check, const char* func = "solve") {
  auto compiled = CompiledProgram::from_source("float32_sums.sim", kProgram);
  EXPECT_TRUE(compiled->ok());
  runtime::Set points("points");
  runtime::Set springs("springs", {&points, &points});
  const int n = 40;
  points.add_many(n);
  points.add_field("x", runtime::FieldType{runtime::ComponentKind::Float, {3}, true});
  points.add_field("m", runtime::FieldType{runtime::ComponentKind::Float, {}, true});
  for (int i = 0; i < n; ++i) {
    const double xyz[3] = {std::cos(0.7 * i) + 0.1 * i, std::sin(1.3 * i), 0.05 * i * i};
    runtime::Tensor t(runtime::ComponentKind::Float, runtime::Shape{3});
    for (int c = 0; c < 3; ++c) t.mutable_floats()[c] = xyz[c];
    points.set(0, i, t);
    runtime::Tensor m(runtime::ComponentKind::Float, runtime::Shape{});
    m.mutable_floats()[0] = 1.0 + 0.01 * i;
    points.set(1, i, m);
  }
  for (int i = 0; i < n; ++i)
    for (int j = 1; j <= 3; ++j)
      if (i + j < n) springs.add({i, i + j});
  springs.add_field("k", runtime::FieldType{runtime::ComponentKind::Float, {}, true});
  for (int e = 0; e < springs.size(); ++e) {
    runtime::Tensor k(runtime::ComponentKind::Float, runtime::Shape{});
    k.mutable_floats()[0] = 10.0 + std::sin(0.3 * e);
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
  for (int call = 0; call < 2; ++call) out.results = engine.call(*compiled->find_func(func), {});
  std::ostringstream os;
  engine.print_jit_stats(os);
  out.stats = os.str();
  return out;
}

bool same_bits(const runtime::Tensor& a, const runtime::Tensor& b) {
  return a.size() == b.size() &&
         std::memcmp(a.floats(), b.floats(), a.size() * sizeof(double)) == 0;
}

bool same_bits(const runtime::SystemMatrix& a, const runtime::SystemMatrix& b) {
  return a.value_count() == b.value_count() &&
         std::memcmp(a.values(), b.values(), a.value_count() * sizeof(double)) == 0;
}

TEST(Float32Sums, CompiledMapsAndLoopsGiveTheInterpretersBits) {
  if (!api::jit_available()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  const Solved in = solve(ExecutorKind::Interpreter, 1, false);
  for (int threads : {1, 3}) {
    const Solved jit = solve(ExecutorKind::Jit, threads, false);
    ASSERT_EQ(jit.results.size(), 3u);
    EXPECT_TRUE(same_bits(in.results[0].tensor(), jit.results[0].tensor())) << threads;
    EXPECT_TRUE(same_bits(in.results[1].tensor(), jit.results[1].tensor())) << threads;
    EXPECT_EQ(jit.results[2].as_int(), 12);
    // The maps and the statements with the loop compiled (its products on a binary32 copy).
    EXPECT_NE(jit.stats.find("stiffness (line 64)"), std::string::npos) << jit.stats;
    EXPECT_NE(jit.stats.find("statements (lines 46-59)"), std::string::npos) << jit.stats;
    // The copy in pairs of rows (PrunedMatrix::pairs): rows have 4, 5, 6, 7 (34 of them), 6, 5
    // and 4 blocks, so the 20 pairs hold 5 + 7 * 18 + 5 = 136 block pairs of 18 binary32
    // values (9,792 bytes, and 8 bytes of padding), 272 columns (1,088) and 21 pair starts
    // (84): 10,972 bytes, 10.7 KB.
    EXPECT_NE(jit.stats.find("its matrices 10.7 KB"), std::string::npos) << jit.stats;
    EXPECT_EQ(jit.stats.find("interpreted:"), std::string::npos) << jit.stats;
  }
  // --check-jit compares every compiled call with the interpreter's on the same inputs.
  EXPECT_NO_THROW(solve(ExecutorKind::Jit, 3, true));
  // Each component is a binary32 value.
  const runtime::Tensor& x = in.results[0].tensor();
  for (size_t i = 0; i < x.size(); ++i)
    EXPECT_EQ(static_cast<double>(static_cast<float>(x.floats()[i])), x.floats()[i]) << i;
}

// A compiled reduction's results come out as the kernel assembled them: the map's final
// binary32 rounding is left out (SiteCall::results_binary32), so each sum must have rounded
// at every addition, in place or as the later chunks' contributions join (3 threads).
TEST(Float32Sums, ACompiledReductionsResultsAreBinary32Values) {
  if (!api::jit_available()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  const Solved in = solve(ExecutorKind::Interpreter, 1, false, "assemble");
  ASSERT_EQ(in.results.size(), 2u);
  const runtime::SystemMatrix& k_in = *in.results[0].matrix();
  for (int threads : {1, 3}) {
    const Solved jit = solve(ExecutorKind::Jit, threads, false, "assemble");
    ASSERT_EQ(jit.results.size(), 2u);
    EXPECT_NE(jit.stats.find("stiffness (line 71)"), std::string::npos) << jit.stats;
    const runtime::SystemMatrix& k = *jit.results[0].matrix();
    EXPECT_TRUE(same_bits(k, k_in)) << threads;
    EXPECT_TRUE(same_bits(in.results[1].tensor(), jit.results[1].tensor())) << threads;
    for (size_t i = 0; i < k.value_count(); ++i)
      ASSERT_EQ(static_cast<double>(static_cast<float>(k.values()[i])), k.values()[i]) << i;
  }
}

// The fused sum A = M + 0.01 K is left pending (jit/pending_sums.h): the loop's binary32 copy
// sums each block as it reads it, and A, returned, has the sum written into it when the host
// reads it: the interpreter's bits either way, on 1 and 3 threads.
TEST(Float32Sums, APendingSumIsSummedByTheLoopAndWrittenWhenTheHostReadsIt) {
  if (!api::jit_available()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  const Solved in = solve(ExecutorKind::Interpreter, 1, false, "solve_and_keep");
  ASSERT_EQ(in.results.size(), 3u);
  const runtime::SystemMatrix& a_in = *in.results[2].matrix();
  for (int threads : {1, 3}) {
    const Solved jit = solve(ExecutorKind::Jit, threads, false, "solve_and_keep");
    ASSERT_EQ(jit.results.size(), 3u);
    EXPECT_TRUE(same_bits(in.results[0].tensor(), jit.results[0].tensor())) << threads;
    EXPECT_TRUE(same_bits(in.results[1].tensor(), jit.results[1].tensor())) << threads;
    EXPECT_TRUE(same_bits(*jit.results[2].matrix(), a_in)) << threads;
    // Both calls left the sum pending, and each call's A was written whole when returned.
    EXPECT_NE(jit.stats.find("2 calls summed where a solver loop's binary32 copy reads them (of "
                             "all fused sums, 2 of 2 written whole for another reader)"),
              std::string::npos)
        << jit.stats;
  }
}

// A map's float argument: the kernel reads it as a binary32 value, so a host-bound one that
// is wider (0.1 in binary64) leaves the call to the interpreter, which multiplies by it as it
// is; a binary32 one (0.5) runs compiled.
const char* kScaled = R"(
element Point
  x : float;
end
extern points : set{Point};
extern s : float;

func scale(c : float, p : Point) -> y : vector[points](float)
  y(p) = c * p.x;
end

export func run() -> y : vector[points](float)
  y = map scale(s) to points reduce +;
end
)";

std::pair<runtime::Tensor, std::string> scaled(ExecutorKind kind, double s) {
  auto compiled = CompiledProgram::from_source("float32_scaled.sim", kScaled);
  EXPECT_TRUE(compiled->ok());
  runtime::Set points("points");
  points.add_many(6);
  points.add_field("x", runtime::FieldType{runtime::ComponentKind::Float, {}, true});
  for (int i = 0; i < 6; ++i) {
    runtime::Tensor x(runtime::ComponentKind::Float, runtime::Shape{});
    x.mutable_floats()[0] = 1.0 + 0.3 * i;
    points.set(0, i, x);
  }
  EngineOptions o;
  o.executor.kind = kind;
  o.executor.threshold = 0;
  o.executor.jit_cache = "off";
  o.float32 = true;
  Engine engine(compiled, o);
  engine.bind_set(*compiled->find_extern("points"), points);
  engine.set_global(*compiled->find_extern("s"), Value::of_float(s));
  runtime::Tensor y = engine.call(*compiled->find_func("run"), {})[0].tensor();
  std::ostringstream os;
  engine.print_jit_stats(os);
  return {y, os.str()};
}

TEST(Float32Sums, AWiderFloatArgumentRunsTheMapInterpreted) {
  if (!api::jit_available()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  const char* note = "calls with a float argument that is not a binary32 value run interpreted";
  for (double s : {0.1, 0.5}) {
    const auto [in, unused] = scaled(ExecutorKind::Interpreter, s);
    const auto [jit, stats] = scaled(ExecutorKind::Jit, s);
    EXPECT_TRUE(same_bits(in, jit)) << s;
    EXPECT_EQ(stats.find(note) != std::string::npos, s == 0.1) << stats;
    // 0.1 as it is, times x, rounded once: not (float)0.1 times x.
    const double x1 = static_cast<float>(1.3);
    EXPECT_EQ(in.floats()[1], static_cast<double>(static_cast<float>(s * x1))) << s;
  }
}

}  // namespace
}  // namespace simit::jit
