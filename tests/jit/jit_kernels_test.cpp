// The tracing JIT against the interpreter, on larger kernels: products too large to unroll,
// large tensors as loops, a solver loop fused into three loops, compiled finite checks, and
// errors reported in the interpreter's words.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <future>
#include <limits>
#include <sstream>
#include <thread>

#include "api/engine.h"
#include "jit/tunables.h"
#include "jit_test_support.h"

namespace simit::jit {
namespace {

using namespace test_support;  // also ast, Value and the engine API's names

// A program whose `step` maps over a set `points` of `count` elements, whose fields `fill`
// adds, run interpreted and then by the JIT at threshold 0: both runs' results, the JIT's
// loop-IR dump and its stats.
struct PointsRuns {
  std::vector<Value> results[2];
  std::string dump, stats;
};
PointsRuns run_points_both_ways(const char* file, const char* program, int count,
                                const std::function<void(runtime::Set&)>& fill) {
  PointsRuns out;
  for (int k = 0; k < 2; ++k) {
    auto compiled = CompiledProgram::from_source(file, program);
    EXPECT_TRUE(compiled->ok());
    if (!compiled->ok()) return out;
    runtime::Set points("points");
    points.add_many(count);
    fill(points);
    std::ostringstream dumped;
    EngineOptions o;
    o.executor.kind = k ? ExecutorKind::Jit : ExecutorKind::Interpreter;
    o.executor.threshold = 0;
    o.dump = &dumped;
    o.executor.dump_loop_ir = true;
    Engine engine(compiled, o);
    engine.bind_set(*compiled->find_extern("points"), points);
    out.results[k] = engine.call(*compiled->find_func("step"), {});
    std::ostringstream os;
    engine.print_jit_stats(os);
    if (k) out.stats = os.str(), out.dump = dumped.str();
  }
  return out;
}

// The loops (For statements) of a loop-IR dump.
size_t count_loops(const std::string& dump) {
  size_t loops = 0;
  for (size_t at = dump.find("for %"); at != std::string::npos; at = dump.find("for %", at + 1))
    ++loops;
  return loops;
}

// Products too large to unroll run as loops over tiles of scratch arrays: a 26 x 7 by 7 x 13
// product (tiles of 2 x 1: the largest extents up to 12 that divide 26 and 13), in one branch
// of an if, or its transpose's transpose in the other (the same bits: each term is a
// product of the same two factors), then P'P, 0.5 * Q + Q and zeros plus that as loops over
// the arrays (169 components), minus an unrolled diagonal matrix (put into an array beside
// them), and that matrix, and its transpose, times a vector. Each component
// is summed from +0.0 in ascending k like the interpreter's, so the bits equal both the
// interpreter's and a plain C++ loop's.
TEST(Jit, ProductsTooLargeToUnrollRunTiledWithTheInterpretersBits) {
  if (!api::jit_available()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  const char* program = R"(
element Point
  a : float;
end
extern points : set{Point};
func tiles(p : Point) -> r : vector[points](vector[6](float))
  var L : matrix[26,7](float);
  var R : matrix[7,13](float);
  var w = 0.0;
  for i in 0:26
    for k in 0:7
      w = w + 0.37;
      L(i, k) = sin(w) * p.a;
    end
  end
  for k in 0:7
    for j in 0:13
      w = w - 0.29;
      R(k, j) = cos(w) + p.a;
    end
  end
  var P : matrix[26,13](float);
  if p.a > 0.0
    P = L * R;
  else
    P = (R' * L')';
  end
  Q = P' * P;
  S = 0.5 * Q + Q;
  var D : matrix[13,13](float);
  for i in 0:13
    D(i, i) = p.a;
  end
  var Z : matrix[13,13](float);
  Z = Z + (S - D);
  var x : vector[13](float);
  for k in 0:13
    x(k) = R(3, k) - p.a;
  end
  y = Z * x;
  u = Z' * x;
  var v : vector[6](float);
  v(0) = P(25, 12);
  v(1) = P(3, 7);
  v(2) = Q(12, 12);
  v(3) = Z(0, 5);
  v(4) = y(11);
  v(5) = u(4);
  r(p) = v;
end
export func step() -> r : vector[points](vector[6](float))
  r = map tiles to points;
end
)";
  const double as[] = {0.5, -1.25, 3.0};
  const auto [results, dump, stats] =
      run_points_both_ways("tiles.sim", program, 3, [&](runtime::Set& points) {
        points.add_field("a", runtime::FieldType{runtime::ComponentKind::Float, {}, false});
        for (int i = 0; i < 3; ++i) points.field(0).at<double>(i)[0] = as[i];
      });
  EXPECT_NE(stats.find("tiles (line " + std::to_string(line_of(program, "map tiles")) + ")"),
            std::string::npos)
      << stats;
  EXPECT_EQ(stats.find("interpreted"), std::string::npos) << stats;
  // Four loops per product (tiles down, tiles across, a tile's rows, k), one per element-wise
  // operation (S - D, D put into an array; Z + (S - D) too: Z's zeros are one value for every
  // component) and one per matrix-vector product (Z * x, and Z' * x reading Z's array
  // transposed).
  EXPECT_EQ(count_loops(dump), 4u * 3u + 4u + 2u) << dump;
  expect_same(results[0][0], results[1][0], "r");
  // The reference: the same sums in plain C++.
  for (int e = 0; e < 3; ++e) {
    double L[26][7], R[7][13], P[26][13], Q[13][13], w = 0.0;
    for (auto& row : L)
      for (double& x : row) w = w + 0.37, x = std::sin(w) * as[e];
    for (auto& row : R)
      for (double& x : row) w = w - 0.29, x = std::cos(w) + as[e];
    for (int i = 0; i < 26; ++i)
      for (int j = 0; j < 13; ++j) {
        P[i][j] = 0.0;
        for (int k = 0; k < 7; ++k) P[i][j] = P[i][j] + L[i][k] * R[k][j];
      }
    for (int i = 0; i < 13; ++i)
      for (int j = 0; j < 13; ++j) {
        Q[i][j] = 0.0;
        for (int k = 0; k < 26; ++k) Q[i][j] = Q[i][j] + P[k][i] * P[k][j];
      }
    double Z[13][13], wv[13], y = 0.0, u = 0.0;
    for (int i = 0; i < 13; ++i)
      for (int j = 0; j < 13; ++j)
        Z[i][j] = 0.0 + ((0.5 * Q[i][j] + Q[i][j]) - (i == j ? as[e] : 0.0));
    for (int k = 0; k < 13; ++k) wv[k] = R[3][k] - as[e];
    for (int k = 0; k < 13; ++k) y = y + Z[11][k] * wv[k];
    for (int k = 0; k < 13; ++k) u = u + Z[k][4] * wv[k];
    const double want[6] = {P[25][12], P[3][7], Q[12][12], Z[0][5], y, u};
    expect_same_bits(results[1][0].tensor().floats() + 6 * e, want, 6,
                     "element " + std::to_string(e));
  }
}

// Tensors of more than 144 components that come from fields, outer products and element-wise
// operations lie in scratch arrays and run as loops: a 13 x 13 field is loaded by one loop
// (binary64 and binary32 storage; a second read of it reuses the array), the outer product
// u w' is one loop over u, and the sums, differences, scaling and both kinds of
// matrix-vector product (T u, w' T, A' w, u' S') one loop each. The bits equal the interpreter's
// and a plain C++ loop's.
TEST(Jit, LargeTensorsFromFieldsAndOuterProductsRunAsLoops) {
  if (!api::jit_available()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  const char* program = R"(
element Point
  A : matrix[13,13](float);
  B : matrix[13,13](float);
  u : vector[13](float);
  w : vector[13](float);
  a : float;
end
extern points : set{Point};
func big(p : Point) -> r : vector[points](vector[8](float))
  O = p.u * p.w';
  S = p.A + O;
  T = p.a * p.B - S;
  y = T * p.u;
  z = p.w' * T;
  q = p.A' * p.w;
  t = p.u' * S';
  var v : vector[8](float);
  v(0) = T(12, 3);
  v(1) = y(7);
  v(2) = z(11);
  v(3) = q(5);
  v(4) = O(4, 9);
  v(5) = S(0, 12) + p.A(3, 3);
  v(6) = p.B(2, 11);
  v(7) = t(4);
  r(p) = v;
end
export func step() -> r : vector[points](vector[8](float))
  r = map big to points;
end
)";
  constexpr int n = 13, count = 3;
  // The fields' values: A, B (binary32), u, w, a per element.
  auto value = [](int field, int e, int k) {
    return std::sin(0.37 * (k + 1) + 1.3 * field + 0.71 * e) * (1.0 + field);
  };
  double stored_b[count][n * n];
  const auto [results, dump, stats] =
      run_points_both_ways("big.sim", program, count, [&](runtime::Set& points) {
        points.add_field("A", runtime::FieldType{runtime::ComponentKind::Float, {n, n}, false});
        points.add_field("B", runtime::FieldType{runtime::ComponentKind::Float, {n, n}, true});
        points.add_field("u", runtime::FieldType{runtime::ComponentKind::Float, {n}, false});
        points.add_field("w", runtime::FieldType{runtime::ComponentKind::Float, {n}, false});
        points.add_field("a", runtime::FieldType{runtime::ComponentKind::Float, {}, false});
        auto field = [&](const char* name) -> runtime::Field& {
          return points.field(points.field_index(name));
        };
        for (int e = 0; e < count; ++e) {
          for (int k = 0; k < n * n; ++k) {
            field("A").at<double>(e)[k] = value(0, e, k);
            field("B").at<float>(e)[k] = static_cast<float>(value(1, e, k));
            // The reference reads B back as stored (rounded to binary32).
            stored_b[e][k] = field("B").at<float>(e)[k];
          }
          for (int k = 0; k < n; ++k) {
            field("u").at<double>(e)[k] = value(2, e, k);
            field("w").at<double>(e)[k] = value(3, e, k);
          }
          field("a").at<double>(e)[0] = value(4, e, 0);
        }
      });
  EXPECT_NE(stats.find("big (line " + std::to_string(line_of(program, "map big")) + ")"),
            std::string::npos)
      << stats;
  EXPECT_EQ(stats.find("interpreted"), std::string::npos) << stats;
  // Loads of A and B, the outer product, A + O, a * B, minus S, T u, w' T, A' w and u' S'.
  EXPECT_EQ(count_loops(dump), 10u) << dump;
  // No component of the 13 x 13 fields is loaded one by one.
  EXPECT_EQ(dump.find("].168"), std::string::npos) << dump;
  expect_same(results[0][0], results[1][0], "r");
  // The reference: the same operations in plain C++.
  for (int e = 0; e < count; ++e) {
    double A[n][n], B[n][n], u[n], w[n], O[n][n], S[n][n], T[n][n];
    for (int i = 0; i < n; ++i) {
      u[i] = value(2, e, i);
      w[i] = value(3, e, i);
      for (int j = 0; j < n; ++j) {
        A[i][j] = value(0, e, i * n + j);
        B[i][j] = stored_b[e][i * n + j];
      }
    }
    const double a = value(4, e, 0);
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) {
        O[i][j] = u[i] * w[j];
        S[i][j] = A[i][j] + O[i][j];
        T[i][j] = a * B[i][j] - S[i][j];
      }
    double y = 0.0, z = 0.0, q = 0.0, t = 0.0;
    for (int k = 0; k < n; ++k) {
      y = y + T[7][k] * u[k];
      z = z + w[k] * T[k][11];
      q = q + A[k][5] * w[k];
      t = t + u[k] * S[4][k];
    }
    const double want[8] = {T[12][3], y, z, q, O[4][9], S[0][12] + A[3][3], B[2][11], t};
    expect_same_bits(results[1][0].tensor().floats() + 8 * e, want, 8,
                     "element " + std::to_string(e));
  }
}

// Every component of a dense local becomes a value of its own: a tensor of more than
// kMaxDenseComponents stays interpreted, saying why, and computes what the interpreter does.
// The mapped function's two writes to its result are no run of statements of their own.
TEST(Jit, ADenseLocalAboveTheComponentLimitStaysInterpreted) {
  if (!api::jit_available()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  const char* program = R"(
element Point
  a : float;
end
extern points : set{Point};
func fill(p : Point) -> r : vector[points](float)
  var A : matrix[8,8](matrix[8,8](float));
  A(7, 7)(7, 7) = p.a;
  r(p) = 0.0;
  r(p) = A(7, 7)(7, 7) + 1.0;
end
export func step() -> r : vector[points](float)
  r = map fill to points;
end
)";
  auto compiled = CompiledProgram::from_source("limit.sim", program);
  ASSERT_TRUE(compiled->ok());
  runtime::Set points("points");
  points.add_many(3);
  points.add_field("a", runtime::FieldType{runtime::ComponentKind::Float, {}, false});
  for (int i = 0; i < 3; ++i) points.field(0).at<double>(i)[0] = 0.5 * i;
  EngineOptions o;
  o.executor.kind = ExecutorKind::Jit;
  o.executor.threshold = 0;
  Engine engine(compiled, o);
  engine.bind_set(*compiled->find_extern("points"), points);
  const std::vector<Value> r = engine.call(*compiled->find_func("step"), {});
  std::ostringstream os;
  engine.print_jit_stats(os);
  const std::string limit = std::to_string(kMaxDenseComponents);
  EXPECT_NE(os.str().find("interpreted: a dense tensor of 4096 components (more than " + limit +
                          ") is not compiled (line 7)"),
            std::string::npos)
      << os.str();
  for (int i = 0; i < 3; ++i) EXPECT_EQ(r[0].tensor().floats()[i], 0.5 * i + 1.0);
  EXPECT_EQ(os.str().find("statement"), std::string::npos) << os.str();
}

// A CG loop compiled whole: three loops per iteration after fusion, the interpreter's bits.
const std::string kSolver = R"(
element Point
  b : float;
  d : float;
end
element Link
  k : float;
end
extern points : set{Point};
extern links : set{Link}(points, points);
)" + std::string(kChainMatrix) +
                            R"(
export func solve() -> (x : vector[points](float), iterations : int)
  A = (map stiffness to links reduce +) + (map diagonal to points reduce +);
  b = points.b;
  x = 0.0 * b;
  var r = b;
  var p = r;
  var rr = r' * r;
  while (rr > 1e-20) and (iterations < 50)
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
)";

TEST(Jit, ASolverLoopFusesIntoThreeLoopsAndComputesTheInterpretersBits) {
  if (!api::jit_available()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  std::vector<Value> results[2];
  std::string dump, stats;
  for (int k = 0; k < 2; ++k) {
    auto compiled = CompiledProgram::from_source("solver.sim", kSolver);
    ASSERT_TRUE(compiled->ok());
    runtime::Set points("points");
    runtime::Set links("links", {&points, &points});
    const int n = 40;
    points.add_many(n);
    points.add_field("b", runtime::FieldType{runtime::ComponentKind::Float, {}, false});
    points.add_field("d", runtime::FieldType{runtime::ComponentKind::Float, {}, false});
    links.add_field("k", runtime::FieldType{runtime::ComponentKind::Float, {}, false});
    for (int i = 0; i < n; ++i) {
      points.field(0).at<double>(i)[0] = std::sin(0.3 * i);
      points.field(1).at<double>(i)[0] = 0.1 + 0.01 * i;
      if (i + 1 < n) links.add({i, i + 1});
    }
    for (int e = 0; e < links.size(); ++e)
      links.field(0).at<double>(e)[0] = 1.0 + 0.5 * std::cos(e);
    std::ostringstream dumped;
    EngineOptions o;
    o.executor.kind = k ? ExecutorKind::Jit : ExecutorKind::Interpreter;
    o.executor.threshold = 0;
    o.dump = &dumped;
    o.executor.dump_loop_ir = true;
    Engine engine(compiled, o);
    engine.bind_set(*compiled->find_extern("points"), points);
    engine.bind_set(*compiled->find_extern("links"), links);
    results[k] = engine.call(*compiled->find_func("solve"), {});
    std::ostringstream os;
    engine.print_jit_stats(os);
    if (k) {
      dump = dumped.str();
      stats = os.str();
    }
  }
  // The loop: the product with p'Ap, one pass for x, r and r'r, one for p.
  const size_t begin = dump.find("  while ");
  ASSERT_NE(begin, std::string::npos) << dump;
  const std::string loop = dump.substr(begin, dump.find("  after", begin) - begin);
  auto count = [&](const std::string& what) {
    size_t c = 0;
    for (size_t at = loop.find(what); at != std::string::npos; at = loop.find(what, at + 1)) ++c;
    return c;
  };
  EXPECT_EQ(count(" = spmv("), 1u) << loop;
  EXPECT_EQ(count("pass over"), 2u) << loop;
  // Six loops before fusion (the product, p'Ap, x, r, r'r, p), three after; the set-up before
  // the loop (x, r, p and r'r) is one pass.
  EXPECT_NE(stats.find(" compiled"), std::string::npos) << stats;
  const size_t setup_at = dump.find("  before");
  ASSERT_LT(setup_at, begin) << dump;
  const std::string setup = dump.substr(setup_at, begin - setup_at);
  EXPECT_NE(setup.find("pass over"), std::string::npos) << setup;
  EXPECT_EQ(setup.find("pass over", setup.find("pass over") + 1), std::string::npos) << setup;
  ASSERT_EQ(results[0][1].as_int(), results[1][1].as_int());
  EXPECT_GT(results[0][1].as_int(), 5);  // CG took real iterations
  expect_same(results[0][0], results[1][0], "x");
}

// --check-finite compiled: a check after every operation, as the interpreter does; a map's
// error is reported by the interpreter running it again, an apply's by the kernel.
const char* kFinite = R"(
element P
  a : float;
  b : float;
end
extern ps : set{P};

func logs(p : P) -> r : vector[ps](float)
  r(p) = 2.0 * log(p.a);
end

func roots(inout p : P)
  p.b = sqrt(p.a) + 1.0;
end

export func map_it() -> (r : vector[ps](float))
  r = map logs to ps reduce +;
end

export func apply_it()
  apply roots to ps;
end
)";

TEST(Jit, CheckFiniteIsCompiledAndStopsWhereTheInterpreterStops) {
  if (!api::jit_available()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  std::string messages[2][2], stats;
  for (int k = 0; k < 2; ++k) {
    auto compiled = CompiledProgram::from_source("finite.sim", kFinite);
    ASSERT_TRUE(compiled->ok());
    runtime::Set ps("ps");
    ps.add_many(5);
    ps.add_field("a", runtime::FieldType{runtime::ComponentKind::Float, {}, false});
    ps.add_field("b", runtime::FieldType{runtime::ComponentKind::Float, {}, false});
    for (int i = 0; i < 5; ++i) ps.field(0).at<double>(i)[0] = i == 3 ? -1.0 : 1.0 + i;
    EngineOptions o;
    o.executor.kind = k ? ExecutorKind::Jit : ExecutorKind::Interpreter;
    o.executor.threshold = 0;
    o.check_finite = true;
    Engine engine(compiled, o);
    engine.bind_set(*compiled->find_extern("ps"), ps);
    for (int f = 0; f < 2; ++f) {
      try {
        engine.call(*compiled->find_func(f ? "apply_it" : "map_it"), {});
      } catch (const interp::RuntimeError& e) {
        messages[k][f] = e.render();
      }
    }
    std::ostringstream os;
    engine.print_jit_stats(os);
    if (k) stats = os.str();
  }
  EXPECT_NE(stats.find("logs (line 17)"), std::string::npos) << stats;
  EXPECT_NE(stats.find("roots (line 21)"), std::string::npos) << stats;
  EXPECT_EQ(stats.find("interpreted"), std::string::npos) << stats;
  // The map: the interpreter's own words (it ran the site again).
  EXPECT_NE(messages[0][0].find("finite.sim:9:16: runtime error: the operation produced NaN"),
            std::string::npos)
      << messages[0][0];
  EXPECT_EQ(messages[0][0], messages[1][0]);
  // The apply: the same place and element, in the kernel's words.
  EXPECT_NE(messages[0][1].find("finite.sim:13:9: runtime error: the operation produced NaN"),
            std::string::npos)
      << messages[0][1];
  EXPECT_NE(messages[1][1].find(
                "finite.sim:13:9: runtime error: the operation produced a NaN or an infinity"),
            std::string::npos)
      << messages[1][1];
  EXPECT_NE(messages[1][1].find("in roots (finite.sim:13), mapping over element 3 of set 'ps'"),
            std::string::npos)
      << messages[1][1];
}

// Error statements: a map compiles one as a check that always fails, so the interpreter runs
// the site again and reports it; an apply that writes fields stays interpreted.
const char* const kErrorStatements = R"(element P
  a : float;
  b : float;
end
extern ps : set{P};

func checked(p : P) -> r : vector[ps](float)
  if p.a < 0.0
    error "a = ", p.a, " < 0";
  end
  r(p) = 2.0 * p.a;
end

func guarded(inout p : P)
  p.b = 3.0 * p.a;
  if p.a < 0.0
    error "a = ", p.a, " < 0 in an apply";
  end
end

export func map_it() -> (r : vector[ps](float))
  r = map checked to ps reduce +;
end

export func apply_it()
  apply guarded to ps;
end
)";

struct ErrorRun {
  std::string messages[2];
  std::vector<double> r, b;
  std::string stats;
};

ErrorRun run_errors(ExecutorKind kind, bool bad) {
  auto compiled = CompiledProgram::from_source("errors.sim", kErrorStatements);
  EXPECT_TRUE(compiled->ok());
  runtime::Set ps("ps");
  ps.add_many(5);
  ps.add_field("a", runtime::FieldType{runtime::ComponentKind::Float, {}, false});
  ps.add_field("b", runtime::FieldType{runtime::ComponentKind::Float, {}, false});
  for (int i = 0; i < 5; ++i) ps.field(0).at<double>(i)[0] = bad && i == 3 ? -1.5 : 0.25 * i;
  EngineOptions o;
  o.executor.kind = kind;
  o.executor.threshold = 0;
  Engine engine(compiled, o);
  engine.bind_set(*compiled->find_extern("ps"), ps);
  ErrorRun run;
  for (int f = 0; f < 2; ++f) {
    try {
      std::vector<Value> res = engine.call(*compiled->find_func(f ? "apply_it" : "map_it"), {});
      if (!f) run.r.assign(res[0].tensor().floats(), res[0].tensor().floats() + 5);
    } catch (const interp::RuntimeError& e) {
      run.messages[f] = e.render();
    }
  }
  for (int i = 0; i < 5; ++i) run.b.push_back(ps.field(1).at<double>(i)[0]);
  std::ostringstream os;
  engine.print_jit_stats(os);
  run.stats = os.str();
  return run;
}

TEST(Jit, ErrorStatementsAreReportedInTheInterpretersWords) {
  if (!api::jit_available()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  for (bool bad : {false, true}) {
    const ErrorRun in = run_errors(ExecutorKind::Interpreter, bad);
    const ErrorRun jit = run_errors(ExecutorKind::Jit, bad);
    for (int f = 0; f < 2; ++f) EXPECT_EQ(in.messages[f], jit.messages[f]) << f;
    EXPECT_EQ(in.r, jit.r);
    EXPECT_EQ(in.b, jit.b);
    // The map is compiled; the apply is not, and says why.
    std::istringstream lines(jit.stats);
    bool map_seen = false;
    for (std::string line; std::getline(lines, line);)
      if (line.find("checked (line 22)") != std::string::npos) {
        map_seen = true;
        EXPECT_EQ(line.find("interpreted"), std::string::npos) << jit.stats;
      }
    EXPECT_TRUE(map_seen) << jit.stats;
    EXPECT_NE(jit.stats.find("interpreted: error statements in an apply with inout fields are "
                             "not compiled (line 17)"),
              std::string::npos)
        << jit.stats;
    if (!bad) {
      EXPECT_EQ(jit.r, (std::vector<double>{0.0, 0.5, 1.0, 1.5, 2.0}));
      EXPECT_EQ(jit.b, (std::vector<double>{0.0, 0.75, 1.5, 2.25, 3.0}));
      EXPECT_EQ(jit.messages[0], "");
      EXPECT_EQ(jit.messages[1], "");
      continue;
    }
    EXPECT_EQ(jit.messages[0],
              "errors.sim:9:5: runtime error: a = -1.5 < 0\n"
              "  in checked (errors.sim:9), mapping over element 3 of set 'ps'\n"
              "  in map_it (errors.sim:22)\n");
    EXPECT_EQ(jit.messages[1],
              "errors.sim:17:5: runtime error: a = -1.5 < 0 in an apply\n"
              "  in guarded (errors.sim:17), mapping over element 3 of set 'ps'\n"
              "  in apply_it (errors.sim:26)\n");
    // The apply stopped at element 3, which had already written its b.
    EXPECT_EQ(jit.b, (std::vector<double>{0.0, 0.75, 1.5, -4.5, 0.0}));
  }
}

}  // namespace
}  // namespace simit::jit
