// A CUDA driver table over host memory: "device" allocations are host allocations and copies
// are memcpy (memory sets memset). It lets the GPU executor's data path (jit/ptx/gpu_executor.h)
// run where there is no GPU, with the CPU target's kernels called on its copies; it loads no module
// and launches nothing (those calls fail with CUDA_ERROR_NOT_SUPPORTED).
#pragma once

#include "jit/ptx/cuda_driver.h"

namespace simit::jit::cuda {

inline constexpr CUresult CUDA_ERROR_NOT_SUPPORTED = 801;

DriverTable host_driver_table();

}  // namespace simit::jit::cuda
