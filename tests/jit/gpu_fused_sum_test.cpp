// The GPU executor's fused matrix sum (GpuExecutor::add_into, jit/ptx/fused_sum_kernel.h)
// against the fake driver (gpu_fake_driver.h): it runs only where a map left K on the device,
// launches the fused-sum kernel with its parameters in order, leaves the sum there, copies in
// what the device does not hold (M, and the table of M's blocks once per pair of patterns),
// and the host reading the sum gets runtime::add_into's bits.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <vector>

#include "gpu_fake_driver.h"
#include "jit/ptx/gpu_executor.h"
#include "runtime/residency.h"
#include "runtime/system_matrix.h"
#include "runtime/system_ops.h"

namespace simit::jit::ptx {
namespace {

using namespace fake_gpu;
namespace residency = runtime::residency;

runtime::PatternPtr tridiagonal() {
  return runtime::MatrixPattern::from_csr(4, 4, {0, 2, 5, 8, 10}, {0, 1, 0, 1, 2, 1, 2, 3, 2, 3});
}
runtime::PatternPtr diagonal() {
  return runtime::MatrixPattern::from_csr(4, 4, {0, 1, 2, 3, 4}, {0, 1, 2, 3});
}

double assembled(size_t i) { return std::cos(0.3 * static_cast<double>(i)) * 1e2 / 7.0; }

class GpuFusedSum : public GpuExecutorFake {
 protected:
  // A map whose one result is K's values: the kernel writes assembled(i) into the device's
  // copy, which stays there (a runtime array, MapArgs::array_resident).
  void assemble(Executor& executor, runtime::SystemMatrix& k) {
    kernel.ptx = "//";
    kernel.entry = kMapEntry;
    void* arrays[] = {k.raw_values()};
    const size_t bytes[] = {k.value_count() * sizeof(double)};
    const uint8_t written[] = {1}, resident[] = {1};
    const ArrayFill fill[] = {ArrayFill::Zero};
    const uint64_t stamps[] = {0};
    const int32_t ends[] = {0, 1, 2, 3};
    double scalar = 0.0;
    MapArgs args{arrays, &scalar, ends};
    args.array_count = 1;
    args.array_bytes = bytes;
    args.array_written = written;
    args.array_resident = resident;
    args.array_fill = fill;
    args.array_version_in = args.array_version_out = stamps;
    args.scalar_count = 1;
    args.arity = 1;
    const size_t n = k.value_count();
    state.on_launch = [n](const Launch& l) {
      if (l.fused_sum) return fused_sum_on_host(l.sum, 0, l.sum.blocks);
      double* v = at<double>(at<CUdeviceptr>(l.table)[0]);
      for (size_t i = 0; i < n; ++i) v[i] = assembled(i);
    };
    ASSERT_EQ(executor.run_map(kernel, args, 4, 1, MapWrites::Disjoint, {}).code, 0);
  }
  PtxKernel kernel;
};

TEST_F(GpuFusedSum, RunsWhereTheMapLeftKAndLeavesTheSumThere) {
  auto executor = make_gpu_executor_over(fake_table());
  runtime::SystemMatrix m(diagonal(), 3, 3), k(tridiagonal(), 3, 3);
  for (size_t i = 0; i < m.value_count(); ++i) m.values()[i] = 1.0 + 0.25 * static_cast<double>(i);
  const double beta = -1e-4;

  // K on the host: the host's sum is cheaper than the copies.
  EXPECT_FALSE(executor->add_into(m, 1.0, k, beta, false));
  EXPECT_TRUE(state.launches.empty());

  assemble(*executor, k);
  ASSERT_EQ(residency::count(), 1);
  const Fake before = state;
  const GpuTraffic t0 = gpu_traffic(*executor);
  ASSERT_TRUE(executor->add_into(m, 1.0, k, beta, false));
  const GpuTraffic t1 = gpu_traffic(*executor);
  ASSERT_EQ(state.launches.size(), before.launches.size() + 1);
  const Launch& l = state.launches.back();
  ASSERT_TRUE(l.fused_sum);
  EXPECT_EQ(l.sum.blocks, 10u);
  EXPECT_EQ(l.sum.components, 9u);
  EXPECT_EQ(l.sum.alpha, 1.0);
  EXPECT_EQ(l.sum.beta, beta);
  EXPECT_EQ(l.sum.zero_plus, 1u);  // M's pattern is not K's: the union sum's 0.0 + a
  EXPECT_EQ(l.sum.float32, 0u);
  EXPECT_EQ(l.grid * l.block >= 10u, true);
  EXPECT_EQ(t1.fused_sums - t0.fused_sums, 1);
  // M (4 blocks) and the table (10 blocks) in; K neither in nor back.
  EXPECT_EQ(state.to_device - before.to_device,
            static_cast<long long>(m.value_count() * sizeof(double) + 10 * sizeof(int32_t)));
  EXPECT_EQ(state.to_host, before.to_host);
  EXPECT_EQ(residency::count(), 1);
  EXPECT_EQ(std::as_const(k).raw_values()[0], 0.0);  // the host's copy: not yet

  // The host reads the sum: runtime::add_into's bits on the map's values.
  runtime::SystemMatrix want(tridiagonal(), 3, 3);
  for (size_t i = 0; i < want.value_count(); ++i) want.values()[i] = assembled(i);
  ASSERT_TRUE(runtime::add_into(m, 1.0, want, beta, nullptr, false));
  EXPECT_EQ(std::memcmp(std::as_const(k).values(), want.values(), want.value_count() * 8), 0);
  EXPECT_EQ(residency::count(), 0);

  // Again on the same patterns, in float32, K assembled on the device again: M, which has no
  // stamp, comes in again; the table does not.
  assemble(*executor, k);
  const Fake again = state;
  ASSERT_TRUE(executor->add_into(m, 1.0, k, beta, true));
  EXPECT_EQ(state.to_device - again.to_device,
            static_cast<long long>(m.value_count() * sizeof(double)));
  EXPECT_EQ(state.launches.back().sum.float32, 1u);
  runtime::SystemMatrix want32(tridiagonal(), 3, 3);
  for (size_t i = 0; i < want32.value_count(); ++i) want32.values()[i] = assembled(i);
  ASSERT_TRUE(runtime::add_into(m, 1.0, want32, beta, nullptr, true));
  EXPECT_EQ(std::memcmp(std::as_const(k).values(), want32.values(), want32.value_count() * 8), 0);
  executor.reset();
  EXPECT_EQ(state.frees, state.allocations);
}

TEST_F(GpuFusedSum, AnMWithABlockOutsideKsPatternIsLeftToTheHost) {
  auto executor = make_gpu_executor_over(fake_table());
  runtime::SystemMatrix m(tridiagonal(), 3, 3), k(diagonal(), 3, 3);
  assemble(*executor, k);
  EXPECT_FALSE(executor->add_into(m, 1.0, k, -1.0, false));
  EXPECT_EQ(residency::count(), 1);  // still on the device, for the host to bring back
  executor.reset();
  EXPECT_EQ(residency::count(), 0);
  EXPECT_EQ(std::as_const(k).values()[3], assembled(3));
}

}  // namespace
}  // namespace simit::jit::ptx
