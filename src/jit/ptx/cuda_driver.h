// The CUDA driver, loaded at run time: nothing links -lcuda, so the project builds and runs
// where there is no NVIDIA driver. libcuda.so.1 is dlopen'd and every entry point is resolved
// through cuGetProcAddress with the CUDA version of the ABI we call (the versioned typedefs of
// the toolkit's cudaTypedefs.h). `Device` works over an injected `DriverTable`, so the launch
// path, argument marshalling and residency are tested against a fake driver without a GPU.
//
// The toolkit's headers are not needed to build: the few types and constants used are
// declared here with the driver API's documented ABI and values (CUDA Driver API reference,
// cuda.h: "Data types used by CUDA driver" and "Error Handling").
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <functional>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

namespace simit::jit::cuda {

// ---- Driver API types (cuda.h). Handles are opaque pointers; CUdeviceptr is the 64-bit
// `CUdeviceptr_v2` (unsigned long long) of every _v2 memory entry point; enums are C enums,
// passed as int.
using CUresult = int;                    // enum cudaError_enum
using CUdevice = int;                    // CUdevice_v1
using CUdeviceptr = unsigned long long;  // CUdeviceptr_v2
using CUcontext = struct CUctx_st*;
using CUmodule = struct CUmod_st*;
using CUfunction = struct CUfunc_st*;
using CUstream = struct CUstream_st*;
using CUdevice_attribute = int;  // enum CUdevice_attribute_enum
using CUjit_option = int;        // enum CUjit_option_enum
using cuuint64_t = std::uint64_t;
using CUdriverProcAddressQueryResult = int;  // enum CUdriverProcAddressQueryResult_enum

// cudaError_enum values used by name here (the rest are reported through cuGetErrorString).
inline constexpr CUresult CUDA_SUCCESS = 0;
inline constexpr CUresult CUDA_ERROR_INVALID_VALUE = 1;
inline constexpr CUresult CUDA_ERROR_OUT_OF_MEMORY = 2;
inline constexpr CUresult CUDA_ERROR_NOT_INITIALIZED = 3;
inline constexpr CUresult CUDA_ERROR_NO_DEVICE = 100;
inline constexpr CUresult CUDA_ERROR_INVALID_DEVICE = 101;
inline constexpr CUresult CUDA_ERROR_INVALID_PTX = 218;
inline constexpr CUresult CUDA_ERROR_NOT_FOUND = 500;
// CUdevice_attribute_enum.
inline constexpr CUdevice_attribute CU_DEVICE_ATTRIBUTE_MULTIPROCESSOR_COUNT = 16;
inline constexpr CUdevice_attribute CU_DEVICE_ATTRIBUTE_COMPUTE_CAPABILITY_MAJOR = 75;
inline constexpr CUdevice_attribute CU_DEVICE_ATTRIBUTE_COMPUTE_CAPABILITY_MINOR = 76;
// CUjit_option_enum: the error log of a PTX that does not load (option values are a char*
// and an unsigned int passed in the void* itself).
inline constexpr CUjit_option CU_JIT_ERROR_LOG_BUFFER = 5;
inline constexpr CUjit_option CU_JIT_ERROR_LOG_BUFFER_SIZE_BYTES = 6;
// CUdriverProcAddress_flags and CUdriverProcAddressQueryResult_enum.
inline constexpr cuuint64_t CU_GET_PROC_ADDRESS_DEFAULT = 0;
inline constexpr CUdriverProcAddressQueryResult CU_GET_PROC_ADDRESS_SUCCESS = 0;
inline constexpr CUdriverProcAddressQueryResult CU_GET_PROC_ADDRESS_SYMBOL_NOT_FOUND = 1;
inline constexpr CUdriverProcAddressQueryResult CU_GET_PROC_ADDRESS_VERSION_NOT_SUFFICIENT = 2;

// ---- Function-pointer types, named as in cudaTypedefs.h: PFN_<base name>_v<the CUDA version
// whose ABI it is>. That version is what cuGetProcAddress is asked for, so a newer driver
// still hands back this ABI (e.g. cuCtxSynchronize_v13000 takes a context; v2000 does not).
using PFN_cuGetErrorString_v6000 = CUresult (*)(CUresult error, const char** str);
using PFN_cuInit_v2000 = CUresult (*)(unsigned int flags);
using PFN_cuDriverGetVersion_v2020 = CUresult (*)(int* version);
using PFN_cuDeviceGet_v2000 = CUresult (*)(CUdevice* device, int ordinal);
using PFN_cuDeviceGetCount_v2000 = CUresult (*)(int* count);
using PFN_cuDeviceGetName_v2000 = CUresult (*)(char* name, int len, CUdevice dev);
using PFN_cuDeviceTotalMem_v3020 = CUresult (*)(std::size_t* bytes, CUdevice dev);
using PFN_cuDeviceGetAttribute_v2000 = CUresult (*)(int* value, CUdevice_attribute attribute,
                                                    CUdevice dev);
using PFN_cuDevicePrimaryCtxRetain_v7000 = CUresult (*)(CUcontext* context, CUdevice dev);
using PFN_cuDevicePrimaryCtxRelease_v11000 = CUresult (*)(CUdevice dev);
using PFN_cuCtxSetCurrent_v4000 = CUresult (*)(CUcontext context);
using PFN_cuCtxSynchronize_v2000 = CUresult (*)();
using PFN_cuModuleLoadDataEx_v2010 = CUresult (*)(CUmodule* module, const void* image,
                                                  unsigned int num_options, CUjit_option* options,
                                                  void** option_values);
using PFN_cuModuleUnload_v2000 = CUresult (*)(CUmodule module);
using PFN_cuModuleGetFunction_v2000 = CUresult (*)(CUfunction* function, CUmodule module,
                                                   const char* name);
using PFN_cuMemAlloc_v3020 = CUresult (*)(CUdeviceptr* pointer, std::size_t bytes);
using PFN_cuMemFree_v3020 = CUresult (*)(CUdeviceptr pointer);
using PFN_cuMemcpyHtoD_v3020 = CUresult (*)(CUdeviceptr destination, const void* source,
                                            std::size_t bytes);
using PFN_cuMemcpyDtoH_v3020 = CUresult (*)(void* destination, CUdeviceptr source,
                                            std::size_t bytes);
using PFN_cuMemsetD8_v3020 = CUresult (*)(CUdeviceptr destination, unsigned char value,
                                          std::size_t count);
using PFN_cuMemsetD32_v3020 = CUresult (*)(CUdeviceptr destination, unsigned int value,
                                           std::size_t count);
// Rows of `width` 32-bit words set to `value`, `height` rows `pitch` bytes apart.
using PFN_cuMemsetD2D32_v3020 = CUresult (*)(CUdeviceptr destination, std::size_t pitch,
                                             unsigned int value, std::size_t width,
                                             std::size_t height);
using PFN_cuLaunchKernel_v4000 = CUresult (*)(CUfunction function, unsigned int grid_x,
                                              unsigned int grid_y, unsigned int grid_z,
                                              unsigned int block_x, unsigned int block_y,
                                              unsigned int block_z, unsigned int shared_bytes,
                                              CUstream stream, void** kernel_params, void** extra);
// cuGetProcAddress: the CUDA 12 entry point (exported as cuGetProcAddress_v2) reports why a
// symbol was not found; the CUDA 11.3 one (exported as cuGetProcAddress) does not.
using PFN_cuGetProcAddress_v12000 = CUresult (*)(const char* symbol, void** pfn, int version,
                                                 cuuint64_t flags,
                                                 CUdriverProcAddressQueryResult* status);
using PFN_cuGetProcAddress_v11030 = CUresult (*)(const char* symbol, void** pfn, int version,
                                                 cuuint64_t flags);

// The driver's entry points this project calls. Every one is set in a table that
// load_driver returns; a test sets its own (static functions over a fake device).
struct DriverTable {
  PFN_cuInit_v2000 cuInit = nullptr;
  PFN_cuDriverGetVersion_v2020 cuDriverGetVersion = nullptr;
  PFN_cuGetErrorString_v6000 cuGetErrorString = nullptr;
  PFN_cuDeviceGet_v2000 cuDeviceGet = nullptr;
  PFN_cuDeviceGetCount_v2000 cuDeviceGetCount = nullptr;
  PFN_cuDeviceGetName_v2000 cuDeviceGetName = nullptr;
  PFN_cuDeviceGetAttribute_v2000 cuDeviceGetAttribute = nullptr;
  PFN_cuDeviceTotalMem_v3020 cuDeviceTotalMem = nullptr;  // cuDeviceTotalMem_v2
  PFN_cuDevicePrimaryCtxRetain_v7000 cuDevicePrimaryCtxRetain = nullptr;
  PFN_cuDevicePrimaryCtxRelease_v11000 cuDevicePrimaryCtxRelease = nullptr;  // _v2
  PFN_cuCtxSetCurrent_v4000 cuCtxSetCurrent = nullptr;
  PFN_cuCtxSynchronize_v2000 cuCtxSynchronize = nullptr;
  PFN_cuModuleLoadDataEx_v2010 cuModuleLoadDataEx = nullptr;
  PFN_cuModuleUnload_v2000 cuModuleUnload = nullptr;
  PFN_cuModuleGetFunction_v2000 cuModuleGetFunction = nullptr;
  PFN_cuMemAlloc_v3020 cuMemAlloc = nullptr;          // cuMemAlloc_v2
  PFN_cuMemFree_v3020 cuMemFree = nullptr;            // cuMemFree_v2
  PFN_cuMemcpyHtoD_v3020 cuMemcpyHtoD = nullptr;      // cuMemcpyHtoD_v2
  PFN_cuMemcpyDtoH_v3020 cuMemcpyDtoH = nullptr;      // cuMemcpyDtoH_v2
  PFN_cuLaunchKernel_v4000 cuLaunchKernel = nullptr;  // the legacy default stream
  // Device memory set to a value (the GPU executor zeroes results with them rather than
  // copying zeros over, and sets deferred blocks to -0.0 with cuMemsetD32 and cuMemsetD2D32:
  // Device::fill_negative_zero). Not among the entries a Device needs to open (missing_entry does
  // not list them, resolve_driver does not ask for them): load_driver resolves them apart
  // (resolve_memset), and Device::zero refuses a table without them.
  PFN_cuMemsetD8_v3020 cuMemsetD8 = nullptr;        // cuMemsetD8_v2
  PFN_cuMemsetD32_v3020 cuMemsetD32 = nullptr;      // cuMemsetD32_v2
  PFN_cuMemsetD2D32_v3020 cuMemsetD2D32 = nullptr;  // cuMemsetD2D32_v2
};

// ---- Streams, events, graphs, pinned host memory and device-to-device copies: what timing
// launches and copies needs (bench/gpu_probe). A table of its own, resolved apart from
// DriverTable, so that a table without these entries (a test's, or one a program does not
// need them in) still opens a Device.
using CUevent = struct CUevent_st*;
using CUgraph = struct CUgraph_st*;
using CUgraphExec = struct CUgraphExec_st*;
using CUstreamCaptureMode = int;  // enum CUstreamCaptureMode_enum
// CUstream_flags_enum, CUevent_flags_enum and CUstreamCaptureMode_enum.
inline constexpr unsigned int CU_STREAM_DEFAULT = 0;
inline constexpr unsigned int CU_STREAM_NON_BLOCKING = 1;
inline constexpr unsigned int CU_EVENT_DEFAULT = 0;
inline constexpr CUstreamCaptureMode CU_STREAM_CAPTURE_MODE_GLOBAL = 0;
inline constexpr CUstreamCaptureMode CU_STREAM_CAPTURE_MODE_THREAD_LOCAL = 1;

using PFN_cuStreamCreate_v2000 = CUresult (*)(CUstream* stream, unsigned int flags);
using PFN_cuStreamDestroy_v4000 = CUresult (*)(CUstream stream);
using PFN_cuStreamSynchronize_v2000 = CUresult (*)(CUstream stream);
using PFN_cuEventCreate_v2000 = CUresult (*)(CUevent* event, unsigned int flags);
using PFN_cuEventDestroy_v4000 = CUresult (*)(CUevent event);
using PFN_cuEventRecord_v2000 = CUresult (*)(CUevent event, CUstream stream);
using PFN_cuEventSynchronize_v2000 = CUresult (*)(CUevent event);
using PFN_cuEventElapsedTime_v2000 = CUresult (*)(float* milliseconds, CUevent start, CUevent end);
using PFN_cuStreamBeginCapture_v10010 = CUresult (*)(CUstream stream, CUstreamCaptureMode mode);
using PFN_cuStreamEndCapture_v10000 = CUresult (*)(CUstream stream, CUgraph* graph);
// cuGraphInstantiate of CUDA 12's headers is this entry (the 5-argument CUDA 10 form is gone).
using PFN_cuGraphInstantiateWithFlags_v11040 = CUresult (*)(CUgraphExec* exec, CUgraph graph,
                                                            unsigned long long flags);
using PFN_cuGraphLaunch_v10000 = CUresult (*)(CUgraphExec exec, CUstream stream);
using PFN_cuGraphExecDestroy_v10000 = CUresult (*)(CUgraphExec exec);
using PFN_cuGraphDestroy_v10000 = CUresult (*)(CUgraph graph);
using PFN_cuMemcpyDtoD_v3020 = CUresult (*)(CUdeviceptr destination, CUdeviceptr source,
                                            std::size_t bytes);
using PFN_cuMemAllocHost_v3020 = CUresult (*)(void** pointer, std::size_t bytes);
using PFN_cuMemFreeHost_v2000 = CUresult (*)(void* pointer);

struct StreamTable {
  PFN_cuStreamCreate_v2000 cuStreamCreate = nullptr;
  PFN_cuStreamDestroy_v4000 cuStreamDestroy = nullptr;  // cuStreamDestroy_v2
  PFN_cuStreamSynchronize_v2000 cuStreamSynchronize = nullptr;
  PFN_cuEventCreate_v2000 cuEventCreate = nullptr;
  PFN_cuEventDestroy_v4000 cuEventDestroy = nullptr;  // cuEventDestroy_v2
  PFN_cuEventRecord_v2000 cuEventRecord = nullptr;
  PFN_cuEventSynchronize_v2000 cuEventSynchronize = nullptr;
  PFN_cuEventElapsedTime_v2000 cuEventElapsedTime = nullptr;
  PFN_cuStreamBeginCapture_v10010 cuStreamBeginCapture = nullptr;  // cuStreamBeginCapture_v2
  PFN_cuStreamEndCapture_v10000 cuStreamEndCapture = nullptr;
  PFN_cuGraphInstantiateWithFlags_v11040 cuGraphInstantiateWithFlags = nullptr;
  PFN_cuGraphLaunch_v10000 cuGraphLaunch = nullptr;
  PFN_cuGraphExecDestroy_v10000 cuGraphExecDestroy = nullptr;
  PFN_cuGraphDestroy_v10000 cuGraphDestroy = nullptr;
  PFN_cuMemcpyDtoD_v3020 cuMemcpyDtoD = nullptr;      // cuMemcpyDtoD_v2
  PFN_cuMemAllocHost_v3020 cuMemAllocHost = nullptr;  // cuMemAllocHost_v2
  PFN_cuMemFreeHost_v2000 cuMemFreeHost = nullptr;
};

// cuGetProcAddress in its CUDA 12 form (a CUDA 11 driver's is adapted to it).
using GetProcAddress =
    std::function<CUresult(const char* symbol, void** pfn, int version, cuuint64_t flags,
                           CUdriverProcAddressQueryResult* status)>;

// Resolves every entry of the table through `get`, each by its base name and the CUDA
// version of its typedef, with CU_GET_PROC_ADDRESS_DEFAULT. nullopt, with `why` naming the
// first entry that failed and how, when one is missing.
std::optional<DriverTable> resolve_driver(const GetProcAddress& get, std::string& why);

// Resolves the table's memory set entries (cuMemsetD8, cuMemsetD32, cuMemsetD2D32) through `get` as
// resolve_driver resolves the others; false with `why` when one is missing.
bool resolve_memset(const GetProcAddress& get, DriverTable& table, std::string& why);

// Resolves every entry of the stream table as resolve_driver does the driver table's.
std::optional<StreamTable> resolve_streams(const GetProcAddress& get, std::string& why);
// The first entry of `streams` that is not set, or nullptr when all are.
const char* missing_stream_entry(const StreamTable& streams);

// dlopen(library) and its cuGetProcAddress (a CUDA 11 driver's adapted to the CUDA 12 form).
// The library stays loaded for the process's life. nullopt with `why` when it does not load
// or has no cuGetProcAddress. load_driver is this on "libcuda.so.1", then resolve_driver.
std::optional<GetProcAddress> open_driver_library(const std::string& library, std::string& why);

// dlopen("libcuda.so.1") (kept loaded for the process's life), then resolve_driver and
// resolve_memset through the driver's cuGetProcAddress. nullopt with `why` when there is no driver,
// when it is too old to have cuGetProcAddress, or when an entry is missing.
std::optional<DriverTable> load_driver(std::string& why);

// A failed driver call: the message names the call and the driver's error string, e.g.
// "cuMemAlloc failed: out of memory (CUDA error 2)".
class CudaError : public std::runtime_error {
 public:
  CudaError(std::string call, CUresult result, const std::string& message)
      : std::runtime_error(message), call_(std::move(call)), result_(result) {}
  const std::string& call() const { return call_; }
  CUresult result() const { return result_; }

 private:
  std::string call_;
  CUresult result_;
};

// An array with a copy on each side. host_dirty: the host copy is newer (the device's must
// be refreshed before a kernel reads it); device_dirty: the device copy is newer (the host's
// must be refreshed before the host reads it). Both at once means two writers raced, which
// to_device and to_host refuse.
struct DeviceArray {
  void* host = nullptr;  // may be null for device-only scratch
  CUdeviceptr device = 0;
  std::size_t bytes = 0;
  bool host_dirty = false;
  bool device_dirty = false;
};

struct Dim3 {
  unsigned int x = 1, y = 1, z = 1;
};

// One kernel argument, by value: cuLaunchKernel's kernelParams holds a pointer to each
// argument's value, read as the kernel's parameter type (a device pointer is a CUdeviceptr).
class KernelArg {
 public:
  template <class T>
  static KernelArg of(T value) {
    static_assert(std::is_trivially_copyable_v<T> && sizeof(T) <= 8,
                  "a kernel argument is a scalar or a device pointer");
    KernelArg a;
    std::memcpy(a.bytes_, &value, sizeof(T));
    a.size_ = sizeof(T);
    return a;
  }
  static KernelArg pointer(const DeviceArray& array) { return of(array.device); }
  // The value's address, for kernelParams; valid while this KernelArg lives.
  const void* address() const { return bytes_; }
  std::size_t size() const { return size_; }

 private:
  alignas(8) unsigned char bytes_[8] = {};
  std::size_t size_ = 0;
};

// A GPU through the driver table: its primary context, made current on the opening thread
// (call make_current() before using the Device from another thread). Every driver call is
// checked; a failure throws CudaError. Modules loaded are unloaded, and the primary context
// released, when the Device goes.
class Device {
 public:
  // Throws std::invalid_argument when an entry of `driver` is not set.
  explicit Device(const DriverTable& driver);
  ~Device();
  Device(const Device&) = delete;
  Device& operator=(const Device&) = delete;

  // cuInit, cuDeviceGet, the primary context retained and made current; then the device's
  // name, compute capability, multiprocessors and memory.
  void open(int ordinal = 0);
  bool is_open() const { return context_ != nullptr; }
  void make_current();

  const std::string& name() const { return name_; }
  int compute_major() const { return compute_major_; }
  int compute_minor() const { return compute_minor_; }
  int multiprocessors() const { return multiprocessors_; }
  std::size_t total_memory() const { return total_memory_; }

  // Device memory for `bytes` mirroring `host` (null for device-only scratch). With a host
  // side, host_dirty starts set: the device copy holds nothing yet. Zero bytes allocate
  // nothing (device stays 0) and copy nothing.
  DeviceArray alloc(void* host, std::size_t bytes);
  void free(DeviceArray& array);
  // Copies host to device only when the host side is dirty; clears host_dirty.
  void to_device(DeviceArray& array);
  // Copies device to host only when the device side is dirty; clears device_dirty.
  void to_host(DeviceArray& array);
  // Sets the device copy's bytes to zero (cuMemsetD32 where the size is a whole number of
  // words, else cuMemsetD8), for an array whose host copy is all zeros: clears host_dirty
  // as a copy would. Throws std::logic_error when the table has no memory set entries.
  void zero(DeviceArray& array);
  // Sets every double of the device copy to -0.0 (the bits 0x8000000000000000), for an array
  // of doubles whose host copy is all -0.0 (a deferred plan's deferred blocks): clears
  // host_dirty as a copy would. Throws std::logic_error when the size is not a whole number
  // of doubles or the table has no cuMemsetD32 and cuMemsetD2D32.
  void fill_negative_zero(DeviceArray& array);

  // A PTX module; a PTX the driver rejects throws with the driver's JIT error log.
  CUmodule load_module(const std::string& ptx);
  void unload_module(CUmodule module);
  CUfunction function(CUmodule module, const std::string& name);
  // Launches on `stream` (the legacy default stream when null); returns without waiting (see
  // synchronize).
  void launch(CUfunction function, Dim3 grid, Dim3 block, std::span<const KernelArg> args,
              unsigned int shared_bytes = 0, CUstream stream = nullptr);
  void synchronize();

  // Throws CudaError when `result` is not CUDA_SUCCESS; `what` (may be empty) says what the
  // call was for, e.g. "of 1024 bytes".
  void check(CUresult result, const char* call, const std::string& what = "") const;

 private:
  void require_open(const char* what) const;

  DriverTable driver_;
  CUdevice device_ = 0;
  CUcontext context_ = nullptr;
  std::vector<CUmodule> modules_;
  std::string name_;
  int compute_major_ = 0, compute_minor_ = 0, multiprocessors_ = 0;
  std::size_t total_memory_ = 0;
};

// The message of a failed call `call` returning `result`, with the driver's error string
// where cuGetErrorString gives one.
std::string error_message(const DriverTable& driver, const char* call, CUresult result,
                          const std::string& what = "");
// The first entry of `driver` that is not set, or nullptr when all are.
const char* missing_entry(const DriverTable& driver);

// "" when device `ordinal` opens through `driver`, else why not.
std::string device_unavailable_reason(const DriverTable& driver, int ordinal = 0);
// "" when this machine's driver opens a GPU, else why not (no driver, a driver too old, no
// device): what running on the GPU says when it cannot.
std::string gpu_unavailable_reason();

}  // namespace simit::jit::cuda
