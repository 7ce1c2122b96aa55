// The GPU executor: map kernels compiled for the GPU (jit/ptx/ptx_target.h) run on a device
// through the CUDA driver (jit/ptx/cuda_driver.h), one thread per element, with the
// interpreter's bits (docs/arithmetic.md).
//
// A map that adds into shared blocks runs with deferred writes in chunks of one element
// (jit/defer_assembly.h): each block's first element adds in place and every later
// contribution lands in a deferred block of its own, so no two threads write one address and
// no floating-point atomic is needed; the deferred blocks are then added in element order on
// the device (finish_deferred: the gather kernel, jit/ptx/gather_kernel.h, one thread per
// block that has deferred blocks, from the plan's gather index, uploaded once per plan build).
//
// Data: device memory is kept per host array between calls (a mirror, reused while the
// array's address and size hold), and remembers which host contents it holds by the stamp
// the caller gives each array (MapArgs::array_version_in and _out: a field's write version
// with its set's identity, a pattern's table by the pattern, the endpoint table by the set's
// topology). Before a launch an array is copied to the device only when its stamp differs
// from the mirror's (or is 0, unknown: vectors, matrices, the scalars); a result the host
// zeroed is zeroed on the device (cuMemsetD32) rather than copied, and a split run's deferred
// blocks, which the host holds at -0.0, are set to -0.0 there (Device::fill_negative_zero),
// never copied.
//
// What a kernel writes into a runtime array (a field, a vector, a result, a matrix's values:
// MapArgs::array_resident) stays on the device as the newest copy (runtime/residency.h): the
// next kernel that reads it finds it there, and the host gets it back only when it touches the
// array (every accessor of tensors, fields and matrices asks first), when a call returns to
// its host (the interpreter brings everything back then, for the hosts that read through
// pointers of their own), or when this executor goes. An array the host frees or sets anew
// meanwhile is dropped, never copied into. Any other array a kernel writes (the controller's
// marks) is copied back after the launch; a deferred map's written arrays are left or copied
// once the gather has run, all but the deferred blocks, which never leave the device. A
// fused matrix sum whose K the device holds runs there too (add_into: the fused-sum kernel,
// jit/ptx/fused_sum_kernel.h), so that K, M and the sum never cross to the host on their way
// to a solver loop on the device.
//
// Emulated: a driver table over host memory (jit/ptx/host_driver.h) stands in for the GPU,
// and the kernels are the CPU target's, called on the copies in that "device" memory (the
// gather kernel's host equivalent likewise): every step of the data path (what is copied,
// when, the pointer table, the one-element chunks, the gather index, the failure report) runs
// as on a GPU, and its results are compared with the interpreter's where no GPU is (the
// corpus and the random programs under SIMIT_TEST_GPU_EMULATION).
#pragma once

#include <memory>
#include <string>

#include "jit/executor.h"

namespace simit::jit::cuda {
struct DriverTable;
struct StreamTable;
}  // namespace simit::jit::cuda

namespace simit::jit::ptx {

// The executor on this machine's GPU 0; null with `why` when there is none (no driver, a
// driver too old, no device: cuda::gpu_unavailable_reason()).
std::unique_ptr<Executor> make_gpu_executor(std::string& why);

// The executor over the host-memory driver table (map kernels of the CPU target).
std::unique_ptr<Executor> make_emulated_gpu_executor();

// The executor over `table` (a test's fake driver), with kernels of the GPU target: the
// launch path, argument marshalling and copies, tested without a GPU; with `streams`, a device
// program's loop batches run as CUDA graphs captured from a stream. Throws CudaError when the
// device does not open.
std::unique_ptr<Executor> make_gpu_executor_over(const cuda::DriverTable& table,
                                                 const cuda::StreamTable* streams = nullptr);

// Whether `executor` is one of the above (its kernels must come from the GPU target unless
// it is emulated), and whether it is emulated.
bool is_gpu_executor(const Executor& executor);
bool is_emulated_gpu_executor(const Executor& executor);

// Figures of a GPU executor's data path so far (for --jit-stats and the tests).
struct GpuTraffic {
  long launches = 0;
  long long bytes_to_device = 0;  // map arguments copied in, and gather indices
  long long bytes_to_host = 0;
  long allocations = 0;
  // Map arguments (arrays, scalars, endpoint tables): copied in; not copied because the
  // device held the host's contents already; zeroed on the device (results); set to -0.0 on
  // the device (deferred blocks).
  long uploads = 0;
  long uploads_skipped = 0;
  long long bytes_skipped = 0;
  long zeroed = 0;
  long long bytes_zeroed = 0;
  long filled = 0;
  long long bytes_filled = 0;
  long gather_launches = 0;  // of the gather kernel (counted in launches too)
  long index_uploads = 0;    // gather indices copied to the device (once per plan build)
  // Device programs (solver loops): calls, and the host's waits for a batch of iterations.
  long system_runs = 0;
  long system_batches = 0;
  // Their batches as CUDA graphs: captured (once per program, batch and sizes), launched.
  long graphs_captured = 0;
  long graph_launches = 0;
  // Residency (runtime/residency.h): arrays a kernel wrote left on the device as the newest
  // copy (and their bytes); uploads skipped because the device held the newest; arrays
  // copied back because the host touched them; arrays freed or set anew by the host while
  // the device held their newest (never copied back).
  long kept_on_device = 0;
  long long bytes_kept = 0;
  long uploads_resident = 0;
  long brought_back = 0;
  long long bytes_brought_back = 0;
  long dropped = 0;
  // Fused matrix sums run on the device (jit/ptx/fused_sum_kernel.h).
  long fused_sums = 0;
};
GpuTraffic gpu_traffic(const Executor& executor);

}  // namespace simit::jit::ptx
