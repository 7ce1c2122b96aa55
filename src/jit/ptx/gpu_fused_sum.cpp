// The GPU executor's fused matrix sum: `A = M - s * K` on the device where its map left K
// (the fused-sum kernel, jit/ptx/fused_sum_kernel.h).
#include <utility>
#include <vector>

#include "jit/array_stamps.h"
#include "jit/ptx/fused_sum_kernel.h"
#include "jit/ptx/gpu_executor_impl.h"

namespace simit::jit::ptx::gpu {

bool GpuExecutor::add_into(const runtime::SystemMatrix& a, double alpha, runtime::SystemMatrix& b,
                           double beta, bool float32) {
  if (!a.is_float() || !b.is_float() || a.block_rows() != b.block_rows() ||
      a.block_cols() != b.block_cols() || b.value_count() == 0 || a.value_count() == 0)
    return false;
  double* host_b = b.raw_values();
  if (!residency::is_elsewhere(host_b, *this)) return false;
  ++call_;
  const SumTable* table = sum_table(a, b);
  if (!table) return false;
  device_->make_current();
  copy_back_pending();
  cuda::DeviceArray* to = to_device(host_b, b.value_count() * sizeof(double), 0);
  cuda::DeviceArray* from =
      to_device(const_cast<double*>(a.raw_values()), a.value_count() * sizeof(double), 0);
  holder(host_b).version = 0;
  FusedSumArgs f;
  f.alpha = alpha;
  f.beta = beta;
  f.blocks = static_cast<uint32_t>(b.pattern().nnz());
  f.components = static_cast<uint32_t>(b.block_size());
  f.zero_plus = a.shared_pattern() == b.shared_pattern() ? 0 : 1;
  f.float32 = float32 ? 1 : 0;
  if (emulated_) {
    // Host memory under the host driver: the device addresses are host addresses.
    f.b = reinterpret_cast<double*>(to->device);
    f.a = reinterpret_cast<const double*>(from->device);
    f.from = reinterpret_cast<const int32_t*>(table->from.device);
    fused_sum_on_host(f, 0, f.blocks);
  } else {
    const cuda::KernelArg params[] = {cuda::KernelArg::of(to->device),
                                      cuda::KernelArg::of(from->device),
                                      cuda::KernelArg::of(table->from.device),
                                      cuda::KernelArg::of(f.alpha),
                                      cuda::KernelArg::of(f.beta),
                                      cuda::KernelArg::of(f.blocks),
                                      cuda::KernelArg::of(f.components),
                                      cuda::KernelArg::of(f.zero_plus),
                                      cuda::KernelArg::of(f.float32)};
    device_->launch(fused_sum_function(), cuda::Dim3{(f.blocks + kBlock - 1) / kBlock},
                    cuda::Dim3{kBlock}, params);
    device_->synchronize();
  }
  ++traffic_.launches;
  ++traffic_.fused_sums;
  to->device_dirty = true;
  leave_or_copy_back(host_b, *to, true);
  evict();
  return true;
}

const GpuExecutor::SumTable* GpuExecutor::sum_table(const runtime::SystemMatrix& a,
                                                    const runtime::SystemMatrix& b) {
  const auto key =
      std::make_pair(pattern_number(a.shared_pattern()), pattern_number(b.shared_pattern()));
  auto it = sum_tables_.find(key);
  if (it == sum_tables_.end()) {
    SumTable t;
    if (!fused_sum_sources(a.pattern(), b.pattern(), t.host)) return nullptr;
    t.from = device_->alloc(t.host.data(), t.host.size() * sizeof(int32_t));
    ++traffic_.allocations;
    device_->to_device(t.from);
    traffic_.bytes_to_device += static_cast<long long>(t.from.bytes);
    it = sum_tables_.emplace(key, std::move(t)).first;
  }
  it->second.used = call_;
  return &it->second;
}

cuda::CUfunction GpuExecutor::fused_sum_function() {
  if (!fused_sum_) {
    cuda::CUmodule module = device_->load_module(fused_sum_ptx(arch_, ptx_version_));
    fused_sum_ = device_->function(module, kFusedSumEntry);
  }
  return fused_sum_;
}

}  // namespace simit::jit::ptx::gpu
