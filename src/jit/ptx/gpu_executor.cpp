// The GPU executor (jit/ptx/gpu_executor.h): a map kernel's arrays mirrored in device memory,
// copied there before the launch and back after it, one thread per element.
#include "jit/ptx/gpu_executor.h"

#include <map>
#include <stdexcept>
#include <vector>

#include "jit/ptx/cuda_driver.h"
#include "jit/ptx/host_driver.h"
#include "jit/ptx/ptx_target.h"

namespace simit::jit::ptx {

namespace {

// Threads per block: a multiple of the warp, small enough that a kernel with many registers
// (a Neo-Hookean stiffness) still fits a block on one multiprocessor.
constexpr unsigned kBlock = 128;
// A mirror not used by the last this many calls is freed (the arrays of sites that stopped
// running, or of a set that grew, do not hold device memory for good).
constexpr long kKeepCalls = 64;

class GpuExecutor final : public Executor {
 public:
  GpuExecutor(std::unique_ptr<cuda::Device> device, bool emulated)
      : emulated_(emulated), device_(std::move(device)) {}
  ~GpuExecutor() override {
    try {
      for (auto& [host, m] : mirrors_) device_->free(m.array);
      device_->free(pointers_);
      device_->free(failure_);
    } catch (const cuda::CudaError&) {
      // A driver that fails while the process ends: the memory goes with the context.
    }
  }

  const char* name() const override { return emulated_ ? "gpu (emulated)" : "gpu"; }
  bool parallel() const override { return true; }
  // One thread per element: each is its own chunk of a deferred assembly.
  int32_t chunk_for(int32_t) const override { return 1; }

  MapOutcome run_map(const Kernel& kernel, const MapArgs& args, int32_t n, int32_t,
                     MapWrites writes, const std::function<bool()>& interrupt) override {
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
    // Every array in: the host may have changed any of them since the last call.
    std::vector<cuda::DeviceArray*> arrays(args.array_count, nullptr);
    pointers_host_.assign(args.array_count, 0);
    for (size_t i = 0; i < args.array_count; ++i) {
      arrays[i] = to_device(args.arrays[i], args.array_bytes[i]);
      pointers_host_[i] = arrays[i] ? arrays[i]->device : 0;
    }
    cuda::DeviceArray* scalars =
        to_device(const_cast<double*>(args.scalars), args.scalar_count * sizeof(double));
    cuda::DeviceArray* endpoints =
        to_device(const_cast<int32_t*>(args.endpoints),
                  static_cast<size_t>(n) * static_cast<size_t>(args.arity) * sizeof(int32_t));
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
    // run leaves the fields the elements before it wrote).
    for (size_t i = 0; i < args.array_count; ++i)
      if (args.array_written[i] && arrays[i]) {
        arrays[i]->device_dirty = true;
        device_->to_host(*arrays[i]);
        traffic_.bytes_to_host += static_cast<long long>(arrays[i]->bytes);
      }
    evict();
    out.code = code;
    out.element = code ? element : -1;
    return out;
  }

  GpuTraffic traffic_;
  bool emulated_ = false;

 private:
  struct Mirror {
    cuda::DeviceArray array;
    long used = 0;  // the call that last used it
  };

  // The device copy of `host` (`bytes` long), refreshed; null for an empty array.
  cuda::DeviceArray* to_device(void* host, size_t bytes) {
    if (!host || bytes == 0) return nullptr;
    Mirror& m = mirrors_[host];
    if (m.array.bytes != bytes || m.array.device == 0) {
      device_->free(m.array);
      m.array = device_->alloc(host, bytes);
      ++traffic_.allocations;
    }
    m.used = call_;
    m.array.host_dirty = true;
    m.array.device_dirty = false;
    device_->to_device(m.array);
    traffic_.bytes_to_device += static_cast<long long>(bytes);
    return &m.array;
  }

  void evict() {
    for (auto it = mirrors_.begin(); it != mirrors_.end();) {
      if (call_ - it->second.used > kKeepCalls) {
        device_->free(it->second.array);
        it = mirrors_.erase(it);
      } else {
        ++it;
      }
    }
  }

  cuda::CUfunction function_for(const Kernel& kernel) {
    if (auto it = functions_.find(&kernel); it != functions_.end()) return it->second;
    const auto* ptx = dynamic_cast<const PtxKernel*>(&kernel);
    if (!ptx) throw std::logic_error("the GPU executor was given a kernel compiled for the CPU");
    cuda::CUmodule module = device_->load_module(ptx->ptx);
    return functions_[&kernel] = device_->function(module, ptx->entry);
  }

  // The kernel on the device: one launch over every element, or, for a map whose elements
  // add into shared blocks in place (no deferred writes), one launch per element in element
  // order (the stream runs them one after another). Returns (code, element).
  std::pair<int32_t, int32_t> launch(const Kernel& kernel, int32_t n, bool in_order,
                                     cuda::CUdeviceptr scalars, cuda::CUdeviceptr endpoints) {
    const cuda::CUfunction fn = function_for(kernel);
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

  std::unique_ptr<cuda::Device> device_;
  std::map<const void*, Mirror> mirrors_;
  std::map<const Kernel*, cuda::CUfunction> functions_;
  std::vector<cuda::CUdeviceptr> pointers_host_;
  cuda::DeviceArray pointers_, failure_;
  uint64_t failure_word_ = kNoFailure;
  long call_ = 0;
};

std::unique_ptr<Executor> open(const cuda::DriverTable& table, bool emulated) {
  auto device = std::make_unique<cuda::Device>(table);
  device->open(0);
  return std::make_unique<GpuExecutor>(std::move(device), emulated);
}

}  // namespace

std::unique_ptr<Executor> make_gpu_executor(std::string& why) {
  std::optional<cuda::DriverTable> table = cuda::load_driver(why);
  if (!table) return nullptr;
  try {
    return open(*table, false);
  } catch (const std::exception& e) {
    why = e.what();
    return nullptr;
  }
}

std::unique_ptr<Executor> make_gpu_executor_over(const cuda::DriverTable& table) {
  return open(table, false);
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
