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
// Data: each array the kernel reads is copied to the device before the launch and each array
// it writes is copied back after it (the host copy stays the one the rest of the program
// reads); a deferred map's written arrays are copied back after the gather, all but the
// deferred blocks, which never leave the device. Device memory is kept per host array between
// calls and reused while its size holds.
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
}

namespace simit::jit::ptx {

// The executor on this machine's GPU 0; null with `why` when there is none (no driver, a
// driver too old, no device: cuda::gpu_unavailable_reason()).
std::unique_ptr<Executor> make_gpu_executor(std::string& why);

// The executor over the host-memory driver table (map kernels of the CPU target).
std::unique_ptr<Executor> make_emulated_gpu_executor();

// The executor over `table` (a test's fake driver), with kernels of the GPU target: the
// launch path, argument marshalling and copies, tested without a GPU. Throws CudaError when
// the device does not open.
std::unique_ptr<Executor> make_gpu_executor_over(const cuda::DriverTable& table);

// Whether `executor` is one of the above (its kernels must come from the GPU target unless
// it is emulated), and whether it is emulated.
bool is_gpu_executor(const Executor& executor);
bool is_emulated_gpu_executor(const Executor& executor);

// Figures of a GPU executor's data path so far (for --jit-stats and the tests).
struct GpuTraffic {
  long launches = 0;
  long long bytes_to_device = 0;
  long long bytes_to_host = 0;
  long allocations = 0;
  long gather_launches = 0;  // of the gather kernel (counted in launches too)
  long index_uploads = 0;    // gather indices copied to the device (once per plan build)
};
GpuTraffic gpu_traffic(const Executor& executor);

}  // namespace simit::jit::ptx
