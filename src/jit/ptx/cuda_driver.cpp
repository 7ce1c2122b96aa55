// The CUDA driver loaded at run time (dlopen + cuGetProcAddress) and the Device over its
// table: primary context, memory with a dirty flag per side, modules, launches.
#include "jit/ptx/cuda_driver.h"

#include <dlfcn.h>

#include <utility>

namespace simit::jit::cuda {
namespace {

// Every entry of the table with its base name and the CUDA version of its ABI (the vNNNN of
// its cudaTypedefs.h typedef). Table is DriverTable or const DriverTable.
template <class Table, class Visit>
void for_each_entry(Table& t, Visit&& visit) {
  visit("cuInit", 2000, t.cuInit);
  visit("cuDriverGetVersion", 2020, t.cuDriverGetVersion);
  visit("cuGetErrorString", 6000, t.cuGetErrorString);
  visit("cuDeviceGet", 2000, t.cuDeviceGet);
  visit("cuDeviceGetCount", 2000, t.cuDeviceGetCount);
  visit("cuDeviceGetName", 2000, t.cuDeviceGetName);
  visit("cuDeviceGetAttribute", 2000, t.cuDeviceGetAttribute);
  visit("cuDeviceTotalMem", 3020, t.cuDeviceTotalMem);
  visit("cuDevicePrimaryCtxRetain", 7000, t.cuDevicePrimaryCtxRetain);
  visit("cuDevicePrimaryCtxRelease", 11000, t.cuDevicePrimaryCtxRelease);
  visit("cuCtxSetCurrent", 4000, t.cuCtxSetCurrent);
  visit("cuCtxSynchronize", 2000, t.cuCtxSynchronize);
  visit("cuModuleLoadDataEx", 2010, t.cuModuleLoadDataEx);
  visit("cuModuleUnload", 2000, t.cuModuleUnload);
  visit("cuModuleGetFunction", 2000, t.cuModuleGetFunction);
  visit("cuMemAlloc", 3020, t.cuMemAlloc);
  visit("cuMemFree", 3020, t.cuMemFree);
  visit("cuMemcpyHtoD", 3020, t.cuMemcpyHtoD);
  visit("cuMemcpyDtoH", 3020, t.cuMemcpyDtoH);
  visit("cuLaunchKernel", 4000, t.cuLaunchKernel);
}

// 3020 -> "3.2" (the driver API's encoding: 1000 * major + 10 * minor).
std::string cuda_version_text(int version) {
  return std::to_string(version / 1000) + "." + std::to_string(version % 1000 / 10);
}

}  // namespace

namespace {

// The stream table's entries, as for_each_entry lists the driver table's.
template <class Table, class Visit>
void for_each_stream_entry(Table& t, Visit&& visit) {
  visit("cuStreamCreate", 2000, t.cuStreamCreate);
  visit("cuStreamDestroy", 4000, t.cuStreamDestroy);
  visit("cuStreamSynchronize", 2000, t.cuStreamSynchronize);
  visit("cuEventCreate", 2000, t.cuEventCreate);
  visit("cuEventDestroy", 4000, t.cuEventDestroy);
  visit("cuEventRecord", 2000, t.cuEventRecord);
  visit("cuEventSynchronize", 2000, t.cuEventSynchronize);
  visit("cuEventElapsedTime", 2000, t.cuEventElapsedTime);
  visit("cuStreamBeginCapture", 10010, t.cuStreamBeginCapture);
  visit("cuStreamEndCapture", 10000, t.cuStreamEndCapture);
  visit("cuGraphInstantiateWithFlags", 11040, t.cuGraphInstantiateWithFlags);
  visit("cuGraphLaunch", 10000, t.cuGraphLaunch);
  visit("cuGraphExecDestroy", 10000, t.cuGraphExecDestroy);
  visit("cuGraphDestroy", 10000, t.cuGraphDestroy);
  visit("cuMemcpyDtoD", 3020, t.cuMemcpyDtoD);
  visit("cuMemAllocHost", 3020, t.cuMemAllocHost);
  visit("cuMemFreeHost", 2000, t.cuMemFreeHost);
}

// The first entry `for_each` lists that is not set, or nullptr.
template <class Table, class ForEach>
const char* first_missing(const Table& table, ForEach for_each) {
  const char* missing = nullptr;
  for_each(table, [&](const char* name, int, const auto& slot) {
    if (!missing && !slot) missing = name;
  });
  return missing;
}

// Every entry `for_each` lists, through `get`, by its base name and the CUDA version of its
// typedef; nullopt with `why` naming the first that failed and how.
template <class Table, class ForEach>
std::optional<Table> resolve_table(const GetProcAddress& get, std::string& why, ForEach for_each) {
  Table table;
  bool ok = true;
  for_each(table, [&](const char* name, int version, auto& slot) {
    if (!ok) return;
    void* pfn = nullptr;
    CUdriverProcAddressQueryResult status = CU_GET_PROC_ADDRESS_SUCCESS;
    const CUresult r = get(name, &pfn, version, CU_GET_PROC_ADDRESS_DEFAULT, &status);
    const std::string entry =
        std::string(name) + " (the CUDA " + cuda_version_text(version) + " ABI)";
    if (r != CUDA_SUCCESS) {
      why = "cuGetProcAddress failed for " + entry + ": CUDA error " + std::to_string(r);
      ok = false;
    } else if (!pfn || status != CU_GET_PROC_ADDRESS_SUCCESS) {
      why = "driver entry " + entry + " missing: " +
            (status == CU_GET_PROC_ADDRESS_VERSION_NOT_SUFFICIENT
                 ? "the driver has only an older version"
                 : "the driver does not have it");
      ok = false;
    } else {
      // A function pointer from void* (POSIX guarantees the round trip, as for dlsym).
      slot = reinterpret_cast<std::remove_reference_t<decltype(slot)>>(pfn);
    }
  });
  if (!ok) return std::nullopt;
  return table;
}

// The memory set entries: resolved apart from the others (DriverTable's comment says why).
template <class Table, class Visit>
void for_each_memset_entry(Table& t, Visit&& visit) {
  visit("cuMemsetD8", 3020, t.cuMemsetD8);
  visit("cuMemsetD32", 3020, t.cuMemsetD32);
  visit("cuMemsetD2D32", 3020, t.cuMemsetD2D32);
}

const auto driver_entries = [](auto& table, auto&& visit) { for_each_entry(table, visit); };
const auto memset_entries = [](auto& table, auto&& visit) { for_each_memset_entry(table, visit); };
const auto stream_entries = [](auto& table, auto&& visit) { for_each_stream_entry(table, visit); };

// dlopen(library) and its cuGetProcAddress; `handle` is the library's on success (null
// otherwise, the library closed again).
std::optional<GetProcAddress> open_library(const std::string& library, std::string& why,
                                           void*& handle) {
  handle = dlopen(library.c_str(), RTLD_NOW | RTLD_LOCAL);
  void* const lib = handle;
  if (!lib) {
    const char* error = dlerror();
    const std::string detail = error ? error : "dlopen failed";
    if (detail.find("No such file") != std::string::npos)
      why = library + " not found" +
            (library == "libcuda.so.1" ? ": no NVIDIA driver on this machine" : "");
    else
      why = library + " could not be loaded: " + detail;
    return std::nullopt;
  }
  GetProcAddress get;
  if (void* v2 = dlsym(lib, "cuGetProcAddress_v2")) {
    get = reinterpret_cast<PFN_cuGetProcAddress_v12000>(v2);
  } else if (void* v1 = dlsym(lib, "cuGetProcAddress")) {
    // A CUDA 11 driver: no status out; a null pointer means not found.
    const auto legacy = reinterpret_cast<PFN_cuGetProcAddress_v11030>(v1);
    get = [legacy](const char* symbol, void** pfn, int version, cuuint64_t flags,
                   CUdriverProcAddressQueryResult* status) {
      const CUresult r = legacy(symbol, pfn, version, flags);
      if (status)
        *status = r == CUDA_SUCCESS && *pfn ? CU_GET_PROC_ADDRESS_SUCCESS
                                            : CU_GET_PROC_ADDRESS_SYMBOL_NOT_FOUND;
      return r;
    };
  } else {
    why = "cuGetProcAddress missing: driver too old (CUDA 11.3 or newer is needed)";
    int version = 0;
    if (auto driver_version =
            reinterpret_cast<PFN_cuDriverGetVersion_v2020>(dlsym(lib, "cuDriverGetVersion"));
        driver_version && driver_version(&version) == CUDA_SUCCESS)
      why += "; this driver supports CUDA " + cuda_version_text(version);
    dlclose(lib);
    handle = nullptr;
    return std::nullopt;
  }
  return get;
}

}  // namespace

const char* missing_entry(const DriverTable& driver) {
  return first_missing(driver, driver_entries);
}

const char* missing_stream_entry(const StreamTable& streams) {
  return first_missing(streams, stream_entries);
}

std::optional<DriverTable> resolve_driver(const GetProcAddress& get, std::string& why) {
  return resolve_table<DriverTable>(get, why, driver_entries);
}

bool resolve_memset(const GetProcAddress& get, DriverTable& table, std::string& why) {
  const auto found = resolve_table<DriverTable>(get, why, memset_entries);
  if (!found) return false;
  table.cuMemsetD8 = found->cuMemsetD8;
  table.cuMemsetD32 = found->cuMemsetD32;
  table.cuMemsetD2D32 = found->cuMemsetD2D32;
  return true;
}

std::optional<StreamTable> resolve_streams(const GetProcAddress& get, std::string& why) {
  return resolve_table<StreamTable>(get, why, stream_entries);
}

std::optional<GetProcAddress> open_driver_library(const std::string& library, std::string& why) {
  void* handle = nullptr;
  return open_library(library, why, handle);
}

std::optional<DriverTable> load_driver(std::string& why) {
  // libcuda.so.1 is what the driver package installs; the unversioned libcuda.so may be the
  // toolkit's link-time stub, which only fails every call.
  void* lib = nullptr;
  const auto get = open_library("libcuda.so.1", why, lib);
  if (!get) return std::nullopt;
  auto table = resolve_driver(*get, why);
  if (table && !resolve_memset(*get, *table, why)) table.reset();
  // On success the library stays loaded for the process's life: the table points into it.
  if (!table) dlclose(lib);
  return table;
}

std::string error_message(const DriverTable& driver, const char* call, CUresult result,
                          const std::string& what) {
  const char* text = nullptr;
  if (!driver.cuGetErrorString || driver.cuGetErrorString(result, &text) != CUDA_SUCCESS || !text)
    text = "error not known to the driver";
  std::string message = call;
  if (!what.empty()) message += " " + what;
  return message + " failed: " + text + " (CUDA error " + std::to_string(result) + ")";
}

// ---- Device

Device::Device(const DriverTable& driver) : driver_(driver) {
  if (const char* missing = missing_entry(driver))
    throw std::invalid_argument(std::string("CUDA driver table without ") + missing);
}

Device::~Device() {
  if (!context_) return;
  // Errors are dropped here: a destructor cannot report them, and releasing the primary
  // context frees whatever was left on the device anyway.
  driver_.cuCtxSetCurrent(context_);
  for (CUmodule m : modules_) driver_.cuModuleUnload(m);
  driver_.cuDevicePrimaryCtxRelease(device_);
}

void Device::check(CUresult result, const char* call, const std::string& what) const {
  if (result != CUDA_SUCCESS)
    throw CudaError(call, result, error_message(driver_, call, result, what));
}

void Device::require_open(const char* what) const {
  if (!context_) throw std::logic_error(std::string(what) + " on a CUDA device not opened");
}

void Device::open(int ordinal) {
  if (context_) throw std::logic_error("CUDA device opened twice");
  check(driver_.cuInit(0), "cuInit");
  int count = 0;
  check(driver_.cuDeviceGetCount(&count), "cuDeviceGetCount");
  if (ordinal < 0 || ordinal >= count)
    throw CudaError("cuDeviceGet", CUDA_ERROR_INVALID_DEVICE,
                    "cuDeviceGet failed: no CUDA device " + std::to_string(ordinal) +
                        " (the driver found " + std::to_string(count) + ")");
  CUdevice device = 0;
  check(driver_.cuDeviceGet(&device, ordinal), "cuDeviceGet");
  CUcontext context = nullptr;
  check(driver_.cuDevicePrimaryCtxRetain(&context, device), "cuDevicePrimaryCtxRetain");
  // Retained: from here the destructor releases it, whatever fails below.
  device_ = device;
  context_ = context;
  check(driver_.cuCtxSetCurrent(context_), "cuCtxSetCurrent");

  char name[256] = {};
  check(driver_.cuDeviceGetName(name, sizeof name, device_), "cuDeviceGetName");
  name[sizeof name - 1] = '\0';
  name_ = name;
  check(driver_.cuDeviceGetAttribute(&compute_major_, CU_DEVICE_ATTRIBUTE_COMPUTE_CAPABILITY_MAJOR,
                                     device_),
        "cuDeviceGetAttribute", "(compute capability major)");
  check(driver_.cuDeviceGetAttribute(&compute_minor_, CU_DEVICE_ATTRIBUTE_COMPUTE_CAPABILITY_MINOR,
                                     device_),
        "cuDeviceGetAttribute", "(compute capability minor)");
  check(driver_.cuDeviceGetAttribute(&multiprocessors_, CU_DEVICE_ATTRIBUTE_MULTIPROCESSOR_COUNT,
                                     device_),
        "cuDeviceGetAttribute", "(multiprocessor count)");
  check(driver_.cuDeviceTotalMem(&total_memory_, device_), "cuDeviceTotalMem");
}

void Device::make_current() {
  require_open("make_current");
  check(driver_.cuCtxSetCurrent(context_), "cuCtxSetCurrent");
}

DeviceArray Device::alloc(void* host, std::size_t bytes) {
  require_open("alloc");
  DeviceArray array;
  array.host = host;
  array.bytes = bytes;
  if (bytes == 0) return array;  // cuMemAlloc refuses 0 bytes; there is nothing to hold
  check(driver_.cuMemAlloc(&array.device, bytes), "cuMemAlloc",
        "of " + std::to_string(bytes) + " bytes");
  array.host_dirty = host != nullptr;
  return array;
}

void Device::free(DeviceArray& array) {
  if (array.device != 0) {
    require_open("free");
    check(driver_.cuMemFree(array.device), "cuMemFree");
  }
  array.device = 0;
  array.host_dirty = array.device_dirty = false;
}

namespace {
void check_single_writer(const DeviceArray& array) {
  if (array.host_dirty && array.device_dirty)
    throw std::logic_error(
        "array written on both the host and the device since they last agreed (" +
        std::to_string(array.bytes) + " bytes)");
}
}  // namespace

void Device::to_device(DeviceArray& array) {
  check_single_writer(array);
  if (!array.host_dirty) return;
  if (array.bytes != 0) {
    require_open("to_device");
    if (!array.host) throw std::logic_error("to_device of an array without a host copy");
    check(driver_.cuMemcpyHtoD(array.device, array.host, array.bytes), "cuMemcpyHtoD",
          "of " + std::to_string(array.bytes) + " bytes");
  }
  array.host_dirty = false;
}

void Device::to_host(DeviceArray& array) {
  check_single_writer(array);
  if (!array.device_dirty) return;
  if (array.bytes != 0) {
    require_open("to_host");
    if (!array.host) throw std::logic_error("to_host of a device-only array");
    check(driver_.cuMemcpyDtoH(array.host, array.device, array.bytes), "cuMemcpyDtoH",
          "of " + std::to_string(array.bytes) + " bytes");
  }
  array.device_dirty = false;
}

void Device::zero(DeviceArray& array) {
  check_single_writer(array);
  if (array.bytes != 0) {
    require_open("zero");
    if (!driver_.cuMemsetD8 || !driver_.cuMemsetD32)
      throw std::logic_error("zero on a CUDA driver table without cuMemsetD8 and cuMemsetD32");
    // cuMemAlloc's memory is aligned for any type: words wherever the size allows.
    if (array.bytes % 4 == 0)
      check(driver_.cuMemsetD32(array.device, 0u, array.bytes / 4), "cuMemsetD32",
            "of " + std::to_string(array.bytes) + " bytes");
    else
      check(driver_.cuMemsetD8(array.device, 0, array.bytes), "cuMemsetD8",
            "of " + std::to_string(array.bytes) + " bytes");
  }
  array.host_dirty = false;
}

// Two memory sets rather than a fill kernel: no module to load, no launch to configure, and
// the driver's own set kernels. First every word zero (cuMemsetD32), then the high word of
// each double (at byte 4 of its 8: both the device and the host are little-endian) set to
// 0x80000000, the sign bit, by a 2D set of one word per row with a pitch of 8 bytes.
void Device::fill_negative_zero(DeviceArray& array) {
  check_single_writer(array);
  if (array.bytes != 0) {
    require_open("fill_negative_zero");
    if (array.bytes % sizeof(double) != 0)
      throw std::logic_error("fill_negative_zero of " + std::to_string(array.bytes) +
                             " bytes: not a whole number of doubles");
    if (!driver_.cuMemsetD32 || !driver_.cuMemsetD2D32)
      throw std::logic_error(
          "fill_negative_zero on a CUDA driver table without cuMemsetD32 and cuMemsetD2D32");
    const std::string what = "of " + std::to_string(array.bytes) + " bytes";
    check(driver_.cuMemsetD32(array.device, 0u, array.bytes / 4), "cuMemsetD32", what);
    check(driver_.cuMemsetD2D32(array.device + 4, sizeof(double), 0x80000000u, 1,
                                array.bytes / sizeof(double)),
          "cuMemsetD2D32", what);
  }
  array.host_dirty = false;
}

CUmodule Device::load_module(const std::string& ptx) {
  require_open("load_module");
  // The driver's JIT writes why a PTX does not load into this buffer (NUL-terminated).
  std::string log(16384, '\0');
  CUjit_option options[] = {CU_JIT_ERROR_LOG_BUFFER, CU_JIT_ERROR_LOG_BUFFER_SIZE_BYTES};
  void* values[] = {log.data(), reinterpret_cast<void*>(static_cast<std::uintptr_t>(log.size()))};
  CUmodule module = nullptr;
  const CUresult r = driver_.cuModuleLoadDataEx(&module, ptx.c_str(), 2, options, values);
  if (r != CUDA_SUCCESS) {
    log.resize(log.find('\0') == std::string::npos ? log.size() : log.find('\0'));
    while (!log.empty() && (log.back() == '\n' || log.back() == ' ')) log.pop_back();
    std::string message = error_message(driver_, "cuModuleLoadDataEx", r, "of a PTX module");
    if (!log.empty()) message += ": " + log;
    throw CudaError("cuModuleLoadDataEx", r, message);
  }
  modules_.push_back(module);
  return module;
}

void Device::unload_module(CUmodule module) {
  require_open("unload_module");
  std::erase(modules_, module);
  check(driver_.cuModuleUnload(module), "cuModuleUnload");
}

CUfunction Device::function(CUmodule module, const std::string& name) {
  require_open("function");
  CUfunction function = nullptr;
  check(driver_.cuModuleGetFunction(&function, module, name.c_str()), "cuModuleGetFunction",
        "of '" + name + "'");
  return function;
}

void Device::launch(CUfunction function, Dim3 grid, Dim3 block, std::span<const KernelArg> args,
                    unsigned int shared_bytes, CUstream stream) {
  require_open("launch");
  // kernelParams: one pointer per parameter, to a value of the parameter's type; the driver
  // copies the values before cuLaunchKernel returns, so `args` need not outlive the launch.
  std::vector<void*> params;
  params.reserve(args.size());
  for (const KernelArg& a : args) params.push_back(const_cast<void*>(a.address()));
  check(driver_.cuLaunchKernel(function, grid.x, grid.y, grid.z, block.x, block.y, block.z,
                               shared_bytes, stream, params.empty() ? nullptr : params.data(),
                               nullptr),
        "cuLaunchKernel");
}

void Device::synchronize() {
  require_open("synchronize");
  check(driver_.cuCtxSynchronize(), "cuCtxSynchronize");
}

// ---- Availability

std::string device_unavailable_reason(const DriverTable& driver, int ordinal) {
  try {
    Device device(driver);
    device.open(ordinal);
    return "";
  } catch (const CudaError& e) {
    return std::string("no usable CUDA device: ") + e.what();
  } catch (const std::exception& e) {
    return e.what();
  }
}

std::string gpu_unavailable_reason() {
  std::string why;
  const auto driver = load_driver(why);
  if (!driver) return why;
  return device_unavailable_reason(*driver, 0);
}

}  // namespace simit::jit::cuda
