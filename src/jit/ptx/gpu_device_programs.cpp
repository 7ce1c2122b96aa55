// The GPU executor's device programs (jit/device_program.h): a solver loop's steps launched
// on the device in batches of iterations, their scalars in a context array there.
#include <algorithm>
#include <cstring>
#include <stdexcept>
#include <vector>

#include "jit/device_program.h"
#include "jit/ptx/gpu_executor_impl.h"

namespace simit::jit::ptx::gpu {

int32_t GpuExecutor::run_system(const Kernel& kernel, const SystemArgs& args) {
  if (!kernel.program) {
    for (size_t i = 0; i < args.array_count; ++i) residency::before_host_access(args.arrays[i]);
    return kernel.run(args);
  }
  if (args.array_count > 0 && (!args.array_bytes || !args.array_written))
    throw std::logic_error("a GPU executor needs each array's size (SystemArgs::array_bytes)");
  const DeviceProgram& p = *kernel.program;
  ++call_;
  ++traffic_.system_runs;
  device_->make_current();
  copy_back_pending();
  const std::vector<int64_t> sizes(args.sizes, args.sizes + args.size_count);
  std::vector<cuda::DeviceArray*> arrays(args.array_count, nullptr);
  system_pointers_host_.assign(args.array_count, 0);
  for (size_t i = 0; i < args.array_count; ++i) {
    arrays[i] = to_device(args.arrays[i], args.array_bytes[i], 0);
    system_pointers_host_[i] = arrays[i] ? arrays[i]->device : 0;
    if (args.array_written[i] && arrays[i]) holder(args.arrays[i]).version = 0;
  }
  sizes_host_ = sizes;
  upload(system_pointers_, system_pointers_host_.data(),
         system_pointers_host_.size() * sizeof(cuda::CUdeviceptr));
  upload(sizes_, sizes_host_.data(), sizes_host_.size() * sizeof(int64_t));
  scratch(lanes_, static_cast<size_t>(p.lane_doubles(sizes)) * sizeof(double));
  scratch(partials_, static_cast<size_t>(p.partial_doubles(sizes)) * sizeof(double));
  context_host_.assign(static_cast<size_t>(p.context_words()), 0);
  context_host_[kCtxArrays] = static_cast<int64_t>(system_pointers_.device);
  context_host_[kCtxSizes] = static_cast<int64_t>(sizes_.device);
  context_host_[kCtxLanes] = static_cast<int64_t>(lanes_.device);
  context_host_[kCtxPartials] = static_cast<int64_t>(partials_.device);
  for (int i = 0; i < p.scalars && static_cast<size_t>(i) < args.scalar_count; ++i)
    put_local(p.local_types[static_cast<size_t>(i)], args.scalars[i],
              &context_host_[static_cast<size_t>(kContextHead + i)]);
  upload(context_, context_host_.data(), context_host_.size() * sizeof(int64_t));

  const std::vector<const DeviceStep*> steps = p.all();
  const size_t loop_first = p.before.size(), after_first = loop_first + p.loop.size();
  auto run = [&](size_t from, size_t to, cuda::CUstream stream = nullptr) {
    for (size_t i = from; i < to; ++i)
      launch_step(kernel, static_cast<int32_t>(i), *steps[i], p, sizes, stream);
  };
  // A batch of iterations: one graph launch where graphs are on (captured the first time
  // this program, batch, context and sizes meet), else its steps one by one.
  auto run_batch = [&](int batch) {
    if (!graphs_) {
      for (int it = 0; it < batch; ++it) run(loop_first, after_first);
      return;
    }
    graphs_->launch(GraphKey{&kernel, batch, context_.device, sizes}, [&] {
      for (int it = 0; it < batch; ++it) run(loop_first, after_first, graphs_->stream());
    });
    traffic_.graphs_captured = graphs_->captured();
    traffic_.graph_launches = graphs_->launched();
  };
  auto read_context = [&] {
    if (!emulated_) device_->synchronize();
    context_.device_dirty = true;
    device_->to_host(context_);
    ++traffic_.system_batches;
  };
  bool interrupted = false;
  run(0, loop_first);
  if (p.has_loop) {
    for (int batch = 1;; batch = std::min(batch * 2, kMostIterationsAtOnce)) {
      run_batch(batch);
      read_context();
      if (context_host_[kCtxError] != 0 || context_host_[kCtxStop] != 0) break;
      if (args.interrupt &&
          __atomic_load_n(static_cast<const uint8_t*>(args.interrupt), __ATOMIC_RELAXED) != 0) {
        interrupted = true;
        break;
      }
    }
  }
  if (!interrupted && context_host_[kCtxError] == 0) run(after_first, steps.size());
  read_context();
  for (int i = 0; i < p.scalars && static_cast<size_t>(i) < args.scalar_count; ++i)
    args.scalars[i] = get_local(p.local_types[static_cast<size_t>(i)],
                                &context_host_[static_cast<size_t>(kContextHead + i)]);
  // Every array the program wrote is the device's newest (after an error statement too:
  // the host's kernel leaves what it wrote, and the caller puts back what it saved).
  for (size_t i = 0; i < args.array_count; ++i)
    if (args.array_written[i] && arrays[i]) {
      arrays[i]->device_dirty = true;
      leave_or_copy_back(args.arrays[i], *arrays[i], args.array_resident && args.array_resident[i]);
    }
  evict();
  if (context_host_[kCtxError] != 0) return static_cast<int32_t>(context_host_[kCtxError]);
  return interrupted ? kSystemInterrupted : 0;
}

void GpuExecutor::put_local(Ty t, double v, int64_t* word) {
  *word = 0;
  if (t == Ty::F64) {
    std::memcpy(word, &v, sizeof v);
  } else if (t == Ty::I32) {
    const auto i = static_cast<int32_t>(v);
    std::memcpy(word, &i, sizeof i);
  } else {
    const uint8_t bit = v != 0.0 ? 1 : 0;
    std::memcpy(word, &bit, sizeof bit);
  }
}

double GpuExecutor::get_local(Ty t, const int64_t* word) {
  if (t == Ty::F64) {
    double v;
    std::memcpy(&v, word, sizeof v);
    return v;
  }
  if (t == Ty::I32) {
    int32_t i;
    std::memcpy(&i, word, sizeof i);
    return i;
  }
  uint8_t bit;
  std::memcpy(&bit, word, sizeof bit);
  return (bit & 1) != 0 ? 1.0 : 0.0;
}

void GpuExecutor::upload(cuda::DeviceArray& a, void* host, size_t bytes) {
  if (a.bytes != bytes || a.device == 0) {
    device_->free(a);
    a = device_->alloc(host, bytes);
    ++traffic_.allocations;
  }
  a.host = host;
  a.host_dirty = true;
  device_->to_device(a);
  traffic_.bytes_to_device += static_cast<long long>(bytes);
}

void GpuExecutor::scratch(cuda::DeviceArray& a, size_t bytes) {
  if (a.bytes >= bytes && a.device != 0) return;
  device_->free(a);
  a = device_->alloc(nullptr, bytes);
  ++traffic_.allocations;
}

void GpuExecutor::launch_step(const Kernel& kernel, int32_t index, const DeviceStep& step,
                              const DeviceProgram& p, const std::vector<int64_t>& sizes,
                              cuda::CUstream stream) {
  const int64_t units = p.units(step, sizes);
  if (units <= 0) return;
  ++traffic_.launches;
  if (emulated_) {
    kernel.run_step(index, reinterpret_cast<int64_t*>(context_.device), 0, units);
    return;
  }
  const cuda::CUfunction fn = functions_of(kernel).at(static_cast<size_t>(index));
  const cuda::KernelArg params[] = {cuda::KernelArg::of(context_.device),
                                    cuda::KernelArg::of(units)};
  const auto blocks = static_cast<unsigned>((units + kBlock - 1) / kBlock);
  device_->launch(fn, cuda::Dim3{blocks},
                  cuda::Dim3{units < kBlock ? static_cast<unsigned>(units) : kBlock}, params, 0,
                  stream);
}

}  // namespace simit::jit::ptx::gpu
