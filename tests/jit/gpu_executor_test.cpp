// The GPU executor (jit/ptx/gpu_executor.h) without a GPU: its launch path and copies against
// a fake driver table (the gather kernel of a deferred assembly among them), and the gather
// kernel's PTX through ptxas. Its whole data path over host memory: gpu_emulation_test.cpp;
// what stays on the device between calls: gpu_residency_test.cpp.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <string>
#include <vector>

#include "gpu_fake_driver.h"
#include "jit/array_stamps.h"
#include "jit/defer_assembly.h"
#include "jit/deferred_plan.h"
#include "jit/ptx/cuda_driver.h"
#include "jit/ptx/gather_kernel.h"
#include "jit/ptx/gpu_executor.h"
#include "jit/ptx/ptx_check.h"
#include "jit/ptx/ptx_target.h"
#include "runtime/set.h"

namespace simit::jit::ptx {
namespace {

using namespace simit::jit::cuda;
using namespace fake_gpu;

TEST_F(GpuExecutorFake, CopiesInLaunchesOneThreadPerElementAndCopiesWritesBack) {
  auto executor = make_gpu_executor_over(fake_table());
  EXPECT_TRUE(is_gpu_executor(*executor));
  EXPECT_FALSE(is_emulated_gpu_executor(*executor));
  EXPECT_EQ(executor->chunk_for(1000), 1);
  EXPECT_TRUE(executor->parallel());
  PtxKernel kernel;
  kernel.ptx = "// the kernel's PTX";
  kernel.entry = kMapEntry;

  double in[4] = {1, 2, 3, 4}, out[3] = {0, 0, 0};
  const double scalars[1] = {2.5};
  void* arrays[2] = {in, out};
  const size_t bytes[2] = {sizeof in, sizeof out};
  const uint8_t written[2] = {0, 1};
  MapArgs args{arrays, scalars, nullptr};
  args.array_count = 2;
  args.array_bytes = bytes;
  args.array_written = written;
  args.scalar_count = 1;

  double seen_scalar = 0, seen_in = 0;
  state.on_launch = [&](const Launch& l) {
    CUdeviceptr* table = at<CUdeviceptr>(l.table);
    seen_in = at<double>(table[0])[3];
    seen_scalar = at<double>(l.scalars)[0];
    at<double>(table[0])[0] = 99;  // a read-only array's device copy: never copied back
    for (int i = 0; i < 3; ++i) at<double>(table[1])[i] = 10 + i;
    *at<uint64_t>(l.failure) = (uint64_t{7} << 32) | 2;  // element 7 failed check 2
  };
  // A failed check copies every written array back, a deferred map's too.
  const MapOutcome o = executor->run_map(kernel, args, 300, 1, MapWrites::Deferred, {});
  EXPECT_EQ(state.ptx, kernel.ptx);
  ASSERT_EQ(state.launches.size(), 1u);
  EXPECT_EQ(state.launches[0].grid, 3u);  // 300 elements in blocks of 128 threads
  EXPECT_EQ(state.launches[0].block, 128u);
  EXPECT_EQ(state.launches[0].begin, 0);
  EXPECT_EQ(state.launches[0].end, 300);
  EXPECT_EQ(seen_in, 4.0);
  EXPECT_EQ(seen_scalar, 2.5);
  EXPECT_EQ(o.code, 3);
  EXPECT_EQ(o.element, 7);
  EXPECT_EQ(in[0], 1.0);
  EXPECT_EQ(out[0], 10.0);
  EXPECT_EQ(out[2], 12.0);
  const GpuTraffic t = gpu_traffic(*executor);
  EXPECT_EQ(t.launches, 1);
  EXPECT_EQ(t.bytes_to_device, static_cast<long long>(sizeof in + sizeof out + sizeof scalars));
  EXPECT_EQ(t.bytes_to_host, static_cast<long long>(sizeof out));

  // Again: the device memory is reused, the arrays copied in again (the host may have
  // changed them), and no check failed this time.
  const int allocations = state.allocations;
  in[3] = -4;
  state.on_launch = [&](const Launch& l) { seen_in = at<double>(at<CUdeviceptr>(l.table)[0])[3]; };
  const MapOutcome again = executor->run_map(kernel, args, 300, 1, MapWrites::Disjoint, {});
  EXPECT_EQ(again.code, 0);
  EXPECT_EQ(again.element, -1);
  EXPECT_EQ(seen_in, -4.0);
  EXPECT_EQ(state.allocations, allocations);
  executor.reset();
  EXPECT_EQ(state.frees, state.allocations);  // everything freed with the executor
}

TEST_F(GpuExecutorFake, SharedBlocksWithoutDeferredWritesRunOneElementAtATimeInOrder) {
  auto executor = make_gpu_executor_over(fake_table());
  PtxKernel kernel;
  kernel.ptx = "//";
  kernel.entry = kMapEntry;
  double out[2] = {0, 0};
  void* arrays[1] = {out};
  const size_t bytes[1] = {sizeof out};
  const uint8_t written[1] = {1};
  MapArgs args{arrays, nullptr, nullptr};
  args.array_count = 1;
  args.array_bytes = bytes;
  args.array_written = written;
  executor->run_map(kernel, args, 5, 1, MapWrites::Shared, {});
  ASSERT_EQ(state.launches.size(), 5u);
  for (int e = 0; e < 5; ++e) {
    EXPECT_EQ(state.launches[e].begin, e);
    EXPECT_EQ(state.launches[e].end, e + 1);
    EXPECT_EQ(state.launches[e].grid, 1u);
  }
}

TEST_F(GpuExecutorFake, AnInterruptBeforeTheLaunchStopsIt) {
  auto executor = make_gpu_executor_over(fake_table());
  PtxKernel kernel;
  MapArgs args;
  const size_t bytes[1] = {0};
  const uint8_t written[1] = {0};
  args.array_bytes = bytes;
  args.array_written = written;
  const MapOutcome o =
      executor->run_map(kernel, args, 10, 1, MapWrites::Disjoint, [] { return true; });
  EXPECT_TRUE(o.interrupted);
  EXPECT_TRUE(state.launches.empty());
}

TEST_F(GpuExecutorFake, ACpuKernelIsRefused) {
  auto executor = make_gpu_executor_over(fake_table());
  struct CpuKernel : Kernel {
    int32_t run(const MapArgs&, ElementRange, int32_t*) const override { return 0; }
    int32_t run(const SystemArgs&) const override { return 0; }
  } cpu;
  MapArgs args;
  const size_t bytes[1] = {0};
  const uint8_t written[1] = {0};
  args.array_bytes = bytes;
  args.array_written = written;
  EXPECT_THROW(executor->run_map(cpu, args, 10, 1, MapWrites::Disjoint, {}), std::logic_error);
}

// ---- A deferred assembly: the map kernel, then the gather kernel, on the device.

// A trace adding a value at both endpoints of each edge into a vector result of one
// component, rewritten with deferred writes (slots: the result, its member table, its
// deferred blocks).
Trace deferred_edge_sum() {
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
  EXPECT_EQ(defer_assembly(t), "");
  return t;
}

// Element e's contribution at its endpoint m: values whose sums round, so that a sum in
// another order shows in the bits.
double contribution(int e, int m) { return 1.0 / (3.0 + e) + (m ? 0.1 : 1e-17 * e); }

// The interpreter's sums: each vertex's contributions added in element order from 0.
std::vector<double> sums_in_element_order(const std::vector<int32_t>& ends, int verts) {
  std::vector<double> f(static_cast<size_t>(verts), 0.0);
  for (size_t e = 0; 2 * e < ends.size(); ++e)
    for (int m = 0; m < 2; ++m) f[static_cast<size_t>(ends[2 * e + m])] += contribution(e, m);
  return f;
}

// Runs the deferred map over `edges` (its plan prepared for chunks of one) through
// `executor`, the fake's map kernel doing what the compiled kernel does on the device
// copies, then finish_deferred. Returns the result's values.
struct DeferredRun {
  std::vector<double> f;
  std::vector<double> deferred_after;    // the host's deferred blocks afterwards
  std::vector<uint64_t> deferred_seen;   // the device's, as the map kernel found them
  long long to_device = 0, to_host = 0;  // the fake's copies during this run
};
// A map kernel whose PTX names an architecture other than the default (the gather module
// follows it). Static: the executor keeps its loaded function by the kernel's address.
const PtxKernel& sm90a_kernel() {
  static const PtxKernel k = [] {
    PtxKernel p;
    p.ptx = "//\n.version 8.0\n.target sm_90a\n.address_size 64\n";
    p.entry = kMapEntry;
    return p;
  }();
  return k;
}

// With `bound`, the arrays bound as the trace controller binds a split run (site_kernel.cpp):
// the result zeroed, the split table stamped by the plan's build, the deferred blocks at
// -0.0, the endpoint table stamped by the topology.
DeferredRun run_deferred(Executor& executor, const Trace& t, DeferredPlan& plan,
                         const runtime::Set& edges, int verts, bool bound = false) {
  std::vector<DeferredPlan::Source> sources(1);
  sources[0].blocks = verts;
  EXPECT_TRUE(plan.prepare(t, edges, sources, executor.chunk_for(edges.size()), true));
  DeferredRun run;
  run.f.assign(static_cast<size_t>(verts), 0.0);
  void* arrays[3] = {run.f.data(), const_cast<int32_t*>(plan.table(0)), plan.deferred(0)};
  const size_t bytes[3] = {run.f.size() * sizeof(double), plan.table_entries(0) * sizeof(int32_t),
                           plan.deferred_values(0) * sizeof(double)};
  uint8_t written[3];
  for (int i = 0; i < 3; ++i) written[i] = t.arrays[static_cast<size_t>(i)].written ? 1 : 0;
  EXPECT_EQ(written[0] + written[1] * 2 + written[2] * 4, 1 + 4);
  MapArgs args{arrays, nullptr, edges.endpoints()};
  args.array_count = 3;
  args.array_bytes = bytes;
  args.array_written = written;
  args.arity = 2;
  const uint64_t split = stamp(StampKind::Split, {plan.build_id(), 0});
  const uint64_t versions[3] = {0, split, 0};
  const ArrayFill fill[3] = {ArrayFill::Zero, ArrayFill::Copy, ArrayFill::NegativeZero};
  if (bound) {
    args.array_version_in = args.array_version_out = versions;
    args.array_fill = fill;
    args.endpoints_version = endpoints_stamp(edges);
  }
  const size_t deferred_values = plan.deferred_values(0);
  fake->on_launch = [&run, deferred_values](const Launch& l) {
    if (l.gather) return;
    const CUdeviceptr* table = at<CUdeviceptr>(l.table);
    double* f = at<double>(table[0]);
    const int32_t* entries = at<int32_t>(table[1]);
    double* deferred = at<double>(table[2]);
    run.deferred_seen.resize(deferred_values);
    std::memcpy(run.deferred_seen.data(), deferred, deferred_values * sizeof(double));
    for (int32_t e = l.begin; e < l.end; ++e)
      for (int m = 0; m < 2; ++m) {
        const int32_t to = entries[3 * e + 1 + m];
        (to >= 0 ? f[to] : deferred[-1 - to]) += contribution(e, m);
      }
  };
  const long long to_device = fake->to_device, to_host = fake->to_host;
  const MapOutcome o = executor.run_map(sm90a_kernel(), args, edges.size(),
                                        executor.chunk_for(edges.size()), MapWrites::Deferred, {});
  EXPECT_EQ(o.code, 0);
  // The gather launch adds on the "device" copies; the fake does it as finish does (deferred
  // blocks outside, components inside).
  fake->on_launch = [](const Launch& l) {
    if (!l.gather) return;
    for (uint32_t i = 0; i < l.g.blocks; ++i)
      for (int32_t j = l.g.start[i]; j < l.g.start[i + 1]; ++j)
        for (uint32_t c = 0; c < l.g.components; ++c)
          l.g.values[static_cast<size_t>(l.g.block[i]) * l.g.components + c] +=
              l.g.deferred[static_cast<size_t>(l.g.k[j]) * l.g.components + c];
  };
  executor.finish_deferred(plan, {run.f.data()});
  run.to_device = fake->to_device - to_device;
  run.to_host = fake->to_host - to_host;
  run.deferred_after.assign(plan.deferred(0), plan.deferred(0) + plan.deferred_values(0));
  return run;
}

TEST_F(GpuExecutorFake, ADeferredMapLaunchesTheGatherAndCopiesBackOnlyTheResults) {
  auto executor = make_gpu_executor_over(fake_table());
  const Trace t = deferred_edge_sum();
  ASSERT_EQ(t.arrays.size(), 3u);
  ASSERT_EQ(t.arrays[2].kind, ArraySlot::Kind::Deferred);
  // Vertex 0 in five edges, the others in two or three: many deferred blocks per block.
  runtime::Set v("v");
  v.add_many(6);
  runtime::Set e("e", {&v, &v});
  const std::vector<int32_t> ends = {0, 1, 2, 0, 0, 3, 1, 2, 4, 0, 2, 3, 0, 5, 5, 4};
  e.add_edges(ends);
  DeferredPlan plan;
  const DeferredRun run = run_deferred(*executor, t, plan, e, 6);

  // The map kernel over every element, then one gather: one thread per block that has
  // deferred blocks (vertices 0 to 5 all do), over the device copies of the result and the
  // deferred blocks, with the plan's gather index copied to the device.
  ASSERT_EQ(state.launches.size(), 2u);
  EXPECT_FALSE(state.launches[0].gather);
  EXPECT_EQ(state.launches[0].begin, 0);
  EXPECT_EQ(state.launches[0].end, 8);
  const Launch& g = state.launches[1];
  ASSERT_TRUE(g.gather);
  EXPECT_EQ(g.grid, 1u);
  EXPECT_EQ(g.block, 128u);
  const std::vector<DeferredPlan::Gather> gathers = plan.gathers();
  ASSERT_EQ(gathers.size(), 1u);
  const DeferredPlan::Gather& d = gathers[0];
  EXPECT_EQ(d.blocks, 6u);
  EXPECT_EQ(plan.deferred_blocks(), 10);  // 16 contributions, 6 of them in place
  EXPECT_EQ(g.g.blocks, 6u);
  EXPECT_EQ(g.g.components, 1u);
  const CUdeviceptr* table = at<CUdeviceptr>(state.launches[0].table);
  EXPECT_EQ(reinterpret_cast<CUdeviceptr>(g.g.values), table[0]);
  EXPECT_EQ(reinterpret_cast<CUdeviceptr>(g.g.deferred), table[2]);
  for (const void* p : {static_cast<const void*>(g.g.block), static_cast<const void*>(g.g.start),
                        static_cast<const void*>(g.g.k)})
    for (const void* host : {static_cast<const void*>(d.block), static_cast<const void*>(d.start),
                             static_cast<const void*>(d.k)})
      EXPECT_NE(p, host);  // device copies, not the plan's
  EXPECT_EQ(std::vector<int32_t>(g.g.block, g.g.block + 6),
            std::vector<int32_t>(d.block, d.block + 6));
  EXPECT_EQ(std::vector<int32_t>(g.g.start, g.g.start + 7),
            std::vector<int32_t>(d.start, d.start + 7));
  EXPECT_EQ(g.g.start[6], 10);
  EXPECT_EQ(std::vector<int32_t>(g.g.k, g.g.k + 10), std::vector<int32_t>(d.k, d.k + 10));

  // The interpreter's sums, bit for bit, from the device.
  EXPECT_EQ(run.f, sums_in_element_order(ends, 6));
  // Copied back: the result (and the failure word); the deferred blocks stayed on the device
  // (the host's are the -0.0 they were prepared with).
  const long long result_bytes = 6 * sizeof(double);
  EXPECT_EQ(run.to_host, result_bytes + static_cast<long long>(sizeof(uint64_t)));
  for (double x : run.deferred_after) EXPECT_TRUE(x == 0.0 && std::signbit(x));
  GpuTraffic traffic = gpu_traffic(*executor);
  EXPECT_EQ(traffic.bytes_to_host, result_bytes);
  EXPECT_EQ(traffic.launches, 2);
  EXPECT_EQ(traffic.gather_launches, 1);
  EXPECT_EQ(traffic.index_uploads, 1);
  // The gather module is written for the map kernels' architecture and PTX version.
  ASSERT_EQ(state.modules.size(), 2u);
  EXPECT_NE(state.modules[1].find(".entry simit_gather("), std::string::npos);
  EXPECT_NE(state.modules[1].find(".target sm_90a\n"), std::string::npos) << state.modules[1];
  EXPECT_NE(state.modules[1].find(".version 8.0\n"), std::string::npos) << state.modules[1];

  // Again on the same topology: the index is not uploaded again (the copies in are those of
  // the first run less the index: block, start and k), the module not loaded again.
  const long long index_bytes = (6 + 7 + 10) * static_cast<long long>(sizeof(int32_t));
  const DeferredRun again = run_deferred(*executor, t, plan, e, 6);
  EXPECT_EQ(again.f, run.f);
  EXPECT_EQ(again.to_device, run.to_device - index_bytes);
  EXPECT_EQ(again.to_host, run.to_host);
  traffic = gpu_traffic(*executor);
  EXPECT_EQ(traffic.index_uploads, 1);
  EXPECT_EQ(traffic.gather_launches, 2);
  EXPECT_EQ(traffic.bytes_to_host, 2 * result_bytes);
  EXPECT_EQ(state.modules.size(), 2u);

  // A new topology (an edge more): the plan is built anew and its index uploaded again.
  std::vector<int32_t> more = ends;
  more.insert(more.end(), {3, 0});
  e.add_edges(std::vector<int32_t>{3, 0});
  const DeferredRun grown = run_deferred(*executor, t, plan, e, 6);
  EXPECT_EQ(grown.f, sums_in_element_order(more, 6));
  traffic = gpu_traffic(*executor);
  EXPECT_EQ(traffic.index_uploads, 2);
  EXPECT_EQ(state.launches.size(), 6u);
  EXPECT_EQ(state.launches[5].g.start[6], 12);  // both new contributions deferred
  executor.reset();
  EXPECT_EQ(state.frees, state.allocations);  // the index arrays too
}

// Bound as the controller binds a split run: the deferred blocks are never copied in, but set
// to -0.0 on the device (every word zeroed, then each double's high word, at byte 4, set to
// the sign bit by a 2D set of one word per 8-byte row), so that the kernel finds -0.0 in every
// component, on the first call (fresh device memory) as on the second (what the last call's
// kernel left there). A second call copies in nothing but the pointer table and failure word.
TEST_F(GpuExecutorFake, ADeferredMapsDeferredBlocksAreSetToNegativeZeroOnTheDevice) {
  auto executor = make_gpu_executor_over(fake_table());
  const Trace t = deferred_edge_sum();
  runtime::Set v("v");
  v.add_many(6);
  runtime::Set e("e", {&v, &v});
  const std::vector<int32_t> ends = {0, 1, 2, 0, 0, 3, 1, 2, 4, 0, 2, 3, 0, 5, 5, 4};
  e.add_edges(ends);
  DeferredPlan plan;
  // From the shape: 8 edges, a table of 3 entries an edge, 16 contributions of which 6 in
  // place, so 10 deferred blocks and the sink of one component, 6 result blocks, the gather
  // index of 6 blocks (block, start, k), 3 array pointers.
  const long long table_bytes = 8 * 3 * 4, ends_bytes = 8 * 2 * 4, deferred_bytes = 11 * 8,
                  result_bytes = 6 * 8, index_bytes = (6 + 7 + 10) * 4, launch_in = 3 * 8 + 8;
  const uint64_t negative_zero = 0x8000000000000000ull;
  for (int call = 0; call < 2; ++call) {
    const GpuTraffic t0 = gpu_traffic(*executor);
    const long long zeroed0 = state.zeroed;
    const size_t sets0 = state.sets_2d.size();
    const DeferredRun run = run_deferred(*executor, t, plan, e, 6, true);
    const GpuTraffic t1 = gpu_traffic(*executor);
    ASSERT_EQ(plan.deferred_values(0), 11u);
    EXPECT_EQ(run.f, sums_in_element_order(ends, 6)) << call;
    ASSERT_EQ(run.deferred_seen.size(), 11u);
    for (uint64_t bits : run.deferred_seen) EXPECT_EQ(bits, negative_zero) << call;
    // Copied in: the split table, the endpoints and the index on the first call only.
    EXPECT_EQ(t1.bytes_to_device - t0.bytes_to_device,
              call == 0 ? table_bytes + ends_bytes + index_bytes : 0);
    EXPECT_EQ(run.to_device, (call == 0 ? table_bytes + ends_bytes + index_bytes : 0) + launch_in);
    EXPECT_EQ(t1.bytes_skipped - t0.bytes_skipped, call == 0 ? 0 : table_bytes + ends_bytes);
    EXPECT_EQ(t1.filled - t0.filled, 1);
    EXPECT_EQ(t1.bytes_filled - t0.bytes_filled, deferred_bytes);
    EXPECT_EQ(t1.bytes_zeroed - t0.bytes_zeroed, result_bytes);
    // The fake's memory sets: the result and the deferred blocks' words zeroed, then one 2D
    // set over the deferred blocks' high words.
    EXPECT_EQ(state.zeroed - zeroed0, result_bytes + deferred_bytes);
    ASSERT_EQ(state.sets_2d.size(), sets0 + 1);
    const Set2D& s = state.sets_2d.back();
    const CUdeviceptr* table = at<CUdeviceptr>(state.launches[state.launches.size() - 2].table);
    EXPECT_EQ(s.to, table[2] + 4);
    EXPECT_EQ(s.pitch, 8u);
    EXPECT_EQ(s.value, 0x80000000u);
    EXPECT_EQ(s.width, 1u);
    EXPECT_EQ(s.height, 11u);
  }
  executor.reset();
  EXPECT_EQ(state.frees, state.allocations);
}

TEST_F(GpuExecutorFake, TheGatherKernelsPtxAddsCorrectlyRoundedAndPtxasAcceptsIt) {
  const std::string p = gather_ptx();
  EXPECT_NE(p.find(".version 7.8\n"), std::string::npos) << p;
  EXPECT_NE(p.find(".target sm_90\n"), std::string::npos) << p;
  EXPECT_NE(p.find(".visible .entry simit_gather("), std::string::npos) << p;
  EXPECT_NE(p.find("add.rn.f64"), std::string::npos) << p;
  // --float32 (the last parameter): each sum rounded to binary32 and widened again.
  EXPECT_NE(p.find("@%p4 cvt.rn.f32.f64"), std::string::npos) << p;
  EXPECT_NE(p.find("@%p4 cvt.f64.f32"), std::string::npos) << p;
  EXPECT_EQ(p.find("fma"), std::string::npos) << p;
  EXPECT_EQ(p.find("atom"), std::string::npos) << p;
  EXPECT_NE(gather_ptx("sm_100", "8.6").find(".version 8.6\n.target sm_100\n"), std::string::npos);
  EXPECT_EQ(ptx_directive(p, ".target"), "sm_90");
  EXPECT_EQ(ptx_directive("// none\n", ".target"), "");
  std::string why;
  const std::string ptxas = find_ptxas(why);
  if (ptxas.empty()) GTEST_SKIP() << "ptxas not found: " << why;
  std::string message;
  EXPECT_TRUE(assemble(ptxas, p, kDefaultGpuArch, message)) << message;
}

// The host equivalent the emulation runs adds what finish adds, bit for bit, on a result of
// three components whose deferred blocks hold values whose sums round: in binary64, and
// under --float32 rounding each sum to binary32.
class GatherOnHost : public ::testing::TestWithParam<bool> {};

TEST_P(GatherOnHost, AddsAsDeferredPlanFinishDoes) {
  Trace t = deferred_edge_sum();
  t.float32 = GetParam();
  runtime::Set v("v");
  v.add_many(7);
  runtime::Set e("e", {&v, &v});
  std::vector<int32_t> ends;
  for (int i = 0; i < 40; ++i) ends.insert(ends.end(), {(i * 3) % 7, i % 2 ? 0 : (i * 5 + 1) % 7});
  for (size_t i = 0; i < ends.size(); i += 2)
    if (ends[i] == ends[i + 1]) ends[i + 1] = (ends[i] + 1) % 7;
  e.add_edges(ends);
  DeferredPlan plan;
  std::vector<DeferredPlan::Source> sources(1);
  sources[0].blocks = 7;
  sources[0].components = 3;
  ASSERT_TRUE(plan.prepare(t, e, sources, 1, true));
  double* deferred = plan.deferred(0);
  for (size_t i = 0; i < plan.deferred_values(0); ++i) deferred[i] = std::sin(1.0 + i) * 1e3;
  std::vector<double> by_finish(21), by_gather(21);
  for (size_t i = 0; i < by_finish.size(); ++i) by_finish[i] = by_gather[i] = 1.0 / (1.0 + i);
  plan.finish({by_finish.data()});
  const DeferredPlan::Gather d = plan.gathers().at(0);
  ASSERT_GT(d.blocks, 0u);
  EXPECT_EQ(d.round32, GetParam());
  GatherArgs a{
      by_gather.data(),   d.deferred, d.block, d.start, d.k, static_cast<uint32_t>(d.blocks), 3,
      d.round32 ? 1u : 0u};
  gather_on_host(a, 0, 2);  // threads apart, in any split, as the GPU's blocks run
  gather_on_host(a, 2, 1000);
  EXPECT_EQ(std::memcmp(by_finish.data(), by_gather.data(), 21 * sizeof(double)), 0);
  std::vector<double> before(21);
  for (size_t i = 0; i < before.size(); ++i) before[i] = 1.0 / (1.0 + i);
  EXPECT_NE(by_finish, before);  // something was added
  // Under --float32 each block's last sum is a binary32 value; in binary64 some are not.
  bool all_binary32 = true;
  for (size_t b = 0; b < d.blocks; ++b)
    for (int c = 0; c < 3; ++c) {
      const double x = by_finish[static_cast<size_t>(d.block[b]) * 3 + static_cast<size_t>(c)];
      all_binary32 = all_binary32 && static_cast<double>(static_cast<float>(x)) == x;
    }
  EXPECT_EQ(all_binary32, GetParam());
}

INSTANTIATE_TEST_SUITE_P(Binary64AndFloat32, GatherOnHost, ::testing::Bool());

}  // namespace
}  // namespace simit::jit::ptx
