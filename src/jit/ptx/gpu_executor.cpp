// The GPU executor (jit/ptx/gpu_executor.h): a map kernel's arrays mirrored in device memory,
// copied there before the launch and back after it, one thread per element; a deferred
// assembly's additions by the gather kernel (jit/ptx/gather_kernel.h) before the copy back.
#include "jit/ptx/gpu_executor.h"

#include <algorithm>
#include <cstring>
#include <map>
#include <optional>
#include <stdexcept>
#include <vector>

#include "jit/array_stamps.h"
#include "jit/deferred_plan.h"
#include "jit/device_program.h"
#include "jit/ptx/batch_graphs.h"
#include "jit/ptx/cuda_driver.h"
#include "jit/ptx/fused_sum_kernel.h"
#include "jit/ptx/gather_kernel.h"
#include "jit/ptx/host_driver.h"
#include "jit/ptx/ptx_target.h"
#include "runtime/residency.h"

namespace simit::jit::ptx {

namespace {

// Threads per block: a multiple of the warp, small enough that a kernel with many registers
// (a Neo-Hookean stiffness) still fits a block on one multiprocessor.
constexpr unsigned kBlock = 128;
// A mirror not used by the last this many calls is freed (the arrays of sites that stopped
// running, or of a set that grew, do not hold device memory for good).
constexpr long kKeepCalls = 64;
// A solver loop's iterations launched before the host next reads the stop word: 1, 2, 4, ...
// up to this many (a loop of n iterations waits about log2(n) + n / 32 times, and launches
// at most 31 iterations' steps that find the stop word set and return at once).
constexpr int kMostIterationsAtOnce = 32;

namespace residency = runtime::residency;

class GpuExecutor final : public Executor, public residency::Holder {
 public:
  // With `streams`, a device program's loop batches run as CUDA graphs (jit/ptx/batch_graphs.h).
  GpuExecutor(std::unique_ptr<cuda::Device> device, bool emulated,
              const std::optional<cuda::StreamTable>& streams)
      : emulated_(emulated), device_(std::move(device)) {
    if (streams && !emulated_) graphs_ = std::make_unique<BatchGraphs>(*device_, *streams);
  }
  ~GpuExecutor() override {
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

  // Each result's deferred blocks added on the device, one thread per block that has some
  // (the gather kernel; emulated, its host equivalent over the "device" memory), then the
  // arrays the map wrote copied back but for the deferred blocks, which the host never reads.
  void finish_deferred(const DeferredPlan& plan, const std::vector<double*>& values) override {
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
                                          cuda::KernelArg::of(a.components)};
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

  // A device program (jit/device_program.h): its arrays mirrored as a map's are, its
  // scalars in the context array, its steps launched one after another with nothing read
  // back between them; the loop's steps in batches of iterations, after each of which the
  // host reads the context's stop and error words (and takes an interrupt). A kernel that is
  // not a device program runs on the host, where the data is (every run copies back).
  int32_t run_system(const Kernel& kernel, const SystemArgs& args) override {
    if (!kernel.program) return kernel.run(args);
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
        leave_or_copy_back(args.arrays[i], *arrays[i],
                           args.array_resident && args.array_resident[i]);
      }
    evict();
    if (context_host_[kCtxError] != 0) return static_cast<int32_t>(context_host_[kCtxError]);
    return interrupted ? kSystemInterrupted : 0;
  }

  // The fused matrix sum on the device, where b's newest values are (its map assembled it
  // there): one thread per block of b (the fused-sum kernel, jit/ptx/fused_sum_kernel.h),
  // a's values copied in unless they are there too, b left there as the newest.
  bool add_into(const runtime::SystemMatrix& a, double alpha, runtime::SystemMatrix& b, double beta,
                bool float32) override {
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

  // residency::Holder: the host touches an array whose newest contents are here.
  void bring_back(void* host) override {
    auto it = mirrors_.find(host);
    if (it == mirrors_.end() || !it->second.array.device_dirty) return;
    device_->make_current();
    copy_back(it->second.array);
    ++traffic_.brought_back;
    traffic_.bytes_brought_back += static_cast<long long>(it->second.array.bytes);
  }
  // The host array is freed, or about to be set anew: the device's contents are nobody's.
  void released(const void* host) noexcept override {
    auto it = mirrors_.find(host);
    if (it == mirrors_.end()) return;
    it->second.array.device_dirty = false;
    it->second.version = 0;
    ++traffic_.dropped;
  }

  GpuTraffic traffic_;
  bool emulated_ = false;

 private:
  struct Mirror {
    cuda::DeviceArray array;
    long used = 0;  // the call that last used it
    // The stamp (MapArgs::array_version_in) of the host contents the device copy holds; 0:
    // not known to be the host's (never skipped).
    uint64_t version = 0;
    long refreshed = 0;  // the call that last copied or zeroed it (once per call)
  };
  // A plan's gather index in device memory: per gather, its block, start and k arrays.
  struct IndexUpload {
    uint64_t build = 0;  // DeferredPlan::build_id of what was uploaded
    long used = 0;
    std::vector<cuda::DeviceArray> arrays;
  };

  void copy_back(cuda::DeviceArray& array) {
    device_->to_host(array);
    traffic_.bytes_to_host += static_cast<long long>(array.bytes);
  }

  // An array a kernel wrote (its device copy marked newer): a runtime array stays on the
  // device until the host touches it (runtime/residency.h); any other (the controller's own
  // tables and marks, which it reads straight after) is copied back now.
  void leave_or_copy_back(const void* host, cuda::DeviceArray& array, bool resident) {
    if (!resident) {
      copy_back(array);
      return;
    }
    residency::mark_elsewhere(const_cast<void*>(host), *this);
    ++traffic_.kept_on_device;
    traffic_.bytes_kept += static_cast<long long>(array.bytes);
  }

  // The arrays of a deferred run whose finish_deferred did not come: what the launch left is
  // the device's newest, as after any other run.
  void copy_back_pending() {
    for (const auto& [host, resident] : pending_)
      if (auto it = mirrors_.find(host); it != mirrors_.end())
        leave_or_copy_back(host, it->second.array, resident);
    pending_.clear();
  }

  const cuda::DeviceArray* mirror_of(const void* host) const {
    auto it = mirrors_.find(host);
    return it == mirrors_.end() || it->second.array.device == 0 ? nullptr : &it->second.array;
  }

  // The plan's gather index on the device: uploaded when the plan's tables were built anew
  // since the last upload (a new topology, chunk or pattern), else the copy already there.
  const IndexUpload& upload_index(const DeferredPlan& plan,
                                  const std::vector<DeferredPlan::Gather>& gathers) {
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

  void free_index(IndexUpload& u) {
    for (cuda::DeviceArray& a : u.arrays) device_->free(a);
    u.arrays.clear();
  }

  // The gather kernel, loaded on first use, for the architecture and PTX ISA of the map
  // kernels this executor loaded (their `.target` and `.version`; sm_90 when they name none).
  cuda::CUfunction gather_function() {
    if (!gather_) {
      cuda::CUmodule module = device_->load_module(gather_ptx(arch_, ptx_version_));
      gather_ = device_->function(module, kGatherEntry);
    }
    return gather_;
  }

  // The device copy of `host` (`bytes` long) as the host has it: copied (with Zero, zeroed;
  // with NegativeZero, every double set to -0.0) unless it already holds the host contents
  // stamped `version` (0: unknown, always copied); an array two slots name is refreshed once
  // per call. A new host address or size is a fresh mirror, which holds nothing known. Null
  // for an empty array.
  cuda::DeviceArray* to_device(void* host, size_t bytes, uint64_t version,
                               ArrayFill how = ArrayFill::Copy) {
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

  Mirror& holder(const void* host) { return mirrors_.at(host); }

  // Per pair of patterns (by their numbers, jit/array_stamps.h), the fused sum's source block
  // of each block of b on the device, built and uploaded once.
  struct SumTable {
    cuda::DeviceArray from;
    std::vector<int32_t> host;
    long used = 0;
  };
  const SumTable* sum_table(const runtime::SystemMatrix& a, const runtime::SystemMatrix& b) {
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

  cuda::CUfunction fused_sum_function() {
    if (!fused_sum_) {
      cuda::CUmodule module = device_->load_module(fused_sum_ptx(arch_, ptx_version_));
      fused_sum_ = device_->function(module, kFusedSumEntry);
    }
    return fused_sum_;
  }

  void evict() {
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

  // A kernel's functions, its module loaded on first use: a map kernel's entry, or a device
  // program's step kernels by step.
  const std::vector<cuda::CUfunction>& functions_of(const Kernel& kernel) {
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

  // The kernel on the device: one launch over every element, or, for a map whose elements
  // add into shared blocks in place (no deferred writes), one launch per element in element
  // order (the stream runs them one after another). Returns (code, element).
  std::pair<int32_t, int32_t> launch(const Kernel& kernel, int32_t n, bool in_order,
                                     cuda::CUdeviceptr scalars, cuda::CUdeviceptr endpoints) {
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

  // A local's value as the program's scalars hold it (a double) into its context word, in
  // the local's own type (as a step stores it: little-endian, at the word's address), and
  // back.
  static void put_local(Ty t, double v, int64_t* word) {
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
  static double get_local(Ty t, const int64_t* word) {
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

  // `host` (`bytes`) into device array `a`, reallocated when its size changed.
  void upload(cuda::DeviceArray& a, void* host, size_t bytes) {
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
  // Device-only scratch of at least `bytes`.
  void scratch(cuda::DeviceArray& a, size_t bytes) {
    if (a.bytes >= bytes && a.device != 0) return;
    device_->free(a);
    a = device_->alloc(nullptr, bytes);
    ++traffic_.allocations;
  }

  // Step `index` of a device program over its units: a launch of one unit per thread, or,
  // emulated, the CPU's step function over all of them (the context's device address is a
  // host address there).
  void launch_step(const Kernel& kernel, int32_t index, const DeviceStep& step,
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

  std::unique_ptr<cuda::Device> device_;
  std::unique_ptr<BatchGraphs> graphs_;  // null: batches launched step by step
  std::map<const void*, Mirror> mirrors_;
  // A device program's pointer table, sizes, context and sum scratch (and their host copies).
  std::vector<cuda::CUdeviceptr> system_pointers_host_;
  std::vector<int64_t> sizes_host_, context_host_;
  cuda::DeviceArray system_pointers_, sizes_, context_, lanes_, partials_;
  std::map<const Kernel*, std::vector<cuda::CUfunction>> functions_;
  // Per plan (by address; its build id tells a rebuilt or new plan there), its gather index.
  std::map<const DeferredPlan*, IndexUpload> uploads_;
  // Host arrays a deferred run wrote, copied back by finish_deferred.
  // Host arrays a deferred run wrote, and whether each is a runtime array (left on the
  // device by finish_deferred) or copied back by it.
  std::vector<std::pair<const void*, bool>> pending_;
  cuda::CUfunction gather_ = nullptr, fused_sum_ = nullptr;
  std::map<std::pair<uint64_t, uint64_t>, SumTable> sum_tables_;
  std::string arch_, ptx_version_;  // of the map kernels ("": not seen yet)
  std::vector<cuda::CUdeviceptr> pointers_host_;
  cuda::DeviceArray pointers_, failure_;
  uint64_t failure_word_ = kNoFailure;
  long call_ = 0;
};

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
