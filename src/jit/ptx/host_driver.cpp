// The host-memory driver table (jit/ptx/host_driver.h).
#include "jit/ptx/host_driver.h"

#include <cstdio>
#include <cstdlib>
#include <cstring>

namespace simit::jit::cuda {

namespace {

CUresult get_error_string(CUresult error, const char** str) {
  switch (error) {
    case CUDA_SUCCESS: *str = "no error"; return CUDA_SUCCESS;
    case CUDA_ERROR_OUT_OF_MEMORY: *str = "out of memory"; return CUDA_SUCCESS;
    case CUDA_ERROR_NOT_SUPPORTED:
      *str = "operation not supported by the host emulation";
      return CUDA_SUCCESS;
    default: *str = "error"; return CUDA_SUCCESS;
  }
}
CUresult init(unsigned int) { return CUDA_SUCCESS; }
CUresult driver_version(int* v) {
  *v = 0;
  return CUDA_SUCCESS;
}
CUresult device_get(CUdevice* d, int ordinal) {
  if (ordinal != 0) return CUDA_ERROR_INVALID_DEVICE;
  *d = 0;
  return CUDA_SUCCESS;
}
CUresult device_count(int* n) {
  *n = 1;
  return CUDA_SUCCESS;
}
CUresult device_name(char* name, int len, CUdevice) {
  std::snprintf(name, static_cast<size_t>(len), "host emulation");
  return CUDA_SUCCESS;
}
CUresult device_attribute(int* value, CUdevice_attribute a, CUdevice) {
  *value = a == CU_DEVICE_ATTRIBUTE_MULTIPROCESSOR_COUNT       ? 1
           : a == CU_DEVICE_ATTRIBUTE_COMPUTE_CAPABILITY_MAJOR ? 9
                                                               : 0;
  return CUDA_SUCCESS;
}
CUresult total_mem(std::size_t* bytes, CUdevice) {
  *bytes = std::size_t{1} << 34;
  return CUDA_SUCCESS;
}
// Any non-null handle: the context is never dereferenced.
CUresult ctx_retain(CUcontext* c, CUdevice) {
  static int context = 0;
  *c = reinterpret_cast<CUcontext>(&context);
  return CUDA_SUCCESS;
}
CUresult ctx_release(CUdevice) { return CUDA_SUCCESS; }
CUresult ctx_set(CUcontext) { return CUDA_SUCCESS; }
CUresult ctx_sync() { return CUDA_SUCCESS; }
CUresult module_load(CUmodule*, const void*, unsigned int, CUjit_option*, void**) {
  return CUDA_ERROR_NOT_SUPPORTED;
}
CUresult module_unload(CUmodule) { return CUDA_SUCCESS; }
CUresult module_function(CUfunction*, CUmodule, const char*) { return CUDA_ERROR_NOT_SUPPORTED; }
CUresult mem_alloc(CUdeviceptr* p, std::size_t bytes) {
  void* m = std::malloc(bytes ? bytes : 1);
  if (!m) return CUDA_ERROR_OUT_OF_MEMORY;
  *p = reinterpret_cast<CUdeviceptr>(m);
  return CUDA_SUCCESS;
}
CUresult mem_free(CUdeviceptr p) {
  std::free(reinterpret_cast<void*>(p));
  return CUDA_SUCCESS;
}
CUresult htod(CUdeviceptr to, const void* from, std::size_t bytes) {
  std::memcpy(reinterpret_cast<void*>(to), from, bytes);
  return CUDA_SUCCESS;
}
CUresult dtoh(void* to, CUdeviceptr from, std::size_t bytes) {
  std::memcpy(to, reinterpret_cast<const void*>(from), bytes);
  return CUDA_SUCCESS;
}
CUresult memset8(CUdeviceptr to, unsigned char value, std::size_t count) {
  std::memset(reinterpret_cast<void*>(to), value, count);
  return CUDA_SUCCESS;
}
CUresult memset32(CUdeviceptr to, unsigned int value, std::size_t count) {
  auto* words = reinterpret_cast<unsigned int*>(to);
  for (std::size_t i = 0; i < count; ++i) words[i] = value;
  return CUDA_SUCCESS;
}
CUresult memset2d32(CUdeviceptr to, std::size_t pitch, unsigned int value, std::size_t width,
                    std::size_t height) {
  for (std::size_t row = 0; row < height; ++row) {
    auto* words = reinterpret_cast<unsigned int*>(to + row * pitch);
    for (std::size_t i = 0; i < width; ++i) words[i] = value;
  }
  return CUDA_SUCCESS;
}
CUresult launch(CUfunction, unsigned int, unsigned int, unsigned int, unsigned int, unsigned int,
                unsigned int, unsigned int, CUstream, void**, void**) {
  return CUDA_ERROR_NOT_SUPPORTED;
}

}  // namespace

DriverTable host_driver_table() {
  DriverTable t;
  t.cuInit = init;
  t.cuDriverGetVersion = driver_version;
  t.cuGetErrorString = get_error_string;
  t.cuDeviceGet = device_get;
  t.cuDeviceGetCount = device_count;
  t.cuDeviceGetName = device_name;
  t.cuDeviceGetAttribute = device_attribute;
  t.cuDeviceTotalMem = total_mem;
  t.cuDevicePrimaryCtxRetain = ctx_retain;
  t.cuDevicePrimaryCtxRelease = ctx_release;
  t.cuCtxSetCurrent = ctx_set;
  t.cuCtxSynchronize = ctx_sync;
  t.cuModuleLoadDataEx = module_load;
  t.cuModuleUnload = module_unload;
  t.cuModuleGetFunction = module_function;
  t.cuMemAlloc = mem_alloc;
  t.cuMemFree = mem_free;
  t.cuMemcpyHtoD = htod;
  t.cuMemcpyDtoH = dtoh;
  t.cuLaunchKernel = launch;
  t.cuMemsetD8 = memset8;
  t.cuMemsetD32 = memset32;
  t.cuMemsetD2D32 = memset2d32;
  return t;
}

}  // namespace simit::jit::cuda
