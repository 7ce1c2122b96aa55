// The GPU executor (jit/ptx/gpu_executor.h): a map kernel's arrays mirrored in device memory,
// copied in before the launch and left there as the newest copy until the host touches them
// (runtime/residency.h), one thread per element; a deferred assembly's additions by the
// gather kernel (jit/ptx/gather_kernel.h); the factories.
#include "jit/ptx/gpu_executor.h"

#include <algorithm>
#include <cstring>
#include <map>
#include <optional>
#include <stdexcept>
#include <vector>

#include "jit/deferred_plan.h"
#include "jit/ptx/cuda_driver.h"
#include "jit/ptx/gather_kernel.h"
#include "jit/ptx/gpu_executor_impl.h"
#include "jit/ptx/host_driver.h"
#include "jit/ptx/ptx_target.h"
#include "runtime/residency.h"

namespace simit::jit::ptx {

namespace gpu {

GpuExecutor::GpuExecutor(std::unique_ptr<cuda::Device> device, bool emulated,
                         const std::optional<cuda::StreamTable>& streams)
    : emulated_(emulated), device_(std::move(device)) {
  if (streams && !emulated_) graphs_ = std::make_unique<BatchGraphs>(*device_, *streams);
}

GpuExecutor::~GpuExecutor() {
  try {
    // What only the device holds goes home: the host's arrays outlive the executor.
    residency::bring_back_all_of(*this);
    graphs_.reset();
    for (auto& [host, m] : mirrors_) device_->free(m.array);
    for (auto& [plan, u] : uploads_) free_index(u);
    for (auto& [key, t] : sum_tables_) device_->free(t.from);
    device_->free(pointers_);
    device_->free(failure_);
    for (cuda::DeviceArray* a : {&system_pointers_, &sizes_, &context_, &lanes_, &partials_})
      device_->free(*a);
  } catch (const cuda::CudaError&) {
    // A driver that fails while the process ends: the memory goes with the context.
  }
}

MapOutcome GpuExecutor::run_map(const Kernel& kernel, const MapArgs& args, int32_t n, int32_t,
                                MapWrites writes, const std::function<bool()>& interrupt) {
  if (!args.array_bytes || !args.array_written)
    throw std::logic_error("a GPU executor needs each array's size (MapArgs::array_bytes)");
  MapOutcome out;
  if (n <= 0) return out;
  if (interrupt && interrupt()) {
    out.interrupted = true;
    return out;
  }
  ++call_;
  device_->make_current();
  copy_back_pending();
  // Each array in unless the device already holds what the host holds (its stamp), a
  // zeroed result zeroed on the device, deferred blocks at -0.0 set so on the device.
  auto stamp = [](const uint64_t* stamps, size_t i) { return stamps ? stamps[i] : 0; };
  std::vector<cuda::DeviceArray*> arrays(args.array_count, nullptr);
  pointers_host_.assign(args.array_count, 0);
  for (size_t i = 0; i < args.array_count; ++i) {
    arrays[i] = to_device(args.arrays[i], args.array_bytes[i], stamp(args.array_version_in, i),
                          args.array_fill ? args.array_fill[i] : ArrayFill::Copy);
    pointers_host_[i] = arrays[i] ? arrays[i]->device : 0;
  }
  cuda::DeviceArray* scalars =
      to_device(const_cast<double*>(args.scalars), args.scalar_count * sizeof(double), 0);
  cuda::DeviceArray* endpoints =
      to_device(const_cast<int32_t*>(args.endpoints),
                static_cast<size_t>(n) * static_cast<size_t>(args.arity) * sizeof(int32_t),
                args.endpoints_version);
  // Until the launch is over, an array it writes holds nothing known (a launch that throws
  // leaves it so).
  for (size_t i = 0; i < args.array_count; ++i)
    if (args.array_written[i] && arrays[i]) holder(args.arrays[i]).version = 0;
  const cuda::CUdeviceptr scalars_at = scalars ? scalars->device : 0;
  const cuda::CUdeviceptr endpoints_at = endpoints ? endpoints->device : 0;

  int32_t code = 0, element = -1;
  if (emulated_) {
    // The CPU target's kernel on the device copies (host memory under the host driver).
    std::vector<void*> at(args.array_count);
    for (size_t i = 0; i < at.size(); ++i) at[i] = reinterpret_cast<void*>(pointers_host_[i]);
    MapArgs dev{at.data(), reinterpret_cast<const double*>(scalars_at),
                reinterpret_cast<const int32_t*>(endpoints_at)};
    code = kernel.run(dev, ElementRange{0, n}, &element);
    traffic_.launches += 1;
  } else {
    std::tie(code, element) =
        launch(kernel, n, writes == MapWrites::Shared, scalars_at, endpoints_at);
  }
  // Every array the kernel wrote back out, also after a failed check (the interpreter's
  // run leaves the fields the elements before it wrote); after a deferred run that
  // succeeded, once finish_deferred has added the deferred blocks on the device, and then
  // without the deferred blocks themselves.
  //
  // Copied back at once rather than when the host reads them: the host reads fields,
  // vectors and matrices through many paths (the interpreter, tensors read from fields,
  // output, the finite check, the API's views), and each would need a hook that brings the
  // device's copy back first.
  const bool later = writes == MapWrites::Deferred && code == 0;
  for (size_t i = 0; i < args.array_count; ++i)
    if (args.array_written[i] && arrays[i]) {
      const bool resident = args.array_resident && args.array_resident[i];
      arrays[i]->device_dirty = true;
      if (later)
        pending_.push_back({args.arrays[i], resident});
      else
        leave_or_copy_back(args.arrays[i], *arrays[i], resident);
    }
  // The host's copies as they are now (a deferred map's once finish_deferred has copied
  // back what it wrote): what the device holds too.
  for (size_t i = 0; i < args.array_count; ++i)
    if (arrays[i]) holder(args.arrays[i]).version = stamp(args.array_version_out, i);
  evict();
  out.code = code;
  out.element = code ? element : -1;
  return out;
}

void GpuExecutor::finish_deferred(const DeferredPlan& plan, const std::vector<double*>& values) {
  device_->make_current();
  const std::vector<DeferredPlan::Gather> gathers = plan.gathers();
  const IndexUpload& index = upload_index(plan, gathers);
  bool launched = false;
  for (size_t g = 0; g < gathers.size(); ++g) {
    const DeferredPlan::Gather& d = gathers[g];
    double* host = static_cast<size_t>(d.result) < values.size()
                       ? values[static_cast<size_t>(d.result)]
                       : nullptr;
    if (!host || d.blocks == 0) continue;
    const cuda::DeviceArray* to = mirror_of(host);
    const cuda::DeviceArray* from = mirror_of(d.deferred);
    if (!to || !from) throw std::logic_error("a deferred assembly's result is not on the device");
    GatherArgs a;
    a.values = reinterpret_cast<double*>(to->device);
    a.deferred = reinterpret_cast<const double*>(from->device);
    a.block = reinterpret_cast<const int32_t*>(index.arrays[3 * g].device);
    a.start = reinterpret_cast<const int32_t*>(index.arrays[3 * g + 1].device);
    a.k = reinterpret_cast<const int32_t*>(index.arrays[3 * g + 2].device);
    a.blocks = static_cast<uint32_t>(d.blocks);
    a.components = static_cast<uint32_t>(d.components);
    a.round32 = d.round32 ? 1 : 0;
    if (emulated_) {
      // Host memory under the host driver: the device addresses are host addresses.
      gather_on_host(a, 0, a.blocks);
    } else {
      const cuda::KernelArg params[] = {cuda::KernelArg::of(to->device),
                                        cuda::KernelArg::of(from->device),
                                        cuda::KernelArg::of(index.arrays[3 * g].device),
                                        cuda::KernelArg::of(index.arrays[3 * g + 1].device),
                                        cuda::KernelArg::of(index.arrays[3 * g + 2].device),
                                        cuda::KernelArg::of(a.blocks),
                                        cuda::KernelArg::of(a.components),
                                        cuda::KernelArg::of(a.round32)};
      device_->launch(gather_function(), cuda::Dim3{(a.blocks + kBlock - 1) / kBlock},
                      cuda::Dim3{kBlock}, params);
      launched = true;
    }
    ++traffic_.launches;
    ++traffic_.gather_launches;
  }
  if (launched) device_->synchronize();
  for (const auto& [host, resident] : pending_) {
    auto it = mirrors_.find(host);
    if (it == mirrors_.end()) continue;
    const bool scratch = std::any_of(gathers.begin(), gathers.end(),
                                     [&](const auto& d) { return d.deferred == host; });
    if (scratch)
      it->second.array.device_dirty = false;  // the next call sets it to -0.0 again
    else
      leave_or_copy_back(host, it->second.array, resident);
  }
  pending_.clear();
}

void GpuExecutor::bring_back(void* host) {
  auto it = mirrors_.find(host);
  if (it == mirrors_.end() || !it->second.array.device_dirty) return;
  device_->make_current();
  copy_back(it->second.array);
  ++traffic_.brought_back;
  traffic_.bytes_brought_back += static_cast<long long>(it->second.array.bytes);
}

void GpuExecutor::released(const void* host) noexcept {
  auto it = mirrors_.find(host);
  if (it == mirrors_.end()) return;
  it->second.array.device_dirty = false;
  it->second.version = 0;
  ++traffic_.dropped;
}

void GpuExecutor::leave_or_copy_back(const void* host, cuda::DeviceArray& array, bool resident) {
  if (!resident) {
    copy_back(array);
    return;
  }
  residency::mark_elsewhere(const_cast<void*>(host), *this);
  ++traffic_.kept_on_device;
  traffic_.bytes_kept += static_cast<long long>(array.bytes);
}

void GpuExecutor::copy_back_pending() {
  for (const auto& [host, resident] : pending_)
    if (auto it = mirrors_.find(host); it != mirrors_.end())
      leave_or_copy_back(host, it->second.array, resident);
  pending_.clear();
}

const GpuExecutor::IndexUpload& GpuExecutor::upload_index(
    const DeferredPlan& plan, const std::vector<DeferredPlan::Gather>& gathers) {
  IndexUpload& u = uploads_[&plan];
  u.used = call_;
  if (u.build == plan.build_id() && u.arrays.size() == 3 * gathers.size()) return u;
  free_index(u);
  u.build = plan.build_id();
  for (const DeferredPlan::Gather& d : gathers) {
    const size_t ks = d.blocks > 0 ? static_cast<size_t>(d.start[d.blocks]) : 0;
    const std::pair<const int32_t*, size_t> parts[] = {
        {d.block, d.blocks}, {d.start, d.blocks + 1}, {d.k, ks}};
    for (const auto& [host, count] : parts) {
      // Nothing to upload where no block has deferred blocks (the kernel is not launched).
      cuda::DeviceArray a =
          device_->alloc(const_cast<int32_t*>(host), d.blocks > 0 ? count * sizeof(int32_t) : 0);
      if (a.device != 0) {
        ++traffic_.allocations;
        device_->to_device(a);
        traffic_.bytes_to_device += static_cast<long long>(a.bytes);
      }
      a.host = nullptr;  // device-only from here: the plan may rebuild its tables
      u.arrays.push_back(a);
    }
  }
  ++traffic_.index_uploads;
  return u;
}

cuda::CUfunction GpuExecutor::gather_function() {
  if (!gather_) {
    cuda::CUmodule module = device_->load_module(gather_ptx(arch_, ptx_version_));
    gather_ = device_->function(module, kGatherEntry);
  }
  return gather_;
}

cuda::DeviceArray* GpuExecutor::to_device(void* host, size_t bytes, uint64_t version,
                                          ArrayFill how) {
  if (!host || bytes == 0) return nullptr;
  Mirror& m = mirrors_[host];
  // Newer elsewhere than here (another executor's memory: two engines over one set) comes
  // home first; newer here in a mirror of another size (a set that grew) too.
  if (!m.array.device_dirty || m.array.bytes != bytes) residency::before_host_access(host);
  if (m.array.bytes != bytes || m.array.device == 0) {
    device_->free(m.array);
    m.array = device_->alloc(host, bytes);
    m.version = 0;
    m.refreshed = 0;
    ++traffic_.allocations;
  }
  m.used = call_;
  if (m.refreshed == call_) return &m.array;
  m.refreshed = call_;
  if (m.array.device_dirty) {
    // The device's copy is newer than the host's, which nobody touched since (that would
    // have brought it back): it stays. A result the host set anew drops it.
    if (how == ArrayFill::Copy) {
      ++traffic_.uploads_resident;
      traffic_.bytes_skipped += static_cast<long long>(bytes);
      return &m.array;
    }
    residency::settle(host);
  }
  m.array.device_dirty = false;
  if (how == ArrayFill::Zero) {
    m.array.host_dirty = false;
    device_->zero(m.array);
    ++traffic_.zeroed;
    traffic_.bytes_zeroed += static_cast<long long>(bytes);
  } else if (how == ArrayFill::NegativeZero) {
    m.array.host_dirty = false;
    device_->fill_negative_zero(m.array);
    ++traffic_.filled;
    traffic_.bytes_filled += static_cast<long long>(bytes);
  } else if (version != 0 && m.version == version) {
    m.array.host_dirty = false;
    ++traffic_.uploads_skipped;
    traffic_.bytes_skipped += static_cast<long long>(bytes);
  } else {
    m.array.host_dirty = true;
    device_->to_device(m.array);
    ++traffic_.uploads;
    traffic_.bytes_to_device += static_cast<long long>(bytes);
  }
  m.version = how == ArrayFill::Copy ? version : 0;
  return &m.array;
}

void GpuExecutor::evict() {
  for (auto it = mirrors_.begin(); it != mirrors_.end();) {
    if (call_ - it->second.used > kKeepCalls) {
      if (it->second.array.device_dirty) residency::before_host_access(it->first);
      device_->free(it->second.array);
      it = mirrors_.erase(it);
    } else {
      ++it;
    }
  }
  for (auto it = sum_tables_.begin(); it != sum_tables_.end();) {
    if (call_ - it->second.used > kKeepCalls) {
      device_->free(it->second.from);
      it = sum_tables_.erase(it);
    } else {
      ++it;
    }
  }
  for (auto it = uploads_.begin(); it != uploads_.end();) {
    if (call_ - it->second.used > kKeepCalls) {
      free_index(it->second);
      it = uploads_.erase(it);
    } else {
      ++it;
    }
  }
}

const std::vector<cuda::CUfunction>& GpuExecutor::functions_of(const Kernel& kernel) {
  std::vector<cuda::CUfunction>& fns = functions_[&kernel];
  if (!fns.empty()) return fns;
  const auto* ptx = dynamic_cast<const PtxKernel*>(&kernel);
  if (!ptx) throw std::logic_error("the GPU executor was given a kernel compiled for the CPU");
  if (arch_.empty()) {
    arch_ = ptx_directive(ptx->ptx, ".target");
    ptx_version_ = ptx_directive(ptx->ptx, ".version");
  }
  cuda::CUmodule module = device_->load_module(ptx->ptx);
  if (kernel.program)
    for (const std::string& entry : ptx->entries) fns.push_back(device_->function(module, entry));
  else
    fns.push_back(device_->function(module, ptx->entry));
  return fns;
}

std::pair<int32_t, int32_t> GpuExecutor::launch(const Kernel& kernel, int32_t n, bool in_order,
                                                cuda::CUdeviceptr scalars,
                                                cuda::CUdeviceptr endpoints) {
  const cuda::CUfunction fn = functions_of(kernel).front();
  if (pointers_.bytes != pointers_host_.size() * sizeof(cuda::CUdeviceptr) ||
      pointers_.device == 0) {
    device_->free(pointers_);
    pointers_ =
        device_->alloc(pointers_host_.data(), pointers_host_.size() * sizeof(cuda::CUdeviceptr));
  }
  pointers_.host = pointers_host_.data();
  pointers_.host_dirty = true;
  device_->to_device(pointers_);
  failure_word_ = kNoFailure;
  if (failure_.device == 0) failure_ = device_->alloc(&failure_word_, sizeof failure_word_);
  failure_.host_dirty = true;
  device_->to_device(failure_);
  auto one = [&](int32_t begin, int32_t end) {
    const unsigned count = static_cast<unsigned>(end - begin);
    const cuda::KernelArg params[] = {cuda::KernelArg::of(pointers_.device),
                                      cuda::KernelArg::of(scalars),
                                      cuda::KernelArg::of(endpoints),
                                      cuda::KernelArg::of(begin),
                                      cuda::KernelArg::of(end),
                                      cuda::KernelArg::of(failure_.device)};
    device_->launch(fn, cuda::Dim3{(count + kBlock - 1) / kBlock}, cuda::Dim3{kBlock}, params);
    ++traffic_.launches;
  };
  if (in_order) {
    for (int32_t e = 0; e < n; ++e) one(e, e + 1);
  } else {
    one(0, n);
  }
  device_->synchronize();
  failure_.device_dirty = true;
  device_->to_host(failure_);
  if (failure_word_ == kNoFailure) return {0, -1};
  return {failed_check(failure_word_) + 1, failed_element(failure_word_)};
}

}  // namespace gpu

using gpu::GpuExecutor;

namespace {

std::unique_ptr<Executor> open(const cuda::DriverTable& table, bool emulated,
                               const std::optional<cuda::StreamTable>& streams = std::nullopt) {
  if (!table.cuMemsetD8 || !table.cuMemsetD32 || !table.cuMemsetD2D32)
    throw std::invalid_argument(
        "a GPU executor needs the driver's cuMemsetD8, cuMemsetD32 and cuMemsetD2D32");
  auto device = std::make_unique<cuda::Device>(table);
  device->open(0);
  return std::make_unique<GpuExecutor>(std::move(device), emulated, streams);
}

}  // namespace

std::unique_ptr<Executor> make_gpu_executor(std::string& why) {
  std::optional<cuda::DriverTable> table = cuda::load_driver(why);
  if (!table) return nullptr;
  // The stream and graph entries (CUDA 11.4 on): without them the batches go step by step.
  std::string streams_why;
  std::optional<cuda::StreamTable> streams;
  if (auto get = cuda::open_driver_library("libcuda.so.1", streams_why))
    streams = cuda::resolve_streams(*get, streams_why);
  try {
    return open(*table, false, streams);
  } catch (const std::exception& e) {
    why = e.what();
    return nullptr;
  }
}

std::unique_ptr<Executor> make_gpu_executor_over(const cuda::DriverTable& table,
                                                 const cuda::StreamTable* streams) {
  return open(table, false, streams ? std::optional<cuda::StreamTable>(*streams) : std::nullopt);
}

std::unique_ptr<Executor> make_emulated_gpu_executor() {
  return open(cuda::host_driver_table(), true);
}

bool is_gpu_executor(const Executor& executor) {
  return dynamic_cast<const GpuExecutor*>(&executor) != nullptr;
}

bool is_emulated_gpu_executor(const Executor& executor) {
  const auto* g = dynamic_cast<const GpuExecutor*>(&executor);
  return g && g->emulated_;
}

GpuTraffic gpu_traffic(const Executor& executor) {
  const auto* g = dynamic_cast<const GpuExecutor*>(&executor);
  return g ? g->traffic_ : GpuTraffic{};
}

}  // namespace simit::jit::ptx
