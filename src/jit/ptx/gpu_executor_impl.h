// The GPU executor's class (jit/ptx/gpu_executor.h), shared by the files that define its
// parts: maps, mirrors and residency (gpu_executor.cpp), device programs
// (gpu_device_programs.cpp) and the fused matrix sum (gpu_fused_sum.cpp).
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "jit/deferred_plan.h"
#include "jit/device_program.h"
#include "jit/executor.h"
#include "jit/ptx/batch_graphs.h"
#include "jit/ptx/cuda_driver.h"
#include "jit/ptx/gpu_executor.h"
#include "jit/ptx/ptx_target.h"
#include "runtime/residency.h"
#include "runtime/system_matrix.h"

namespace simit::jit::ptx::gpu {

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
              const std::optional<cuda::StreamTable>& streams);
  ~GpuExecutor() override;

  const char* name() const override { return emulated_ ? "gpu (emulated)" : "gpu"; }
  bool parallel() const override { return true; }
  // One thread per element: each is its own chunk of a deferred assembly.
  int32_t chunk_for(int32_t) const override { return 1; }

  MapOutcome run_map(const Kernel& kernel, const MapArgs& args, int32_t n, int32_t,
                     MapWrites writes, const std::function<bool()>& interrupt) override;

  // Each result's deferred blocks added on the device, one thread per block that has some
  // (the gather kernel; emulated, its host equivalent over the "device" memory), then the
  // arrays the map wrote left there or copied back (leave_or_copy_back), but for the
  // deferred blocks, which the host never reads.
  void finish_deferred(const DeferredPlan& plan, const std::vector<double*>& values) override;

  // A device program (jit/device_program.h): its arrays mirrored as a map's are, its
  // scalars in the context array, its steps launched one after another with nothing read
  // back between them; the loop's steps in batches of iterations, after each of which the
  // host reads the context's stop and error words (and takes an interrupt). A kernel that is
  // not a device program runs on the host, its arrays brought back first.
  int32_t run_system(const Kernel& kernel, const SystemArgs& args) override;

  // The fused matrix sum on the device, where b's newest values are (its map assembled it
  // there): one thread per block of b (the fused-sum kernel, jit/ptx/fused_sum_kernel.h),
  // a's values copied in unless they are there too, b left there as the newest.
  bool add_into(const runtime::SystemMatrix& a, double alpha, runtime::SystemMatrix& b, double beta,
                bool float32) override;

  // residency::Holder: the host touches an array whose newest contents are here.
  void bring_back(void* host) override;
  // The host array is freed, or about to be set anew: the device's contents are nobody's.
  void released(const void* host) noexcept override;

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
  void leave_or_copy_back(const void* host, cuda::DeviceArray& array, bool resident);

  // The arrays of a deferred run whose finish_deferred did not come: what the launch left is
  // the device's newest, as after any other run.
  void copy_back_pending();

  const cuda::DeviceArray* mirror_of(const void* host) const {
    auto it = mirrors_.find(host);
    return it == mirrors_.end() || it->second.array.device == 0 ? nullptr : &it->second.array;
  }

  // The plan's gather index on the device: uploaded when the plan's tables were built anew
  // since the last upload (a new topology, chunk or pattern), else the copy already there.
  const IndexUpload& upload_index(const DeferredPlan& plan,
                                  const std::vector<DeferredPlan::Gather>& gathers);

  void free_index(IndexUpload& u) {
    for (cuda::DeviceArray& a : u.arrays) device_->free(a);
    u.arrays.clear();
  }

  // The gather kernel, loaded on first use, for the architecture and PTX ISA of the map
  // kernels this executor loaded (their `.target` and `.version`; sm_90 when they name none).
  cuda::CUfunction gather_function();

  // The device copy of `host` (`bytes` long) as the host has it: copied (with Zero, zeroed;
  // with NegativeZero, every double set to -0.0) unless it already holds the host contents
  // stamped `version` (0: unknown, always copied); an array two slots name is refreshed once
  // per call. A new host address or size is a fresh mirror, which holds nothing known. Null
  // for an empty array.
  cuda::DeviceArray* to_device(void* host, size_t bytes, uint64_t version,
                               ArrayFill how = ArrayFill::Copy);

  Mirror& holder(const void* host) { return mirrors_.at(host); }

  // Per pair of patterns (by their numbers, jit/array_stamps.h), the fused sum's source block
  // of each block of b on the device, built and uploaded once.
  struct SumTable {
    cuda::DeviceArray from;
    std::vector<int32_t> host;
    long used = 0;
  };
  const SumTable* sum_table(const runtime::SystemMatrix& a, const runtime::SystemMatrix& b);

  // The fused-sum kernel, loaded on first use as the gather kernel is.
  cuda::CUfunction fused_sum_function();

  // Frees the mirrors, gather indices and sum tables no call used for kKeepCalls calls (a
  // mirror whose device copy is the newest comes home first).
  void evict();

  // A kernel's functions, its module loaded on first use: a map kernel's entry, or a device
  // program's step kernels by step.
  const std::vector<cuda::CUfunction>& functions_of(const Kernel& kernel);

  // The kernel on the device: one launch over every element, or, for a map whose elements
  // add into shared blocks in place (no deferred writes), one launch per element in element
  // order (the stream runs them one after another). Returns (code, element).
  std::pair<int32_t, int32_t> launch(const Kernel& kernel, int32_t n, bool in_order,
                                     cuda::CUdeviceptr scalars, cuda::CUdeviceptr endpoints);

  // A local's value as the program's scalars hold it (a double) into its context word, in
  // the local's own type (as a step stores it: little-endian, at the word's address), and
  // back.
  static void put_local(Ty t, double v, int64_t* word);
  static double get_local(Ty t, const int64_t* word);

  // `host` (`bytes`) into device array `a`, reallocated when its size changed.
  void upload(cuda::DeviceArray& a, void* host, size_t bytes);
  // Device-only scratch of at least `bytes`.
  void scratch(cuda::DeviceArray& a, size_t bytes);

  // Step `index` of a device program over its units: a launch of one unit per thread, or,
  // emulated, the CPU's step function over all of them (the context's device address is a
  // host address there).
  void launch_step(const Kernel& kernel, int32_t index, const DeviceStep& step,
                   const DeviceProgram& p, const std::vector<int64_t>& sizes,
                   cuda::CUstream stream);

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

}  // namespace simit::jit::ptx::gpu
