// The executor seam (jit/executor.h): the serial executor's chunks, the test-only shuffled
// one's order and failures, which traces may run out of order, and a program's bits through
// both executors.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <sstream>
#include <vector>

#include "api/compiled_program.h"
#include "api/engine.h"
#include "jit/executor.h"
#include "recording_kernel.h"
#include "runtime/set.h"

namespace simit::jit {
namespace {

// Every element of [0, n) exactly once.
void expect_cover(const std::vector<ElementRange>& ranges, int32_t n) {
  std::vector<int> seen(static_cast<size_t>(n), 0);
  for (const ElementRange& r : ranges)
    for (int32_t e = r.begin; e < r.end; ++e) ++seen[static_cast<size_t>(e)];
  for (int32_t e = 0; e < n; ++e) EXPECT_EQ(seen[static_cast<size_t>(e)], 1) << e;
}

TEST(Executor, SerialRunsChunksInElementOrder) {
  RecordingKernel k;
  const MapOutcome out = make_serial_executor()->run_map(k, {}, 10, 4, MapWrites::Shared, {});
  EXPECT_EQ(out.code, 0);
  ASSERT_EQ(k.ranges.size(), 3u);
  EXPECT_EQ(k.ranges[0].begin, 0);
  EXPECT_EQ(k.ranges[1].begin, 4);
  EXPECT_EQ(k.ranges[2].begin, 8);
  EXPECT_EQ(k.ranges[2].end, 10);
}

TEST(Executor, SerialStopsAtTheFirstFailureAndForAnInterrupt) {
  RecordingKernel k;
  k.failing = {5, 9};
  MapOutcome out = make_serial_executor()->run_map(k, {}, 12, 4, MapWrites::Shared, {});
  EXPECT_EQ(out.code, 1);
  EXPECT_EQ(out.element, 5);
  EXPECT_EQ(k.ranges.size(), 2u);  // the chunk after the failure does not run

  RecordingKernel quiet;
  int asked = 0;
  out = make_serial_executor()->run_map(quiet, {}, 12, 4, MapWrites::Shared,
                                        [&] { return ++asked == 2; });
  EXPECT_TRUE(out.interrupted);
  EXPECT_EQ(quiet.ranges.size(), 2u);  // stopped between the second and the third chunk
}

TEST(Executor, ShuffledRunsDisjointChunksOutOfOrderAndSharedOnesInOrder) {
  RecordingKernel k;
  const int32_t n = 100;
  const auto shuffled = make_shuffled_executor(7, 3);
  EXPECT_EQ(shuffled->chunk_for(n), 3);  // its own chunks, so small sets have several
  MapOutcome out = shuffled->run_map(k, {}, n, 3, MapWrites::Disjoint, {});
  EXPECT_EQ(out.code, 0);
  EXPECT_EQ(k.ranges.size(), 34u);
  expect_cover(k.ranges, n);
  EXPECT_FALSE(std::is_sorted(k.ranges.begin(), k.ranges.end(),
                              [](ElementRange a, ElementRange b) { return a.begin < b.begin; }));

  RecordingKernel shared;
  out = make_shuffled_executor(7, 3)->run_map(shared, {}, n, 16, MapWrites::Shared, {});
  expect_cover(shared.ranges, n);
  EXPECT_TRUE(std::is_sorted(shared.ranges.begin(), shared.ranges.end(),
                             [](ElementRange a, ElementRange b) { return a.begin < b.begin; }));
}

TEST(Executor, ShuffledReportsTheLowestFailingElement) {
  for (uint64_t seed = 1; seed <= 20; ++seed) {
    RecordingKernel k;
    k.failing = {61, 17, 90};
    const MapOutcome out =
        make_shuffled_executor(seed, 3)->run_map(k, {}, 100, 3, MapWrites::Disjoint, {});
    EXPECT_EQ(out.code, 1);
    EXPECT_EQ(out.element, 17) << "seed " << seed;
  }
}

Trace trace_with(Stmt s) {
  Trace t;
  t.body.push_back(std::move(s));
  return t;
}

ExprRef element() {
  auto e = std::make_shared<Expr>();
  e->kind = ExprKind::Element;
  e->ty = Ty::I32;
  return e;
}

ExprRef endpoint(int k) {
  auto e = std::make_shared<Expr>();
  e->kind = ExprKind::Endpoint;
  e->ty = Ty::I32;
  e->slot = k;
  return e;
}

TEST(Executor, WritesOfATraceSayWhetherChunksMayRunOutOfOrder) {
  Stmt store;
  store.kind = StmtKind::Store;
  store.index = element();
  EXPECT_EQ(writes_of(trace_with(store)), MapWrites::Disjoint);
  store.index = endpoint(0);
  EXPECT_EQ(writes_of(trace_with(store)), MapWrites::Shared);

  Stmt add;
  add.kind = StmtKind::Assemble;
  add.index = element();
  EXPECT_EQ(writes_of(trace_with(add)), MapWrites::Disjoint);
  add.pair = 0;  // into a matrix block
  EXPECT_EQ(writes_of(trace_with(add)), MapWrites::Shared);

  Stmt branch;  // the write inside a branch counts too
  branch.kind = StmtKind::If;
  add.pair = -1;
  add.index = endpoint(1);
  branch.orelse.push_back(add);
  EXPECT_EQ(writes_of(trace_with(branch)), MapWrites::Shared);
}

// A program whose maps both write apart (an apply over the vertices) and add into shared
// blocks (a matrix and a vector over the edges), run serially and shuffled: the same bits.
constexpr const char* kProgram = R"(
element V
  x : vector[2](float);
  y : vector[2](float);
end
element E
end
extern verts : set{V};
extern edges : set{E}(verts, verts);

func spring(e : E, v : (V*2)) -> (K : tensor[verts,verts](tensor[2,2](float)),
                                 f : tensor[verts](tensor[2](float)))
  d = v(1).x - v(0).x;
  K(v(0), v(1)) = d' * d * 0.5;
  K(v(0), v(0)) = d' * d;
  f(v(0)) = 0.3 * d;
  f(v(1)) = -sin(d(0)) * d;
end

func move(inout v : V)
  var w : vector[2](float);
  w(0) = cos(v.x(0));
  w(1) = 1.0 / (1.0 + v.x(1) * v.x(1));
  v.y = v.y + 0.25 * v.x * v.x(1) - w;
end

export func step() -> (s : float)
  K, f = map spring to edges reduce +;
  apply move to verts;
  verts.x = verts.x + 0.01 * (K * verts.y + f);
  s = verts.x' * verts.x;
end
)";

std::vector<double> run_program(uint64_t seed, double& s, int threads = 1, int n = 50) {
  auto compiled = api::CompiledProgram::from_source("seam.sim", kProgram);
  EXPECT_TRUE(compiled->ok());
  runtime::Set v("verts");
  runtime::Set e("edges", {&v, &v});
  v.add_many(n);
  v.add_field("x", runtime::FieldType{runtime::ComponentKind::Float, {2}, false});
  v.add_field("y", runtime::FieldType{runtime::ComponentKind::Float, {2}, false});
  for (int i = 0; i < n; ++i) {
    const int j = i % 50;  // a large set repeats the first 50 vertices' positions
    v.field(0).at<double>(i)[0] = 0.1 * j - 0.7;
    v.field(0).at<double>(i)[1] = 0.05 * j * j / 50 + 0.3;
  }
  std::vector<int32_t> ends;
  for (int i = 0; i + 1 < n; ++i) ends.insert(ends.end(), {i, i + 1, (7 * i) % n, i});
  e.add_edges(ends);
  api::EngineOptions o;
  o.executor.kind = api::ExecutorKind::Jit;
  o.executor.threshold = 0;
  o.shuffle_seed_for_test = seed;
  o.executor.threads = threads;
  api::Engine engine(compiled, o);
  engine.bind_set(*compiled->find_extern("verts"), v);
  engine.bind_set(*compiled->find_extern("edges"), e);
  for (int f = 0; f < 4; ++f) s = engine.call(*compiled->find_func("step"), {})[0].as_float();
  std::ostringstream stats;
  engine.print_jit_stats(stats);
  EXPECT_NE(stats.str().find("compiled"), std::string::npos) << stats.str();
  std::vector<double> out(v.field(0).data<double>(), v.field(0).data<double>() + 2 * n);
  out.insert(out.end(), v.field(1).data<double>(), v.field(1).data<double>() + 2 * n);
  return out;
}

TEST(Executor, AProgramGivesTheSameBitsSerialAndShuffled) {
  double s0 = 0, s1 = 0, s2 = 0;
  const std::vector<double> serial = run_program(0, s0);
  const std::vector<double> a = run_program(3, s1), b = run_program(99, s2);
  ASSERT_EQ(serial.size(), a.size());
  EXPECT_EQ(std::memcmp(serial.data(), a.data(), serial.size() * sizeof(double)), 0);
  EXPECT_EQ(std::memcmp(serial.data(), b.data(), serial.size() * sizeof(double)), 0);
  EXPECT_EQ(std::memcmp(&s0, &s1, sizeof s0), 0);
  EXPECT_EQ(std::memcmp(&s0, &s2, sizeof s0), 0);
  EXPECT_TRUE(std::isfinite(s0));
}

// Threads: the same bits for every thread count, on a set large enough for several chunks
// whose springs reach across chunks (their blocks are shared: deferred assembly).
TEST(Executor, AProgramGivesTheSameBitsOnAnyNumberOfThreads) {
  double s1 = 0;
  const std::vector<double> one = run_program(0, s1, 1, 3000);
  for (int threads : {2, 3, 7}) {
    double s = 0;
    const std::vector<double> many = run_program(0, s, threads, 3000);
    ASSERT_EQ(one.size(), many.size());
    EXPECT_EQ(std::memcmp(one.data(), many.data(), one.size() * sizeof(double)), 0) << threads;
    EXPECT_EQ(std::memcmp(&s1, &s, sizeof s), 0) << threads;
  }
  EXPECT_TRUE(std::isfinite(s1));
}

}  // namespace
}  // namespace simit::jit
