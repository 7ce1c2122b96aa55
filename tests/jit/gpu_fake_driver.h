// A fake CUDA driver table for the GPU executor's tests (gpu_executor_test.cpp,
// gpu_residency_test.cpp): device memory is host memory, every copy and memory set is counted,
// and each launch is recorded and handed to the test's `on_launch` (map, gather and device
// program step kernels); its stream table captures launches into graphs and replays them.
#pragma once

#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <string>
#include <vector>

#include "jit/ptx/cuda_driver.h"
#include "jit/ptx/fused_sum_kernel.h"
#include "jit/ptx/gather_kernel.h"
#include "jit/ptx/ptx_target.h"

namespace simit::jit::ptx::fake_gpu {

using namespace simit::jit::cuda;

// A driver whose device memory is host memory and whose launches call `on_launch`. Its
// functions: the map kernel's entry, the gather kernel's and the fused-sum kernel's, told
// apart by their handles.
inline int map_function = 0, gather_function = 0, fused_sum_function = 0;
// A device program's step kernels (ptx::kStepEntry's names), by step index.
inline int step_functions[64];
struct Launch {
  bool gather = false;
  unsigned grid = 0, block = 0;
  // A map kernel's parameters.
  CUdeviceptr table = 0, scalars = 0, endpoints = 0, failure = 0;
  int32_t begin = 0, end = 0;
  // The gather kernel's.
  GatherArgs g;
  // The fused-sum kernel's.
  bool fused_sum = false;
  FusedSumArgs sum;
  // A device program's step kernel: its index (-1: not one), the context and the units.
  int step = -1;
  CUdeviceptr context = 0;
  int64_t units = 0;
};
// One cuMemsetD2D32: `height` rows of `width` words set to `value`, `pitch` bytes apart.
struct Set2D {
  CUdeviceptr to = 0;
  std::size_t pitch = 0;
  unsigned value = 0;
  std::size_t width = 0, height = 0;
};
struct Fake {
  int allocations = 0, frees = 0;
  long long to_device = 0, to_host = 0;
  long long zeroed = 0;              // bytes set to zero (cuMemsetD8, cuMemsetD32)
  std::vector<Set2D> sets_2d;        // every cuMemsetD2D32, in order
  std::string ptx;                   // the last module loaded
  std::vector<std::string> modules;  // every module loaded, in order
  std::vector<Launch> launches;
  std::function<void(const Launch&)> on_launch;
  // Streams and graphs (fake_streams): a launch into a capturing stream is recorded, not run;
  // a graph launch runs its recorded launches in order.
  bool capturing = false;
  std::vector<Launch> capture;
  std::vector<std::vector<Launch>> graphs;  // by handle - 1
  int streams_created = 0, streams_destroyed = 0, graphs_destroyed = 0, execs_destroyed = 0;
  int graph_launches = 0;
};
inline Fake* fake = nullptr;

template <class T>
T param(void** params, int i) {
  T v;
  std::memcpy(&v, params[i], sizeof v);
  return v;
}

inline DriverTable fake_table() {
  DriverTable t;
  t.cuInit = [](unsigned) { return CUDA_SUCCESS; };
  t.cuDriverGetVersion = [](int* v) {
    *v = 13000;
    return CUDA_SUCCESS;
  };
  t.cuGetErrorString = [](CUresult, const char** s) {
    *s = "fake error";
    return CUDA_SUCCESS;
  };
  t.cuDeviceGet = [](CUdevice* d, int) {
    *d = 0;
    return CUDA_SUCCESS;
  };
  t.cuDeviceGetCount = [](int* n) {
    *n = 1;
    return CUDA_SUCCESS;
  };
  t.cuDeviceGetName = [](char* name, int len, CUdevice) {
    std::snprintf(name, static_cast<size_t>(len), "Fake GPU");
    return CUDA_SUCCESS;
  };
  t.cuDeviceGetAttribute = [](int* v, CUdevice_attribute, CUdevice) {
    *v = 9;
    return CUDA_SUCCESS;
  };
  t.cuDeviceTotalMem = [](std::size_t* b, CUdevice) {
    *b = 1 << 30;
    return CUDA_SUCCESS;
  };
  t.cuDevicePrimaryCtxRetain = [](CUcontext* c, CUdevice) {
    static int context;
    *c = reinterpret_cast<CUcontext>(&context);
    return CUDA_SUCCESS;
  };
  t.cuDevicePrimaryCtxRelease = [](CUdevice) { return CUDA_SUCCESS; };
  t.cuCtxSetCurrent = [](CUcontext) { return CUDA_SUCCESS; };
  t.cuCtxSynchronize = [] { return CUDA_SUCCESS; };
  t.cuModuleLoadDataEx = [](CUmodule* m, const void* image, unsigned, CUjit_option*, void**) {
    fake->ptx = static_cast<const char*>(image);
    fake->modules.push_back(fake->ptx);
    static int module;
    *m = reinterpret_cast<CUmodule>(&module);
    return CUDA_SUCCESS;
  };
  t.cuModuleUnload = [](CUmodule) { return CUDA_SUCCESS; };
  t.cuModuleGetFunction = [](CUfunction* f, CUmodule, const char* name) {
    const std::string n = name, step = std::string(kStepEntry) + "_step";
    if (n.rfind(step, 0) == 0) {
      *f = reinterpret_cast<CUfunction>(&step_functions[std::stoi(n.substr(step.size()))]);
      return CUDA_SUCCESS;
    }
    if (n == kFusedSumEntry) {
      *f = reinterpret_cast<CUfunction>(&fused_sum_function);
      return CUDA_SUCCESS;
    }
    if (n != kMapEntry && n != kGatherEntry) return CUDA_ERROR_NOT_FOUND;
    *f = reinterpret_cast<CUfunction>(n == kMapEntry ? &map_function : &gather_function);
    return CUDA_SUCCESS;
  };
  t.cuMemAlloc = [](CUdeviceptr* p, std::size_t bytes) {
    ++fake->allocations;
    *p = reinterpret_cast<CUdeviceptr>(std::malloc(bytes));
    return CUDA_SUCCESS;
  };
  t.cuMemFree = [](CUdeviceptr p) {
    ++fake->frees;
    std::free(reinterpret_cast<void*>(p));
    return CUDA_SUCCESS;
  };
  t.cuMemcpyHtoD = [](CUdeviceptr to, const void* from, std::size_t bytes) {
    fake->to_device += static_cast<long long>(bytes);
    std::memcpy(reinterpret_cast<void*>(to), from, bytes);
    return CUDA_SUCCESS;
  };
  t.cuMemcpyDtoH = [](void* to, CUdeviceptr from, std::size_t bytes) {
    fake->to_host += static_cast<long long>(bytes);
    std::memcpy(to, reinterpret_cast<const void*>(from), bytes);
    return CUDA_SUCCESS;
  };
  t.cuMemsetD8 = [](CUdeviceptr to, unsigned char value, std::size_t count) {
    fake->zeroed += value == 0 ? static_cast<long long>(count) : 0;
    std::memset(reinterpret_cast<void*>(to), value, count);
    return CUDA_SUCCESS;
  };
  t.cuMemsetD32 = [](CUdeviceptr to, unsigned int value, std::size_t count) {
    fake->zeroed += value == 0 ? static_cast<long long>(4 * count) : 0;
    for (std::size_t i = 0; i < count; ++i) reinterpret_cast<unsigned int*>(to)[i] = value;
    return CUDA_SUCCESS;
  };
  t.cuMemsetD2D32 = [](CUdeviceptr to, std::size_t pitch, unsigned value, std::size_t width,
                       std::size_t height) {
    fake->sets_2d.push_back(Set2D{to, pitch, value, width, height});
    for (std::size_t row = 0; row < height; ++row)
      for (std::size_t i = 0; i < width; ++i)
        reinterpret_cast<unsigned int*>(to + row * pitch)[i] = value;
    return CUDA_SUCCESS;
  };
  t.cuLaunchKernel = [](CUfunction f, unsigned gx, unsigned, unsigned, unsigned bx, unsigned,
                        unsigned, unsigned, CUstream, void** params, void**) {
    Launch l;
    l.grid = gx;
    l.block = bx;
    l.gather = f == reinterpret_cast<CUfunction>(&gather_function);
    l.fused_sum = f == reinterpret_cast<CUfunction>(&fused_sum_function);
    const auto* fn = reinterpret_cast<const int*>(f);
    if (fn >= step_functions && fn < step_functions + 64) {
      l.step = static_cast<int>(fn - step_functions);
      l.context = param<CUdeviceptr>(params, 0);
      l.units = param<int64_t>(params, 1);
    } else if (l.fused_sum) {
      l.sum.b = reinterpret_cast<double*>(param<CUdeviceptr>(params, 0));
      l.sum.a = reinterpret_cast<const double*>(param<CUdeviceptr>(params, 1));
      l.sum.from = reinterpret_cast<const int32_t*>(param<CUdeviceptr>(params, 2));
      l.sum.alpha = param<double>(params, 3);
      l.sum.beta = param<double>(params, 4);
      l.sum.blocks = param<uint32_t>(params, 5);
      l.sum.components = param<uint32_t>(params, 6);
      l.sum.zero_plus = param<uint32_t>(params, 7);
      l.sum.float32 = param<uint32_t>(params, 8);
    } else if (l.gather) {
      l.g.values = reinterpret_cast<double*>(param<CUdeviceptr>(params, 0));
      l.g.deferred = reinterpret_cast<const double*>(param<CUdeviceptr>(params, 1));
      l.g.block = reinterpret_cast<const int32_t*>(param<CUdeviceptr>(params, 2));
      l.g.start = reinterpret_cast<const int32_t*>(param<CUdeviceptr>(params, 3));
      l.g.k = reinterpret_cast<const int32_t*>(param<CUdeviceptr>(params, 4));
      l.g.blocks = param<uint32_t>(params, 5);
      l.g.components = param<uint32_t>(params, 6);
      l.g.round32 = param<uint32_t>(params, 7);
    } else {
      l.table = param<CUdeviceptr>(params, 0);
      l.scalars = param<CUdeviceptr>(params, 1);
      l.endpoints = param<CUdeviceptr>(params, 2);
      l.begin = param<int32_t>(params, 3);
      l.end = param<int32_t>(params, 4);
      l.failure = param<CUdeviceptr>(params, 5);
    }
    if (fake->capturing) {
      fake->capture.push_back(l);
      return CUDA_SUCCESS;
    }
    fake->launches.push_back(l);
    if (fake->on_launch) fake->on_launch(l);
    return CUDA_SUCCESS;
  };
  return t;
}

// The stream table of the fake: one stream at a time, graphs captured from it.
inline StreamTable fake_streams() {
  StreamTable s;
  static int stream;
  s.cuStreamCreate = [](CUstream* out, unsigned) {
    ++fake->streams_created;
    *out = reinterpret_cast<CUstream>(&stream);
    return CUDA_SUCCESS;
  };
  s.cuStreamDestroy = [](CUstream) {
    ++fake->streams_destroyed;
    return CUDA_SUCCESS;
  };
  s.cuStreamSynchronize = [](CUstream) { return CUDA_SUCCESS; };
  s.cuEventCreate = [](CUevent*, unsigned) { return CUDA_ERROR_INVALID_VALUE; };
  s.cuEventDestroy = [](CUevent) { return CUDA_ERROR_INVALID_VALUE; };
  s.cuEventRecord = [](CUevent, CUstream) { return CUDA_ERROR_INVALID_VALUE; };
  s.cuEventSynchronize = [](CUevent) { return CUDA_ERROR_INVALID_VALUE; };
  s.cuEventElapsedTime = [](float*, CUevent, CUevent) { return CUDA_ERROR_INVALID_VALUE; };
  s.cuStreamBeginCapture = [](CUstream, CUstreamCaptureMode) {
    if (fake->capturing) return CUDA_ERROR_INVALID_VALUE;
    fake->capturing = true;
    fake->capture.clear();
    return CUDA_SUCCESS;
  };
  s.cuStreamEndCapture = [](CUstream, CUgraph* graph) {
    if (!fake->capturing) return CUDA_ERROR_INVALID_VALUE;
    fake->capturing = false;
    fake->graphs.push_back(fake->capture);
    *graph = reinterpret_cast<CUgraph>(fake->graphs.size());
    return CUDA_SUCCESS;
  };
  s.cuGraphInstantiateWithFlags = [](CUgraphExec* exec, CUgraph graph, unsigned long long) {
    *exec = reinterpret_cast<CUgraphExec>(graph);
    return CUDA_SUCCESS;
  };
  s.cuGraphLaunch = [](CUgraphExec exec, CUstream) {
    ++fake->graph_launches;
    for (const Launch& l : fake->graphs.at(reinterpret_cast<size_t>(exec) - 1)) {
      fake->launches.push_back(l);
      if (fake->on_launch) fake->on_launch(l);
    }
    return CUDA_SUCCESS;
  };
  s.cuGraphExecDestroy = [](CUgraphExec) {
    ++fake->execs_destroyed;
    return CUDA_SUCCESS;
  };
  s.cuGraphDestroy = [](CUgraph) {
    ++fake->graphs_destroyed;
    return CUDA_SUCCESS;
  };
  s.cuMemcpyDtoD = [](CUdeviceptr, CUdeviceptr, std::size_t) { return CUDA_ERROR_INVALID_VALUE; };
  s.cuMemAllocHost = [](void**, std::size_t) { return CUDA_ERROR_INVALID_VALUE; };
  s.cuMemFreeHost = [](void*) { return CUDA_ERROR_INVALID_VALUE; };
  return s;
}

class GpuExecutorFake : public ::testing::Test {
 protected:
  void SetUp() override { fake = &state; }
  void TearDown() override { fake = nullptr; }
  Fake state;
};

template <class T>
T* at(CUdeviceptr p) {
  return reinterpret_cast<T*>(p);
}

}  // namespace simit::jit::ptx::fake_gpu
