// Zero folding (jit/zero_fold.h) and map kernels in four lanes against the interpreter.
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
#include "jit_test_support.h"

namespace simit::jit {
namespace {

using namespace test_support;  // also ast, Value and the engine API's names

// ---------------------------------------------------------------------------
// Zero folding (jit/zero_fold.h)

const char* const kZeros = R"(element P
  x : float;
  y : vector[3](float);
end
extern ps : set{P};

func unit(d : int) -> e : vector[3](float)
  e(d) = 1.0;
end

func outer(p : P) -> r : vector[ps](vector[3](float))
  M = unit(1) * p.y';
  r(p) = M * p.y;
end

func reciprocal(p : P) -> q : vector[ps](float)
  z = p.x * unit(1)(0);
  q(p) = 1.0 / z;
end

export func main() -> (r : vector[ps](vector[3](float)), q : vector[ps](float))
  r = map outer to ps reduce +;
  q = map reciprocal to ps reduce +;
end
)";

struct ZeroRun {
  std::vector<Value> results;
  std::string dump, stats;
};

// y of element 2 holds an infinity when `inf` is set: 0 * inf is NaN, not 0.
ZeroRun run_zeros(ExecutorKind kind, bool inf) {
  auto compiled = CompiledProgram::from_source("zeros.sim", kZeros);
  EXPECT_TRUE(compiled->ok());
  runtime::Set ps("ps");
  ps.add_many(4);
  ps.add_field("x", runtime::FieldType{runtime::ComponentKind::Float, {}, false});
  ps.add_field("y", runtime::FieldType{runtime::ComponentKind::Float, {3}, false});
  for (int i = 0; i < 4; ++i) {
    ps.field(0).at<double>(i)[0] = i % 2 ? -2.0 - i : 3.0 + i;  // odd elements negative
    for (int k = 0; k < 3; ++k) ps.field(1).at<double>(i)[k] = 0.5 * (i + 1) - 0.75 * k;
  }
  if (inf) ps.field(1).at<double>(2)[2] = HUGE_VAL;
  std::ostringstream dump;
  EngineOptions o;
  o.executor.kind = kind;
  o.executor.threshold = 0;
  o.dump = &dump;
  o.executor.dump_loop_ir = true;
  Engine engine(compiled, o);
  engine.bind_set(*compiled->find_extern("ps"), ps);
  ZeroRun r;
  r.results = engine.call(*compiled->find_func("main"), {});
  std::ostringstream stats;
  engine.print_jit_stats(stats);
  r.dump = dump.str();
  r.stats = stats.str();
  return r;
}

TEST(Jit, ProductsByKnownZerosFoldWhereTheyCannotChangeAValue) {
  if (!api::jit_available()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  for (bool inf : {false, true}) {
    const ZeroRun in = run_zeros(ExecutorKind::Interpreter, inf);
    const ZeroRun jit = run_zeros(ExecutorKind::Jit, inf);
    const double* a = in.results[0].tensor().floats();
    const double* b = jit.results[0].tensor().floats();
    for (size_t i = 0; i < 12; ++i) {
      // Row 1 of the outer product is y', so r(p) = (0, y'y, 0); rows 0 and 2 are zeros
      // whose sign the interpreter takes from y (its 0 * y(k)), the JIT from nothing.
      if (std::isnan(a[i])) {
        EXPECT_TRUE(std::isnan(b[i])) << i;
        continue;
      }
      EXPECT_EQ(a[i], b[i]) << "r[" << i << "] inf " << inf;
    }
    // Element 2's y holds an infinity: 0 * inf is NaN in its rows 0 and 2, and the JIT's check
    // of the folded factors handed the call back to the interpreter, which computed it.
    EXPECT_EQ(std::isnan(a[6]), inf);
    EXPECT_EQ(a[1], 0.5 * 0.5 + -0.25 * -0.25 + -1.0 * -1.0);
    // 1 / (x * 0) depends on the zero's sign (-inf for negative x): not folded, exact.
    const double* qa = in.results[1].tensor().floats();
    const double* qb = jit.results[1].tensor().floats();
    for (int i = 0; i < 4; ++i) {
      EXPECT_EQ(qa[i], i % 2 ? -HUGE_VAL : HUGE_VAL) << i;
      EXPECT_EQ(qb[i], qa[i]) << i;
    }
    // Both sites compiled; the outer product's zero rows left no multiplication behind.
    EXPECT_NE(jit.stats.find("outer (line 22)"), std::string::npos) << jit.stats;
    EXPECT_EQ(jit.stats.find("interpreted"), std::string::npos) << jit.stats;
    const size_t outer = jit.dump.find("trace outer"), next = jit.dump.find("trace reciprocal");
    ASSERT_NE(outer, std::string::npos) << jit.dump;
    const std::string body = jit.dump.substr(outer, next - outer);
    size_t products = 0;
    for (size_t at = body.find(" * "); at != std::string::npos; at = body.find(" * ", at + 1))
      ++products;
    EXPECT_EQ(products, 3u) << body;  // y'y: three products
    EXPECT_NE(body.find("check"), std::string::npos) << body;
  }
}

// Map kernels compute four elements at once, one per SIMD lane, then run each element's writes,
// branches and checks in order. Eleven springs: two full groups and one of three; the
// branches differ between lanes of one group, and the results are the interpreter's bits.
const char* const kLanes = R"(element P
  x : vector[3](float);
  fixed : bool;
end
element S
  k : float;
end
extern ps : set{P};
extern ss : set{S}(ps, ps);

func pull(s : S, p : (P * 2)) -> (f : vector[ps](vector[3](float)), K : matrix[ps,ps](matrix[3,3](float)))
  d = p(1).x - p(0).x;
  l = norm(d);
  t = (s.k * (l - 1.0) / l) * d;
  if not p(0).fixed
    f(p(0)) = t;
    K(p(0), p(0)) = (s.k / l) * (d * d');
  end
  if not p(1).fixed
    f(p(1)) = -t;
    K(p(1), p(1)) = (s.k / (l * l)) * (d * d');
  end
  if not (p(0).fixed or p(1).fixed)
    K(p(0), p(1)) = -exp(-l) * (d * d');
  end
end

func ratio(s : S, p : (P * 2)) -> r : vector[ss](float)
  r(s) = log(s.k) * p(1).x(0);
end

export func both() -> (f : vector[ps](vector[3](float)), K : matrix[ps,ps](matrix[3,3](float)))
  f, K = map pull to ss reduce +;
end

export func ratios() -> r : vector[ss](float)
  r = map ratio to ss reduce +;
end
)";

struct LaneRun {
  std::vector<Value> results;
  std::string stats, error;
};

LaneRun run_lanes(ExecutorKind kind, const char* function, int zero_at = -1, bool float32 = false) {
  auto compiled = CompiledProgram::from_source("lanes.sim", kLanes);
  EXPECT_TRUE(compiled->ok());
  runtime::Set ps("ps"), ss("ss", {&ps, &ps});
  const int n = 12;
  ps.add_many(n);
  // Under --float32 the fields are binary32 (as a scene binds them), their values rounded.
  ps.add_field("x", runtime::FieldType{runtime::ComponentKind::Float, {3}, float32});
  ps.add_field("fixed", runtime::FieldType{runtime::ComponentKind::Bool, {}, false});
  for (int i = 0; i < n; ++i) {
    for (int k = 0; k < 3; ++k) {
      const double x = 0.3 + 0.71 * i - 0.13 * k * i;
      if (float32)
        ps.field(0).at<float>(i)[k] = static_cast<float>(x);
      else
        ps.field(0).at<double>(i)[k] = x;
    }
    ps.field(1).at<bool>(i)[0] = i % 5 == 2;  // lanes of one group take different branches
  }
  std::vector<int32_t> ends;
  for (int i = 0; i + 1 < n; ++i) ends.insert(ends.end(), {i, (5 * i + 3) % n});
  ss.add_edges(ends);
  ss.add_field("k", runtime::FieldType{runtime::ComponentKind::Float, {}, float32});
  for (int i = 0; i + 1 < n; ++i) {
    const double k = i == zero_at ? 0.0 : 1.0 + 0.37 * i;
    if (float32)
      ss.field(0).at<float>(i)[0] = static_cast<float>(k);
    else
      ss.field(0).at<double>(i)[0] = k;
  }
  EngineOptions o;
  o.executor.kind = kind;
  o.executor.threshold = 0;
  o.check_finite = zero_at >= 0;
  o.float32 = float32;
  Engine engine(compiled, o);
  engine.bind_set(*compiled->find_extern("ps"), ps);
  engine.bind_set(*compiled->find_extern("ss"), ss);
  LaneRun run;
  try {
    for (int call = 0; call < 2; ++call)
      run.results = engine.call(*compiled->find_func(function), {});
  } catch (const interp::RuntimeError& e) {
    run.error = e.render();
  }
  std::ostringstream os;
  engine.print_jit_stats(os);
  run.stats = os.str();
  return run;
}

TEST(Jit, MapKernelsComputeFourElementsAtOnceWithTheInterpretersBits) {
  if (!api::jit_available()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  const LaneRun in = run_lanes(ExecutorKind::Interpreter, "both");
  const LaneRun jit = run_lanes(ExecutorKind::Jit, "both");
  ASSERT_EQ(in.results.size(), 2u);
  ASSERT_EQ(jit.results.size(), 2u);
  expect_same(in.results[0], jit.results[0], "f");
  expect_same(in.results[1], jit.results[1], "K");
  EXPECT_NE(in.results[0].tensor().floats()[0], 0.0);
  EXPECT_NE(jit.stats.find("pull (line 33)"), std::string::npos) << jit.stats;
  EXPECT_NE(jit.stats.find("4 elements at once"), std::string::npos) << jit.stats;
  EXPECT_EQ(jit.stats.find("interpreted"), std::string::npos) << jit.stats;
}

// Under --float32 eight elements at once (kLanes32): one full group and one of three; `ratios`
// calls log, four lanes at a time, twice per group.
TEST(Jit, UnderFloat32MapKernelsComputeEightElementsAtOnceWithTheInterpretersBits) {
  if (!api::jit_available()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  for (const char* function : {"both", "ratios"}) {
    const LaneRun in = run_lanes(ExecutorKind::Interpreter, function, -1, true);
    const LaneRun jit = run_lanes(ExecutorKind::Jit, function, -1, true);
    ASSERT_EQ(in.results.size(), jit.results.size()) << function;
    for (size_t r = 0; r < in.results.size(); ++r)
      expect_same(in.results[r], jit.results[r], function);
    EXPECT_NE(in.results[0].tensor().floats()[1], 0.0) << function;
    EXPECT_NE(jit.stats.find("8 elements at once"), std::string::npos) << jit.stats;
    EXPECT_EQ(jit.stats.find("interpreted"), std::string::npos) << jit.stats;
  }
}

// A check that fails in one lane only (spring 6: lane 2 of the second group) stops the call
// at that element: the interpreter, running the site again, reports it in its own words.
TEST(Jit, ACheckFailingInOneLaneStopsAtItsElement) {
  if (!api::jit_available()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  const LaneRun in = run_lanes(ExecutorKind::Interpreter, "ratios", 6);
  const LaneRun jit = run_lanes(ExecutorKind::Jit, "ratios", 6);
  EXPECT_NE(in.error.find("lanes.sim:29:10: runtime error"), std::string::npos) << in.error;
  EXPECT_NE(in.error.find("element 6 of set 'ss'"), std::string::npos) << in.error;
  EXPECT_EQ(in.error, jit.error);
  EXPECT_NE(jit.stats.find("4 elements at once"), std::string::npos) << jit.stats;
}

}  // namespace
}  // namespace simit::jit
