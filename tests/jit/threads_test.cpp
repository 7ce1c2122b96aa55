// The engine's thread pool and the threaded executor (jit/thread_pool.h, jit/executor.h):
// every task exactly once, every element exactly once, the lowest failure reported, an
// interrupt stopping every thread; and the deferred assembly's tables (jit/deferred_plan.h).
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <vector>

#include "jit/defer_assembly.h"
#include "jit/deferred_plan.h"
#include "jit/executor.h"
#include "jit/thread_pool.h"
#include "recording_kernel.h"
#include "runtime/set.h"

namespace simit::jit {
namespace {

TEST(ThreadPool, RunsEveryTaskOnceJobAfterJob) {
  for (int threads : {1, 2, 3, 7}) {
    ThreadPool pool(threads);
    EXPECT_EQ(pool.threads(), threads);
    for (int64_t tasks : {0, 1, 2, 5, 1000}) {
      for (int job = 0; job < 20; ++job) {
        std::vector<std::atomic<int>> runs(static_cast<size_t>(tasks));
        pool.run(tasks, [&](int64_t i) { runs[static_cast<size_t>(i)].fetch_add(1); });
        for (int64_t i = 0; i < tasks; ++i)
          ASSERT_EQ(runs[static_cast<size_t>(i)].load(), 1) << threads << " " << tasks << " " << i;
      }
    }
  }
}

TEST(ThreadedExecutor, CoversEveryElementOnceInItsChunks) {
  for (int threads : {2, 3, 7}) {
    const auto x = make_threaded_executor(threads);
    EXPECT_TRUE(x->parallel());
    const int32_t n = 100000, chunk = x->chunk_for(n);
    EXPECT_GE(chunk, 256);
    EXPECT_EQ(chunk % 4, 0);
    RecordingKernel k;
    const MapOutcome out = x->run_map(k, {}, n, chunk, MapWrites::Deferred, {});
    EXPECT_EQ(out.code, 0);
    std::vector<int> seen(n, 0);
    for (const ElementRange& r : k.ranges) {
      EXPECT_EQ(r.begin % chunk, 0);  // the chunks a deferred assembly's tables were built for
      for (int32_t e = r.begin; e < r.end; ++e) ++seen[static_cast<size_t>(e)];
    }
    EXPECT_EQ(std::count(seen.begin(), seen.end(), 1), n);
  }
}

TEST(ThreadedExecutor, RunsSharedWritesInElementOrderOnTheCallingThread) {
  const auto x = make_threaded_executor(3);
  RecordingKernel k;
  x->run_map(k, {}, 5000, 300, MapWrites::Shared, {});
  EXPECT_TRUE(std::is_sorted(k.ranges.begin(), k.ranges.end(),
                             [](ElementRange a, ElementRange b) { return a.begin < b.begin; }));
}

TEST(ThreadedExecutor, ReportsTheLowestFailingElement) {
  for (int round = 0; round < 20; ++round) {
    const auto x = make_threaded_executor(1 + round % 7 + 1);
    RecordingKernel k;
    k.failing = {9000, 1700, 6100};
    const MapOutcome out = x->run_map(k, {}, 10000, 256, MapWrites::Disjoint, {});
    EXPECT_EQ(out.code, 1);
    EXPECT_EQ(out.element, 1700) << round;
    EXPECT_FALSE(out.interrupted);
  }
}

TEST(ThreadedExecutor, AnInterruptStopsEveryThread) {
  const auto x = make_threaded_executor(3);
  RecordingKernel k;
  std::atomic<int> asked{0};
  const MapOutcome out =
      x->run_map(k, {}, 100000, 256, MapWrites::Disjoint, [&] { return asked.fetch_add(1) >= 10; });
  EXPECT_TRUE(out.interrupted);
  EXPECT_EQ(out.code, 0);
  EXPECT_LE(k.ranges.size(), 10u + 3u);  // each thread stops at its next chunk
}

// A trace adding 1.0 at both endpoints of each edge (a vector result of one component).
Trace edge_sum_trace() {
  Trace t;
  t.arity = 2;
  t.reduce = true;
  ArraySlot r;
  r.kind = ArraySlot::Kind::Result;
  r.written = true;
  r.name = "f";
  t.arrays.push_back(r);
  t.pairs = {0};
  for (int k = 0; k < 2; ++k) {
    auto at = std::make_shared<Expr>();
    at->kind = ExprKind::Endpoint;
    at->ty = Ty::I32;
    at->slot = k;
    auto one = std::make_shared<Expr>();
    one->f = 1.0;
    Stmt s;
    s.kind = StmtKind::Assemble;
    s.index = at;
    s.value = one;
    t.body.push_back(s);
  }
  return t;
}

TEST(DeferAssembly, SendsLaterChunksContributionsToDeferredBlocksInElementOrder) {
  Trace t = edge_sum_trace();
  ASSERT_EQ(defer_assembly(t), "");
  EXPECT_TRUE(t.deferred);
  EXPECT_EQ(verify(t), "");
  ASSERT_EQ(t.arrays.size(), 3u);  // the result, its member table, its deferred blocks
  EXPECT_EQ(t.arrays[1].kind, ArraySlot::Kind::Table);
  EXPECT_EQ(t.arrays[1].components, 3);
  EXPECT_EQ(t.arrays[2].kind, ArraySlot::Kind::Deferred);
  EXPECT_EQ(t.body[1].member, 2);

  // A path 0-1-2-3-4 and an edge (4, 0), in chunks of 2 edges: vertex 2 is first written by
  // chunk 0 (edge 1), then by chunk 1 (edge 2); vertex 4 by chunk 1, then chunk 2; vertex 0
  // by chunk 0, then chunk 2.
  runtime::Set v("v");
  v.add_many(5);
  runtime::Set e("e", {&v, &v});
  const std::vector<int32_t> ends = {0, 1, 1, 2, 2, 3, 3, 4, 4, 0};
  e.add_edges(ends);
  DeferredPlan plan;
  std::vector<DeferredPlan::Source> sources(1);
  sources[0].blocks = 5;
  ASSERT_TRUE(plan.prepare(t, e, sources, 2, true));
  const int32_t* table = plan.table(0);
  // Per edge: (element, endpoint 0, endpoint 1); only the endpoints are written.
  EXPECT_EQ(table[0 * 3 + 1], 0);
  EXPECT_EQ(table[1 * 3 + 2], 2);
  // Deferred block 0 is the sink of the entries a specialised pattern leaves out.
  EXPECT_EQ(table[2 * 3 + 1], -2);  // edge 2 at vertex 2: deferred block 1
  EXPECT_EQ(table[2 * 3 + 2], 3);
  EXPECT_EQ(table[3 * 3 + 2], 4);
  EXPECT_EQ(table[4 * 3 + 1], -3);  // edge 4 at vertex 4: deferred block 2
  EXPECT_EQ(table[4 * 3 + 2], -4);  // edge 4 at vertex 0: deferred block 3
  EXPECT_EQ(plan.deferred_blocks(), 3);
  // Deferred blocks start at -0.0 (an addition into one gives the value added exactly) and
  // are added to their blocks after the run.
  double* d = plan.deferred(0);
  EXPECT_TRUE(std::signbit(d[1]) && d[1] == 0.0);
  d[0] += 100.0;  // the sink: added nowhere
  d[1] += 0.5;
  d[2] += 0.25;
  std::vector<double> f = {1.0, 1.0, 1.0, 2.0, 2.0};
  plan.finish({f.data()});
  EXPECT_EQ(f, (std::vector<double>{1.0, 1.0, 1.5, 2.0, 2.25}));
  // In element order (split false), every entry is the block itself.
  ASSERT_TRUE(plan.prepare(t, e, sources, 2, false));
  EXPECT_EQ(plan.table(0)[2 * 3 + 1], 2);
  EXPECT_EQ(plan.table(0)[4 * 3 + 2], 0);
}

TEST(DeferAssembly, RefusesWhatChunksCouldNotSplit) {
  Trace twice = edge_sum_trace();
  twice.body.push_back(twice.body[0]);  // one component written twice
  EXPECT_NE(defer_assembly(twice), "");
  EXPECT_FALSE(twice.deferred);

  Trace t = edge_sum_trace();
  ASSERT_EQ(defer_assembly(t), "");
  // A loop edge writes one vertex through both endpoints: no split on this topology.
  runtime::Set v("v");
  v.add_many(3);
  runtime::Set e("e", {&v, &v});
  const std::vector<int32_t> ends = {0, 1, 2, 2};
  e.add_edges(ends);
  DeferredPlan plan;
  std::vector<DeferredPlan::Source> sources(1);
  sources[0].blocks = 3;
  EXPECT_FALSE(plan.prepare(t, e, sources, 1, true));
  EXPECT_EQ(plan.table(0)[1 * 3 + 1], 2);  // the plain table, to run in element order
}

}  // namespace
}  // namespace simit::jit
