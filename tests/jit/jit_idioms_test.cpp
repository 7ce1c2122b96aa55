// Idioms of ordinary Simit programs under the JIT, each against the interpreter bit for bit
// and against values computed by hand: scalar-broadcast declarations in mapped functions,
// sets of no elements, `mod` and integer division, a direct solve of a matrix the JIT
// specialises (also under --check-jit), a product written into its own operand and call
// chains deeper than the old inlining limit.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <sstream>
#include <string>
#include <vector>

#include "api/engine.h"
#include "interp/runtime_error.h"

namespace simit::jit {
namespace {

using api::CompiledProgram;
using api::Engine;
using api::EngineOptions;
using api::ExecutorKind;
using interp::Value;

// A program over `verts` (x, y : vector[3](float); k : int) and `edges` between them, run
// through `step` for some frames.
struct IdiomRun {
  std::vector<Value> results;
  std::vector<double> y;   // verts.y after the last frame
  std::vector<int32_t> m;  // verts.m after the last frame
  std::string stats;
  std::string error;  // the run-time error, if the run stopped
};

IdiomRun run(const std::string& source, ExecutorKind kind, int verts, std::vector<int32_t> ends,
             int frames = 3, bool check = false) {
  auto compiled = CompiledProgram::from_source("idioms.sim", source);
  EXPECT_TRUE(compiled->ok());
  runtime::Set v("verts");
  runtime::Set e("edges", {&v, &v});
  v.add_many(verts);
  using runtime::ComponentKind;
  v.add_field("x", runtime::FieldType{ComponentKind::Float, {3}, false});
  v.add_field("y", runtime::FieldType{ComponentKind::Float, {3}, false});
  v.add_field("k", runtime::FieldType{ComponentKind::Int, {}, false});
  v.add_field("m", runtime::FieldType{ComponentKind::Int, {3}, false});
  for (int i = 0; i < verts; ++i) {
    for (int c = 0; c < 3; ++c) v.field(0).at<double>(i)[c] = 0.3 + 0.7 * i - 0.11 * c * c;
    v.field(2).at<int32_t>(i)[0] = 5 * i - 7;  // negative and positive dividends
  }
  e.add_edges(ends);
  EngineOptions o;
  o.executor.kind = kind;
  o.executor.threshold = 0;
  o.executor.check = check;
  Engine engine(compiled, o);
  engine.bind_set(*compiled->find_extern("verts"), v);
  engine.bind_set(*compiled->find_extern("edges"), e);
  IdiomRun r;
  try {
    for (int f = 0; f < frames; ++f) r.results = engine.call(*compiled->find_func("step"), {});
  } catch (const interp::RuntimeError& err) {
    r.error = err.what();
  }
  r.y.assign(v.field(1).data<double>(), v.field(1).data<double>() + 3 * verts);
  r.m.assign(v.field(3).data<int32_t>(), v.field(3).data<int32_t>() + 3 * verts);
  std::ostringstream os;
  engine.print_jit_stats(os);
  r.stats = os.str();
  return r;
}

void expect_same_bits(const std::vector<double>& a, const std::vector<double>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i)
    EXPECT_EQ(std::memcmp(&a[i], &b[i], sizeof(double)), 0) << i << ": " << a[i] << " vs " << b[i];
}

std::vector<double> floats(const Value& v) {
  if (v.kind() == Value::Kind::Float) return {v.as_float()};
  return {v.tensor().floats(), v.tensor().floats() + v.tensor().size()};
}

// Lines of --jit-stats that name a site and do not say "compiled".
std::string not_compiled(const std::string& stats) {
  std::istringstream in(stats);
  std::string line, out;
  while (std::getline(in, line))
    if (line.find("(line") != std::string::npos && line.find(" compiled") == std::string::npos)
      out += line + "\n";
  return out;
}

const std::vector<int32_t> kEdges = {0, 1, 1, 2, 2, 3, 3, 0};

// The sets every program here runs on (the fields run() makes).
const std::string kPrelude = R"(
element V
  x : vector[3](float);
  y : vector[3](float);
  k : int;
  m : vector[3](int);
end
element E
end
extern verts : set{V};
extern edges : set{E}(verts, verts);
)";

const std::string kBroadcast = kPrelude + R"(
func ones_times(x : vector[3](float)) -> r : vector[3](float)
  const c : vector[3](float) = 0.5;
  var E : matrix[3,3](float) = 1.0;
  r = E * x + c;
end

func f(e : E, p : (V * 2)) -> F : vector[verts](vector[3](float))
  var E : matrix[3,3](float) = 1.0;
  var w : vector[3](float) = 2.0;
  var one : vector[1](float) = 3.0;
  var D : matrix[3,3](float) = 0.0;
  D(0, 1) = 4.0;
  var z : vector[3](float) = 7.0;
  z = 0.25;
  F(p(0)) = E * p(1).x + norm(w) * w + E' * p(0).x;
  F(p(1)) = D * p(0).x + one(0) * z + ones_times(p(1).x) + (E .* E) * w;
end

export func step() -> n : float
  F = map f to edges reduce +;
  verts.y = F;
  var w : vector[3](float) = 2.0;
  n = norm(w);
end
)";

// `var E : matrix[3,3](float) = 1.0` is the all-ones matrix: E * x sums x's components.
TEST(JitIdioms, ScalarBroadcastDeclarationsFillEveryComponent) {
  if (!api::jit_available()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  const IdiomRun in = run(kBroadcast, ExecutorKind::Interpreter, 4, kEdges);
  const IdiomRun jit = run(kBroadcast, ExecutorKind::Jit, 4, kEdges);
  ASSERT_EQ(in.error, "");
  ASSERT_EQ(jit.error, "");
  expect_same_bits(in.y, jit.y);
  EXPECT_EQ(not_compiled(jit.stats), "") << jit.stats;
  // By hand: vertex 0 is p(0) of edge 0 (0 -> 1) and p(1) of edge 3 (3 -> 0).
  auto x = [](int i, int c) { return 0.3 + 0.7 * i - 0.11 * c * c; };
  auto sum = [&](int i) { return x(i, 0) + x(i, 1) + x(i, 2); };
  const double nw = std::sqrt(12.0);
  for (int c = 0; c < 3; ++c) {
    const double from_edge0 = sum(1) + nw * 2.0 + sum(0);
    const double d = c == 0 ? 4.0 * x(3, 1) : 0.0;
    const double from_edge3 = d + 3.0 * 0.25 + (sum(0) + 0.5) + 6.0;
    EXPECT_NEAR(jit.y[c], from_edge0 + from_edge3, 1e-12) << c;
  }
  EXPECT_NEAR(jit.results[0].as_float(), nw, 1e-15);
}

const std::string kEmpty = kPrelude + R"(
func spring(e : E, p : (V * 2)) -> (A : matrix[verts,verts](matrix[3,3](float)),
                                    F : vector[verts](vector[3](float)))
  var K : matrix[3,3](float) = 1.0;
  A(p(0), p(1)) = K;
  A(p(0), p(0)) = K;
  F(p(0)) = p(1).x;
end

export func step() -> (d : float, n : int)
  A, F = map spring to edges reduce +;
  verts.y = A * verts.x;
  var z : vector[verts](vector[3](float)) = verts.x;
  z = z + F;
  var r = z - verts.y;
  var rr = r' * r;
  n = 0;
  while rr > 1e-30 and n < 3
    r = 0.5 * r;
    rr = r' * r;
    n = n + 1;
  end
  d = rr;
end
)";

// Maps and system statements over sets of no elements run and give empty results.
TEST(JitIdioms, SetsOfNoElementsRun) {
  if (!api::jit_available()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  for (int verts : {0, 3}) {
    const std::vector<int32_t> ends = verts ? std::vector<int32_t>{} : std::vector<int32_t>{};
    const IdiomRun in = run(kEmpty, ExecutorKind::Interpreter, verts, ends);
    for (bool check : {false, true}) {
      const IdiomRun jit = run(kEmpty, ExecutorKind::Jit, verts, ends, 3, check);
      ASSERT_EQ(in.error, "");
      ASSERT_EQ(jit.error, "") << check;
      expect_same_bits(in.y, jit.y);
      EXPECT_EQ(jit.results[0].as_float(), in.results[0].as_float());
      EXPECT_EQ(jit.results[1].as_int(), in.results[1].as_int());
    }
  }
  const IdiomRun none = run(kEmpty, ExecutorKind::Jit, 0, {});
  EXPECT_EQ(none.results[0].as_float(), 0.0);
  EXPECT_EQ(none.results[1].as_int(), 0);  // an empty sum is 0: the loop does not run
}

const std::string kModDiv = kPrelude + R"(
func f(e : E, p : (V * 2)) -> F : vector[verts](vector[3](float))
  for k in 0:3
    F(p(0))(k) = p(1).x(mod(k + 1, 3)) - p(0).x(mod(k + 2, 3));
  end
end

func g(inout v : V)
  var a = v.k;
  v.m(0) = mod(a, 3) + 10 * (a / 4);
  v.m(1) = mod(a, -3) + 10 * (-a / 3);
  v.m(2) = (a * 3) / (a - 2 * a + a + 3) + mod(a, a + 100);
end

export func step()
  verts.y = map f to edges reduce +;
  apply g to verts;
end
)";

int c_mod(int a, int b) { return b == -1 ? 0 : a % b; }

TEST(JitIdioms, ModAndIntegerDivisionCompileWithTheInterpretersValues) {
  if (!api::jit_available()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  const IdiomRun in = run(kModDiv, ExecutorKind::Interpreter, 4, kEdges);
  const IdiomRun jit = run(kModDiv, ExecutorKind::Jit, 4, kEdges);
  ASSERT_EQ(in.error, "");
  ASSERT_EQ(jit.error, "");
  expect_same_bits(in.y, jit.y);
  EXPECT_EQ(not_compiled(jit.stats), "") << jit.stats;
  // Vertex 1 is p(0) of edge 1 (1 -> 2) only.
  auto x = [](int i, int c) { return 0.3 + 0.7 * i - 0.11 * c * c; };
  for (int k = 0; k < 3; ++k) EXPECT_EQ(jit.y[3 + k], x(2, (k + 1) % 3) - x(1, (k + 2) % 3)) << k;
  for (int i = 0; i < 4; ++i) {
    const int a = 5 * i - 7;  // -7, -2, 3, 8
    EXPECT_EQ(jit.m[3 * i + 0], c_mod(a, 3) + 10 * (a / 4)) << i;
    EXPECT_EQ(jit.m[3 * i + 1], c_mod(a, -3) + 10 * (-a / 3)) << i;
    EXPECT_EQ(jit.m[3 * i + 2], (a * 3) / 3 + c_mod(a, a + 100)) << i;
    for (int c = 0; c < 3; ++c) EXPECT_EQ(jit.m[3 * i + c], in.m[3 * i + c]) << i;
  }
  EXPECT_EQ(-7 % 3, -1);  // the sign follows the dividend, as LANGUAGE.md says
}

const std::string kDivZero = kPrelude + R"(
func f(e : E, p : (V * 2)) -> F : vector[verts](vector[3](float))
  if p(0).k / (p(1).k - 3) > 0
    F(p(0)) = p(1).x;
  end
  if mod(p(1).k, p(0).k + 2) == 1
    F(p(1)) = p(0).x;
  end
end

export func step()
  verts.y = map f to edges reduce +;
end
)";

// k = 5i - 7 (-7, -2, 3, 8): p(1).k - 3 is 0 for p(1) = vertex 2 (edge 1 -> 2), and
// p(0).k + 2 for p(0) = vertex 1 (the same edge), so integer division by zero stops the run at
// edge 1, before its mod, in the interpreter's words.
TEST(JitIdioms, ADivisionByZeroIsReportedAsTheInterpreterReportsIt) {
  if (!api::jit_available()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  const IdiomRun in = run(kDivZero, ExecutorKind::Interpreter, 4, kEdges, 1);
  const IdiomRun jit = run(kDivZero, ExecutorKind::Jit, 4, kEdges, 1);
  EXPECT_NE(in.error.find("integer division by zero"), std::string::npos) << in.error;
  EXPECT_EQ(jit.error, in.error);
}

const std::string kSolve = kPrelude + R"(
func stiffness(e : E, p : (V * 2)) -> A : matrix[verts,verts](matrix[3,3](float))
  var K : matrix[3,3](float) = 0.0;
  const s = 1.0 + 0.1 * norm(p(0).x - p(1).x);
  K(0, 0) = s;
  K(1, 1) = 2.0 * s;
  K(2, 2) = 3.0 * s;
  K(0, 1) = 0.1 * s;
  K(1, 0) = 0.1 * s;
  A(p(0), p(0)) = K;
  A(p(1), p(1)) = K;
  % the vertices below 14 are pinned (k = 5i - 7): no coupling block touches them
  if p(0).k > 60 and p(1).k > 60
    A(p(0), p(1)) = -0.3 * K;
    A(p(1), p(0)) = -0.3 * K;
  end
end

export func step()
  A = map stiffness to edges reduce +;
  verts.y = A \ (verts.x + verts.y);
end
)";

// The JIT assembles A on the blocks its map writes (none that touches a vertex below 14);
// the solve sees the same nonzeros as the interpreter's full pattern and gives its bits, on
// every frame, and --check-jit runs the specialised matrix too.
TEST(JitIdioms, ADirectSolveOfASpecialisedMatrixGivesTheInterpretersBits) {
  if (!api::jit_available()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  std::vector<int32_t> ends;
  const int n = 30;
  for (int i = 0; i + 1 < n; ++i) ends.insert(ends.end(), {i, i + 1});
  for (int i = 0; i + 5 < n; i += 3) ends.insert(ends.end(), {i, i + 5});
  const IdiomRun in = run(kSolve, ExecutorKind::Interpreter, n, ends, 10);
  ASSERT_EQ(in.error, "");
  for (bool check : {false, true}) {
    const IdiomRun jit = run(kSolve, ExecutorKind::Jit, n, ends, 10, check);
    ASSERT_EQ(jit.error, "") << check;
    expect_same_bits(in.y, jit.y);
    EXPECT_NE(jit.stats.find("specialised to"), std::string::npos) << jit.stats;
  }
}

const std::string kOwnOperand = kPrelude + R"(
func stiffness(e : E, p : (V * 2)) -> A : matrix[verts,verts](matrix[3,3](float))
  var K : matrix[3,3](float) = 0.25;
  A(p(0), p(0)) = K;
  A(p(0), p(1)) = 0.5 * K;
end

export func step() -> r : float
  A = map stiffness to edges reduce +;
  var x = verts.x;
  var i = 0;
  while i < 4
    x = A * x;
    verts.y = A * verts.y + x;
    i = i + 1;
  end
  r = x' * x;
end
)";

// `x = A * x` reads all of x for each row: the product goes through a scratch vector.
TEST(JitIdioms, AProductWrittenIntoItsOwnOperandCompiles) {
  if (!api::jit_available()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  const IdiomRun in = run(kOwnOperand, ExecutorKind::Interpreter, 4, kEdges, 2);
  const IdiomRun jit = run(kOwnOperand, ExecutorKind::Jit, 4, kEdges, 2);
  ASSERT_EQ(jit.error, "");
  expect_same_bits(in.y, jit.y);
  expect_same_bits(floats(in.results[0]), floats(jit.results[0]));
  EXPECT_EQ(jit.stats.find("own operand"), std::string::npos) << jit.stats;
  EXPECT_NE(jit.stats.find("statements (lines"), std::string::npos) << jit.stats;
  EXPECT_EQ(not_compiled(jit.stats), "") << jit.stats;
}

const std::string kLoneProduct = kPrelude + R"(
func stiffness(e : E, p : (V * 2)) -> A : matrix[verts,verts](matrix[3,3](float))
  var K : matrix[3,3](float) = 0.0;
  K(0, 0) = norm(p(0).x - p(1).x);
  K(1, 2) = 0.5;
  A(p(0), p(0)) = K;
  A(p(0), p(1)) = -K;
end

export func step() -> r : float
  A = map stiffness to edges reduce +;
  verts.y = 0.5 * verts.y + A * verts.x;
  r = norm(A * verts.y - verts.x) / norm(verts.x);
end
)";

// Products outside a loop read the matrix in place (no copy), with the interpreter's bits.
TEST(JitIdioms, ProductsOutsideALoopCompileAndReadTheMatrixInPlace) {
  if (!api::jit_available()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  for (bool check : {false, true}) {
    const IdiomRun in = run(kLoneProduct, ExecutorKind::Interpreter, 4, kEdges, 3);
    const IdiomRun jit = run(kLoneProduct, ExecutorKind::Jit, 4, kEdges, 3, check);
    ASSERT_EQ(jit.error, "");
    expect_same_bits(in.y, jit.y);
    expect_same_bits(floats(in.results[0]), floats(jit.results[0]));
    EXPECT_NE(jit.stats.find("statements (lines 23-24)"), std::string::npos) << jit.stats;
    EXPECT_EQ(not_compiled(jit.stats), "") << jit.stats;
    EXPECT_EQ(jit.stats.find("products stream"), std::string::npos) << jit.stats;  // no copy
    EXPECT_GT(in.results[0].as_float(), 0.0);
  }
}

// `mod` and integer division among a solver loop's scalars; with zero = 1 the divisor
// reaches 0 on the fourth iteration.
std::string loop_division_program(int zero) {
  return kPrelude + R"(
export func step() -> (k : int, q : int)
  var x = verts.x;
  k = 0;
  q = 0;
  while k < 6
    x = 0.5 * x + verts.x;
    q = q + mod(k * 7 - 11, 4) + (k - 9) / (4 - )" +
         std::to_string(zero) + R"( * k);
    k = k + 1;
  end
  verts.y = x;
end
)";
}

TEST(JitIdioms, ModAndIntegerDivisionInASolverLoopCompile) {
  if (!api::jit_available()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  const std::string source = loop_division_program(0);
  const IdiomRun in = run(source, ExecutorKind::Interpreter, 4, kEdges, 2);
  const IdiomRun jit = run(source, ExecutorKind::Jit, 4, kEdges, 2);
  ASSERT_EQ(jit.error, "");
  expect_same_bits(in.y, jit.y);
  EXPECT_EQ(not_compiled(jit.stats), "") << jit.stats;
  EXPECT_NE(jit.stats.find("statements (lines"), std::string::npos) << jit.stats;
  int q = 0;
  for (int k = 0; k < 6; ++k) q += (k * 7 - 11) % 4 + (k - 9) / 4;
  EXPECT_EQ(jit.results[1].as_int(), q);
  EXPECT_EQ(in.results[1].as_int(), q);
  // A zero divisor hands the loop back: the interpreter reports it.
  const std::string zero = loop_division_program(1);
  const IdiomRun in0 = run(zero, ExecutorKind::Interpreter, 4, kEdges, 1);
  const IdiomRun jit0 = run(zero, ExecutorKind::Jit, 4, kEdges, 1);
  EXPECT_NE(in0.error.find("integer division by zero"), std::string::npos) << in0.error;
  EXPECT_EQ(jit0.error, in0.error);
}

// f0 calls f1 ... calls f39: 40 levels, past the old limit of 32.
std::string deep_chain_program() {
  std::string s = kPrelude + R"(
func f40(x : float) -> r : float
  r = x;
end
)";
  for (int i = 39; i >= 0; --i)
    s += "func f" + std::to_string(i) + "(x : float) -> r : float\n  r = f" +
         std::to_string(i + 1) + "(x) + 1.0;\nend\n";
  s += R"(
func g(e : E, p : (V * 2)) -> F : vector[verts](vector[3](float))
  F(p(0)) = f0(p(1).x(0)) * p(0).x;
end

export func step()
  verts.y = map g to edges reduce +;
end
)";
  return s;
}

TEST(JitIdioms, CallChainsDeeperThanThirtyTwoAreInlined) {
  if (!api::jit_available()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  const std::string source = deep_chain_program();
  const IdiomRun in = run(source, ExecutorKind::Interpreter, 4, kEdges, 1);
  const IdiomRun jit = run(source, ExecutorKind::Jit, 4, kEdges, 1);
  ASSERT_EQ(jit.error, "");
  expect_same_bits(in.y, jit.y);
  EXPECT_EQ(not_compiled(jit.stats), "") << jit.stats;
  // Vertex 0 is p(0) of edge 0 only: (x(1, 0) + 40) * x(0).
  EXPECT_NEAR(jit.y[0], (0.3 + 0.7 + 40.0) * 0.3, 1e-12);
}

}  // namespace
}  // namespace simit::jit
