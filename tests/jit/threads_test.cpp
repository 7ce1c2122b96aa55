// The engine's thread pool and the threaded executor (jit/thread_pool.h, jit/executor.h):
// every task exactly once, every element exactly once, the lowest failure reported, an
// interrupt stopping every thread; and the deferred assembly's tables (jit/deferred_plan.h).
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstring>
#include <mutex>
#include <random>
#include <thread>
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

TEST(ThreadPool, RunsEveryTaskOnceWithMoreThreadsThanCpus) {
  // The workers and the caller yield their cores between polls rather than spin.
  for (int cpus : {1, 2}) {
    ThreadPool pool(5, cpus);
    for (int64_t tasks : {1, 3, 5, 40}) {
      for (int job = 0; job < 30; ++job) {
        std::vector<std::atomic<int>> runs(static_cast<size_t>(tasks));
        pool.run(tasks, [&](int64_t i) { runs[static_cast<size_t>(i)].fetch_add(1); });
        for (int64_t i = 0; i < tasks; ++i) ASSERT_EQ(runs[static_cast<size_t>(i)].load(), 1);
      }
    }
  }
}

TEST(ThreadPool, RunsEveryTaskOnceWhenThreadsTakeFromEachOthersRanges) {
  // Tasks of uneven cost, so that threads finish their home ranges at different times and
  // take tasks from the back of the others'; and a run of more tasks than one job holds.
  std::mt19937 rng(7);
  for (int threads : {2, 3, 7}) {
    ThreadPool pool(threads);
    for (int job = 0; job < 50; ++job) {
      const int64_t tasks = std::uniform_int_distribution<int64_t>(2, 300)(rng);
      std::vector<std::atomic<int>> runs(static_cast<size_t>(tasks));
      pool.run(tasks, [&](int64_t i) {
        volatile double x = 0;
        for (int64_t k = 0; k < (i % 5 == 0 ? 20000 : 10); ++k) x = x + 1.0;
        runs[static_cast<size_t>(i)].fetch_add(1);
      });
      for (int64_t i = 0; i < tasks; ++i) ASSERT_EQ(runs[static_cast<size_t>(i)].load(), 1) << i;
    }
  }
  ThreadPool pool(3);
  const int64_t many = 150000;  // three jobs of at most 65535 tasks
  std::vector<std::atomic<int>> runs(static_cast<size_t>(many));
  pool.run(many, [&](int64_t i) { runs[static_cast<size_t>(i)].fetch_add(1); });
  for (int64_t i = 0; i < many; ++i) ASSERT_EQ(runs[static_cast<size_t>(i)].load(), 1) << i;
}

TEST(ThreadPool, RunsEachGivenRangeOnceAndTheCallerTakesTheRangeOfAWorkerThatSleeps) {
  static std::vector<std::atomic<int>> runs(64);
  static std::vector<std::thread::id> by(64);
  static std::atomic<int> unit_cost{0};
  auto op = [](const int64_t*, int64_t first, int64_t end) {
    volatile double x = 0;
    for (int64_t u = first; u < end; ++u) {
      for (int k = 0; k < unit_cost.load(); ++k) x = x + 1.0;
      runs[static_cast<size_t>(u)].fetch_add(1);
      by[static_cast<size_t>(u)] = std::this_thread::get_id();
    }
  };
  const std::vector<int64_t> bounds = {0, 5, 5, 17, 40};  // range 1 empty
  for (int cpus : {0, 1}) {  // 0: the machine's, 1: more threads than CPUs
    ThreadPool pool(4, cpus);
    for (int call = 0; call < 200; ++call) {
      unit_cost.store(call % 3 == 0 ? 2000 : 10);
      for (auto& r : runs) r.store(0);
      std::vector<double> times(4, -1.0);
      pool.run_ranges(op, nullptr, bounds.data(), 4, times.data());
      for (int64_t u = 0; u < 64; ++u)
        ASSERT_EQ(runs[static_cast<size_t>(u)].load(), u < 40 ? 1 : 0) << cpus << " " << u;
      for (double t : times) EXPECT_GE(t, 0.0);
    }
  }
  // A worker asleep (the pool idle for longer than its workers spin) takes microseconds to
  // wake, and the caller, done with its own range, runs the others' itself: at once in a pool
  // with more threads than CPUs (asserted: the caller tries before the worker can have woken),
  // after 10 us in the others (each range still runs once, whoever runs it).
  const std::thread::id caller = std::this_thread::get_id();
  const std::vector<int64_t> three = {0, 1, 2, 3};
  unit_cost.store(0);
  for (int cpus : {1, 0}) {
    ThreadPool pool(3, cpus);
    bool took = false;
    for (int trial = 0; trial < (cpus == 1 ? 200 : 20) && !(took && cpus == 1); ++trial) {
      std::this_thread::sleep_for(std::chrono::milliseconds(8));  // workers poll for 5 ms
      for (auto& r : runs) r.store(0);
      std::vector<double> times(3, -1.0);
      pool.run_ranges(op, nullptr, three.data(), 3, times.data());
      for (int64_t u = 0; u < 3; ++u) ASSERT_EQ(runs[static_cast<size_t>(u)].load(), 1);
      took = took || by[1] == caller || by[2] == caller;
    }
    if (cpus == 1) {
      EXPECT_TRUE(took) << "the caller never ran a sleeping worker's range";
    }
  }
}

TEST(ParallelFor, RunsOneContiguousRangePerThreadCoveringEveryUnitOnce) {
  static std::mutex mutex;
  static std::vector<std::pair<int64_t, int64_t>> seen;
  auto op = [](const int64_t*, int64_t first, int64_t end) {
    // Units 0-4 cost far more than the rest, so that the learnt bounds move from call to call
    // (RangeSplit's own test checks where to; here the ranges must cover every unit whatever
    // the bounds).
    volatile double x = 0;
    for (int64_t u = first; u < end; ++u)
      for (int k = 0; k < (u < 5 ? 20000 : 100); ++k) x = x + 1.0;
    std::lock_guard lock(mutex);
    seen.emplace_back(first, end);
  };
  for (int threads : {1, 2, 3, 7}) {
    ThreadPool pool(threads);
    for (int64_t units : {1, 2, 15, 40}) {
      for (int call = 0; call < 20; ++call) {
        seen.clear();
        simit_jit_parallel_for(&pool, op, nullptr, units);
        std::sort(seen.begin(), seen.end());
        ASSERT_FALSE(seen.empty());
        EXPECT_LE(static_cast<int64_t>(seen.size()), std::min<int64_t>(threads, units));
        EXPECT_EQ(seen.front().first, 0);
        EXPECT_EQ(seen.back().second, units);
        for (size_t i = 0; i < seen.size(); ++i) {
          EXPECT_LT(seen[i].first, seen[i].second);
          if (i > 0) {
            EXPECT_EQ(seen[i].first, seen[i - 1].second) << threads << " " << units;
          }
        }
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

// A trace adding 1.0 into each of `pairs` blocks of a matrix result per element.
Trace matrix_sum_trace(int arity, int pairs) {
  Trace t;
  t.arity = arity;
  t.reduce = true;
  ArraySlot r;
  r.kind = ArraySlot::Kind::Result;
  r.written = true;
  r.name = "K";
  t.arrays.push_back(r);
  t.pairs = {pairs};
  for (int p = 0; p < pairs; ++p) {
    auto one = std::make_shared<Expr>();
    one->f = 1.0;
    Stmt s;
    s.kind = StmtKind::Assemble;
    s.pair = p;
    s.value = one;
    t.body.push_back(s);
  }
  return t;
}

// The split tables of a plan, computed here the plain way: walking the elements in order, a
// block's entries point at it while they lie in the chunk of its first writer, and every
// later one takes the next deferred block; the gather index lists, per block in ascending
// order, its deferred blocks in ascending order.
struct ReferenceSplit {
  std::vector<int32_t> table;
  std::vector<int32_t> dest = {-1};
  std::vector<int32_t> gather_block, gather_start = {0}, gather_k;
};

ReferenceSplit reference_split(const std::vector<int32_t>& source, int stride,
                               const std::vector<int>& written, int32_t n, int32_t chunk,
                               int32_t blocks) {
  ReferenceSplit r;
  r.table.assign(source.size(), 0);
  std::vector<int32_t> first(static_cast<size_t>(blocks), -1);
  for (int32_t e = 0; e < n; ++e)
    for (int w : written) {
      const size_t at = static_cast<size_t>(e) * static_cast<size_t>(stride) + w;
      const int32_t b = source[at];
      if (b < 0) {
        r.table[at] = -1;
        continue;
      }
      if (first[static_cast<size_t>(b)] < 0) first[static_cast<size_t>(b)] = e;
      if (first[static_cast<size_t>(b)] / chunk == e / chunk) {
        r.table[at] = b;
      } else {
        r.table[at] = -1 - static_cast<int32_t>(r.dest.size());
        r.dest.push_back(b);
      }
    }
  std::vector<std::vector<int32_t>> of(static_cast<size_t>(blocks));
  for (size_t k = 1; k < r.dest.size(); ++k)
    of[static_cast<size_t>(r.dest[k])].push_back(static_cast<int32_t>(k));
  for (int32_t b = 0; b < blocks; ++b) {
    if (of[static_cast<size_t>(b)].empty()) continue;
    r.gather_k.insert(r.gather_k.end(), of[static_cast<size_t>(b)].begin(),
                      of[static_cast<size_t>(b)].end());
    r.gather_block.push_back(b);
    r.gather_start.push_back(static_cast<int32_t>(r.gather_k.size()));
  }
  return r;
}

void expect_split(const DeferredPlan& plan, const ReferenceSplit& want, const std::string& what) {
  const int32_t* table = plan.table(0);
  ASSERT_NE(table, nullptr) << what;
  for (size_t i = 0; i < want.table.size(); ++i)
    ASSERT_EQ(table[i], want.table[i]) << what << ", entry " << i;
  EXPECT_EQ(plan.deferred_blocks(), static_cast<int64_t>(want.dest.size()) - 1) << what;
  const std::vector<DeferredPlan::Gather> g = plan.gathers();
  ASSERT_EQ(g.size(), 1u) << what;
  ASSERT_EQ(g[0].blocks, want.gather_block.size()) << what;
  for (size_t i = 0; i < g[0].blocks; ++i) {
    ASSERT_EQ(g[0].block[i], want.gather_block[i]) << what << ", gathered block " << i;
    ASSERT_EQ(g[0].start[i + 1], want.gather_start[i + 1]) << what << ", gathered block " << i;
  }
  for (size_t j = 0; j < want.gather_k.size(); ++j)
    ASSERT_EQ(g[0].k[j], want.gather_k[j]) << what << ", gather entry " << j;
  for (size_t v = 0; v < g[0].deferred_values; ++v)
    ASSERT_TRUE(g[0].deferred[v] == 0.0 && std::signbit(g[0].deferred[v])) << what;
}

// Triangles over a strip of vertices (each near the one before, as a renumbered mesh's are)
// in chunks of every size from one element to all of them, written as a vector (through the
// endpoints) and as a matrix whose table leaves some blocks out (the sink).
TEST(DeferredPlan, SplitTablesMatchTheElementOrderOnRandomTopologies) {
  std::mt19937 rng(7);
  for (int round = 0; round < 4; ++round) {
    const int32_t verts = 40 + round * 150, n = verts * 2;
    runtime::Set v("v");
    v.add_many(verts);
    runtime::Set tri("tri", {&v, &v, &v});
    std::vector<int32_t> ends;
    for (int32_t e = 0; e < n; ++e) {
      const int32_t base = std::min(e / 2, verts - 12);  // 12 vertices to pick 3 from
      std::vector<int32_t> picked;
      while (picked.size() < 3) {
        const int32_t x = base + static_cast<int32_t>(rng() % 12);
        if (std::find(picked.begin(), picked.end(), x) == picked.end()) picked.push_back(x);
      }
      ends.insert(ends.end(), picked.begin(), picked.end());
    }
    tri.add_edges(ends);
    // The vector: its member table (element, then each endpoint), endpoints written.
    Trace vt = edge_sum_trace();
    vt.arity = 3;
    vt.body.push_back(vt.body[0]);
    auto third = std::make_shared<Expr>(*vt.body[0].index);
    third->slot = 2;
    vt.body[2].index = third;
    ASSERT_EQ(defer_assembly(vt), "");
    std::vector<int32_t> members(static_cast<size_t>(n) * 4, 0);
    for (int32_t e = 0; e < n; ++e)
      for (int k = 0; k < 3; ++k)
        members[static_cast<size_t>(e) * 4 + 1 + k] = ends[static_cast<size_t>(e) * 3 + k];
    // The matrix: 6 blocks per element, each a block of its own or (one in five) left out.
    const int pairs = 6;
    Trace mt = matrix_sum_trace(3, pairs);
    ASSERT_EQ(defer_assembly(mt), "");
    const int32_t blocks = n * 2;
    std::vector<int32_t> table(static_cast<size_t>(n) * pairs);
    for (int32_t e = 0; e < n; ++e) {
      std::vector<int32_t> mine;
      for (int p = 0; p < pairs; ++p) {
        int32_t b = -1;
        if (rng() % 5 != 0) {
          do {
            b = std::min(blocks - 1, e + static_cast<int32_t>(rng() % 40));
          } while (std::find(mine.begin(), mine.end(), b) != mine.end());
          mine.push_back(b);
        }
        table[static_cast<size_t>(e) * pairs + p] = b;
      }
    }
    for (int32_t chunk : {1, 2, 3, 7, 16, 61, n - 1, n}) {
      const std::string what =
          "round " + std::to_string(round) + ", chunk " + std::to_string(chunk);
      DeferredPlan vp;
      std::vector<DeferredPlan::Source> vs(1);
      vs[0].blocks = verts;
      ASSERT_TRUE(vp.prepare(vt, tri, vs, chunk, true)) << what;
      expect_split(vp, reference_split(members, 4, {1, 2, 3}, n, chunk, verts), what + " (vector)");
      DeferredPlan mp;
      std::vector<DeferredPlan::Source> ms(1);
      ms[0].table = table.data();
      ms[0].blocks = blocks;
      ms[0].components = 4;
      ASSERT_TRUE(mp.prepare(mt, tri, ms, chunk, true)) << what;
      expect_split(mp, reference_split(table, pairs, {0, 1, 2, 3, 4, 5}, n, chunk, blocks),
                   what + " (matrix)");
      // Prepared again for the next call: the same tables, the deferred blocks at -0.0 again.
      mp.deferred(0)[0] = 3.0;
      ASSERT_TRUE(mp.prepare(mt, tri, ms, chunk, true)) << what;
      expect_split(mp, reference_split(table, pairs, {0, 1, 2, 3, 4, 5}, n, chunk, blocks),
                   what + " (matrix, again)");
      // A block written twice by one element cannot be split.
      std::vector<int32_t> twice = table;
      twice[static_cast<size_t>(n / 2) * pairs + 1] = 0;
      twice[static_cast<size_t>(n / 2) * pairs + 4] = 0;
      ms[0].table = twice.data();
      EXPECT_FALSE(mp.prepare(mt, tri, ms, chunk, true)) << what;
    }
  }
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
