// The CUDA driver layer (jit/ptx/cuda_driver.h) against a fake driver table, with no GPU:
// entry points resolved by name and ABI version, the open sequence, kernel argument
// marshalling, residency (copies only when dirty, in the right direction and size), errors
// naming the call and the driver's error string; and load_driver on this machine.
#include <dlfcn.h>
#include <gtest/gtest.h>

#include <cstdio>
#include <cstring>
#include <iostream>
#include <map>
#include <string>
#include <vector>

#include "jit/ptx/cuda_driver.h"

namespace simit::jit::cuda {
namespace {

// The fake driver's state: one device, a memory map, the calls made in order, and a result
// that a named call returns instead of succeeding. The table's entries are captureless
// lambdas (plain function pointers, as the driver's are), so the state is a global.
struct FakeDriver {
  std::vector<std::string> calls;
  std::map<CUdeviceptr, std::vector<unsigned char>> memory;
  CUdeviceptr next_pointer = 0x10000;
  std::map<std::string, CUresult> fail;  // call -> the result it returns
  bool initialised = false;
  CUcontext current = nullptr;
  int retained = 0;
  std::vector<CUmodule> loaded;
  std::string jit_log;  // written to the error log buffer when cuModuleLoadDataEx fails
  std::string last_ptx;
  // The last launch: its dimensions and the kernelParams pointers as given.
  unsigned int grid[3] = {}, block[3] = {}, shared = 0;
  CUstream stream = reinterpret_cast<CUstream>(1);
  void** params = nullptr;
  void** extra = reinterpret_cast<void**>(1);
  std::vector<unsigned char> params_seen;  // the values behind params, read during the call
  std::vector<std::size_t> param_sizes;    // how many bytes of each parameter to read

  CUresult call(const std::string& record, const std::string& name) {
    calls.push_back(record);
    const auto it = fail.find(name);
    return it == fail.end() ? CUDA_SUCCESS : it->second;
  }
};
FakeDriver* fake = nullptr;

constexpr CUdevice kDevice = 7;
CUcontext const kContext = reinterpret_cast<CUcontext>(0xC0);

std::string hex(unsigned long long v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "0x%llx", v);
  return buf;
}

DriverTable fake_table() {
  DriverTable t;
  t.cuInit = [](unsigned int flags) {
    const CUresult r = fake->call("cuInit " + std::to_string(flags), "cuInit");
    if (r == CUDA_SUCCESS) fake->initialised = true;
    return r;
  };
  t.cuDriverGetVersion = [](int* v) {
    *v = 13000;
    return fake->call("cuDriverGetVersion", "cuDriverGetVersion");
  };
  t.cuGetErrorString = [](CUresult r, const char** s) {
    // Not recorded: only error paths call it.
    switch (r) {
      case CUDA_ERROR_OUT_OF_MEMORY: *s = "out of memory"; return CUDA_SUCCESS;
      case CUDA_ERROR_NO_DEVICE: *s = "no CUDA-capable device is detected"; return CUDA_SUCCESS;
      case CUDA_ERROR_INVALID_PTX: *s = "a PTX JIT compilation failed"; return CUDA_SUCCESS;
      case CUDA_ERROR_NOT_FOUND: *s = "named symbol not found"; return CUDA_SUCCESS;
      default: *s = nullptr; return CUDA_ERROR_INVALID_VALUE;
    }
  };
  t.cuDeviceGetCount = [](int* n) {
    *n = 1;
    return fake->call("cuDeviceGetCount", "cuDeviceGetCount");
  };
  t.cuDeviceGet = [](CUdevice* d, int ordinal) {
    if (!fake->initialised) return CUDA_ERROR_NOT_INITIALIZED;
    *d = kDevice;
    return fake->call("cuDeviceGet " + std::to_string(ordinal), "cuDeviceGet");
  };
  t.cuDeviceGetName = [](char* name, int len, CUdevice d) {
    std::snprintf(name, static_cast<std::size_t>(len), "Fake H200");
    return fake->call("cuDeviceGetName " + std::to_string(len) + " " + std::to_string(d),
                      "cuDeviceGetName");
  };
  t.cuDeviceGetAttribute = [](int* v, CUdevice_attribute a, CUdevice d) {
    *v = a == CU_DEVICE_ATTRIBUTE_COMPUTE_CAPABILITY_MAJOR   ? 9
         : a == CU_DEVICE_ATTRIBUTE_COMPUTE_CAPABILITY_MINOR ? 0
         : a == CU_DEVICE_ATTRIBUTE_MULTIPROCESSOR_COUNT     ? 132
                                                             : -1;
    return fake->call("cuDeviceGetAttribute " + std::to_string(a) + " " + std::to_string(d),
                      "cuDeviceGetAttribute");
  };
  t.cuDeviceTotalMem = [](std::size_t* bytes, CUdevice d) {
    *bytes = std::size_t{150} << 30;
    return fake->call("cuDeviceTotalMem " + std::to_string(d), "cuDeviceTotalMem");
  };
  t.cuDevicePrimaryCtxRetain = [](CUcontext* c, CUdevice d) {
    *c = kContext;
    const CUresult r =
        fake->call("cuDevicePrimaryCtxRetain " + std::to_string(d), "cuDevicePrimaryCtxRetain");
    if (r == CUDA_SUCCESS) ++fake->retained;
    return r;
  };
  t.cuDevicePrimaryCtxRelease = [](CUdevice d) {
    --fake->retained;
    return fake->call("cuDevicePrimaryCtxRelease " + std::to_string(d),
                      "cuDevicePrimaryCtxRelease");
  };
  t.cuCtxSetCurrent = [](CUcontext c) {
    fake->current = c;
    return fake->call("cuCtxSetCurrent " + hex(reinterpret_cast<std::uintptr_t>(c)),
                      "cuCtxSetCurrent");
  };
  t.cuCtxSynchronize = []() { return fake->call("cuCtxSynchronize", "cuCtxSynchronize"); };
  t.cuModuleLoadDataEx = [](CUmodule* m, const void* image, unsigned int n, CUjit_option* opts,
                            void** values) {
    fake->last_ptx = static_cast<const char*>(image);
    const CUresult r = fake->call("cuModuleLoadDataEx", "cuModuleLoadDataEx");
    if (r != CUDA_SUCCESS) {
      // Like the driver: the log into the buffer the options name, within its size.
      char* buffer = nullptr;
      std::size_t size = 0;
      for (unsigned int i = 0; i < n; ++i) {
        if (opts[i] == CU_JIT_ERROR_LOG_BUFFER) buffer = static_cast<char*>(values[i]);
        if (opts[i] == CU_JIT_ERROR_LOG_BUFFER_SIZE_BYTES)
          size = reinterpret_cast<std::uintptr_t>(values[i]);
      }
      if (buffer && size) std::snprintf(buffer, size, "%s", fake->jit_log.c_str());
      return r;
    }
    *m = reinterpret_cast<CUmodule>(0x100 + fake->loaded.size());
    fake->loaded.push_back(*m);
    return r;
  };
  t.cuModuleUnload = [](CUmodule m) {
    std::erase(fake->loaded, m);
    return fake->call("cuModuleUnload " + hex(reinterpret_cast<std::uintptr_t>(m)),
                      "cuModuleUnload");
  };
  t.cuModuleGetFunction = [](CUfunction* f, CUmodule m, const char* name) {
    *f = reinterpret_cast<CUfunction>(0xF00);
    return fake->call(
        "cuModuleGetFunction " + hex(reinterpret_cast<std::uintptr_t>(m)) + " " + name,
        "cuModuleGetFunction");
  };
  t.cuMemAlloc = [](CUdeviceptr* p, std::size_t bytes) {
    const CUresult r = fake->call("cuMemAlloc " + std::to_string(bytes), "cuMemAlloc");
    if (r != CUDA_SUCCESS) return r;
    *p = fake->next_pointer;
    fake->next_pointer += 0x1000;
    fake->memory[*p].assign(bytes, 0xEE);
    return r;
  };
  t.cuMemFree = [](CUdeviceptr p) {
    if (!fake->memory.erase(p)) return CUDA_ERROR_INVALID_VALUE;
    return fake->call("cuMemFree " + hex(p), "cuMemFree");
  };
  t.cuMemcpyHtoD = [](CUdeviceptr dst, const void* src, std::size_t bytes) {
    auto& m = fake->memory.at(dst);
    if (bytes > m.size()) return CUDA_ERROR_INVALID_VALUE;
    std::memcpy(m.data(), src, bytes);
    return fake->call("cuMemcpyHtoD " + hex(dst) + " " + std::to_string(bytes), "cuMemcpyHtoD");
  };
  t.cuMemcpyDtoH = [](void* dst, CUdeviceptr src, std::size_t bytes) {
    const auto& m = fake->memory.at(src);
    if (bytes > m.size()) return CUDA_ERROR_INVALID_VALUE;
    std::memcpy(dst, m.data(), bytes);
    return fake->call("cuMemcpyDtoH " + hex(src) + " " + std::to_string(bytes), "cuMemcpyDtoH");
  };
  t.cuLaunchKernel = [](CUfunction f, unsigned int gx, unsigned int gy, unsigned int gz,
                        unsigned int bx, unsigned int by, unsigned int bz, unsigned int shared,
                        CUstream stream, void** params, void** extra) {
    fake->grid[0] = gx, fake->grid[1] = gy, fake->grid[2] = gz;
    fake->block[0] = bx, fake->block[1] = by, fake->block[2] = bz;
    fake->shared = shared;
    fake->stream = stream;
    fake->params = params;
    fake->extra = extra;
    // The kernel reads each parameter's bytes through its pointer, as the driver does.
    fake->params_seen.clear();
    for (std::size_t i = 0; i < fake->param_sizes.size(); ++i) {
      const auto* p = static_cast<const unsigned char*>(params[i]);
      fake->params_seen.insert(fake->params_seen.end(), p, p + fake->param_sizes[i]);
    }
    return fake->call("cuLaunchKernel " + hex(reinterpret_cast<std::uintptr_t>(f)),
                      "cuLaunchKernel");
  };
  return t;
}

class CudaDriver : public ::testing::Test {
 protected:
  void SetUp() override { fake = &state; }
  void TearDown() override { fake = nullptr; }
  FakeDriver state;
};

TEST_F(CudaDriver, OpenRetainsThePrimaryContextAndReadsTheDevice) {
  {
    Device device(fake_table());
    EXPECT_FALSE(device.is_open());
    device.open(0);
    EXPECT_TRUE(device.is_open());
    const std::vector<std::string> expected = {
        "cuInit 0",
        "cuDeviceGetCount",
        "cuDeviceGet 0",
        "cuDevicePrimaryCtxRetain 7",
        "cuCtxSetCurrent 0xc0",
        "cuDeviceGetName 256 7",
        "cuDeviceGetAttribute 75 7",
        "cuDeviceGetAttribute 76 7",
        "cuDeviceGetAttribute 16 7",
        "cuDeviceTotalMem 7",
    };
    EXPECT_EQ(state.calls, expected);
    EXPECT_EQ(state.current, kContext);
    EXPECT_EQ(state.retained, 1);
    EXPECT_EQ(device.name(), "Fake H200");
    EXPECT_EQ(device.compute_major(), 9);
    EXPECT_EQ(device.compute_minor(), 0);
    EXPECT_EQ(device.multiprocessors(), 132);
    EXPECT_EQ(device.total_memory(), std::size_t{161061273600});
    EXPECT_THROW(device.open(0), std::logic_error);
    device.load_module("// ptx");
    state.calls.clear();
  }
  // Gone: its module unloaded, then the primary context released.
  const std::vector<std::string> expected = {"cuCtxSetCurrent 0xc0", "cuModuleUnload 0x100",
                                             "cuDevicePrimaryCtxRelease 7"};
  EXPECT_EQ(state.calls, expected);
  EXPECT_EQ(state.retained, 0);
  EXPECT_TRUE(state.loaded.empty());
}

TEST_F(CudaDriver, OpenOfADeviceThatIsNotThereSaysSo) {
  Device device(fake_table());
  try {
    device.open(1);
    FAIL() << "opened device 1 of 1";
  } catch (const CudaError& e) {
    EXPECT_EQ(e.call(), "cuDeviceGet");
    EXPECT_EQ(e.result(), CUDA_ERROR_INVALID_DEVICE);
    EXPECT_NE(std::string(e.what()).find("no CUDA device 1 (the driver found 1)"),
              std::string::npos)
        << e.what();
  }
  EXPECT_FALSE(device.is_open());
  EXPECT_EQ(state.retained, 0);
}

TEST_F(CudaDriver, UnopenedDeviceAndIncompleteTableAreRefused) {
  Device device(fake_table());
  EXPECT_THROW(device.alloc(nullptr, 8), std::logic_error);
  EXPECT_THROW(device.synchronize(), std::logic_error);
  DriverTable t = fake_table();
  t.cuMemcpyDtoH = nullptr;
  EXPECT_STREQ(missing_entry(t), "cuMemcpyDtoH");
  EXPECT_EQ(missing_entry(fake_table()), nullptr);
  try {
    Device incomplete(t);
    FAIL() << "a table without cuMemcpyDtoH was taken";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "CUDA driver table without cuMemcpyDtoH");
  }
  EXPECT_TRUE(state.calls.empty());
}

TEST_F(CudaDriver, LaunchPassesAPointerToEachArgumentValue) {
  Device device(fake_table());
  device.open();
  std::vector<double> x(4, 1.5);
  DeviceArray a = device.alloc(x.data(), x.size() * sizeof(double));
  const std::vector<KernelArg> args = {KernelArg::pointer(a), KernelArg::of<int32_t>(-5),
                                       KernelArg::of(2.25), KernelArg::of<int64_t>(1LL << 40)};
  EXPECT_EQ(args[0].size(), 8u);
  EXPECT_EQ(args[1].size(), 4u);
  state.param_sizes = {8, 4, 8, 8};
  const CUmodule m = device.load_module(".version 7.8\n.target sm_90\n");
  EXPECT_EQ(state.last_ptx, ".version 7.8\n.target sm_90\n");
  const CUfunction f = device.function(m, "assemble");
  EXPECT_EQ(state.calls.back(), "cuModuleGetFunction 0x100 assemble");
  device.launch(f, Dim3{30, 2, 1}, Dim3{256, 1, 1}, args, 1024);
  EXPECT_EQ(state.calls.back(), "cuLaunchKernel 0xf00");
  EXPECT_EQ(state.grid[0], 30u);
  EXPECT_EQ(state.grid[1], 2u);
  EXPECT_EQ(state.grid[2], 1u);
  EXPECT_EQ(state.block[0], 256u);
  EXPECT_EQ(state.block[1], 1u);
  EXPECT_EQ(state.block[2], 1u);
  EXPECT_EQ(state.shared, 1024u);
  EXPECT_EQ(state.stream, nullptr);  // the legacy default stream
  EXPECT_EQ(state.extra, nullptr);
  // The values the kernel read, laid out by hand: the device pointer, then the scalars.
  std::vector<unsigned char> expected(28);
  const unsigned long long pointer = 0x10000;  // the fake's first allocation
  const int32_t i = -5;
  const double d = 2.25;
  const int64_t l = int64_t{1} << 40;
  std::memcpy(&expected[0], &pointer, 8);
  std::memcpy(&expected[8], &i, 4);
  std::memcpy(&expected[12], &d, 8);
  std::memcpy(&expected[20], &l, 8);
  EXPECT_EQ(state.params_seen, expected);
  // No arguments: kernelParams is null.
  state.param_sizes.clear();
  device.launch(f, Dim3{1, 1, 1}, Dim3{32, 1, 1}, {});
  EXPECT_EQ(state.params, nullptr);
  device.synchronize();
  EXPECT_EQ(state.calls.back(), "cuCtxSynchronize");
  device.free(a);
}

TEST_F(CudaDriver, CopiesOnlyWhatIsDirtyInItsDirection) {
  Device device(fake_table());
  device.open();
  std::vector<double> x = {1.0, 2.0, 3.0};
  DeviceArray a = device.alloc(x.data(), 24);
  EXPECT_EQ(a.device, 0x10000u);
  EXPECT_EQ(a.bytes, 24u);
  EXPECT_EQ(a.host, x.data());
  EXPECT_TRUE(a.host_dirty);  // the device holds nothing yet
  EXPECT_FALSE(a.device_dirty);
  EXPECT_EQ(state.calls.back(), "cuMemAlloc 24");
  const std::size_t before = state.calls.size();

  device.to_host(a);  // the device is not newer: nothing
  EXPECT_EQ(state.calls.size(), before);
  device.to_device(a);
  ASSERT_EQ(state.calls.size(), before + 1);
  EXPECT_EQ(state.calls.back(), "cuMemcpyHtoD 0x10000 24");
  EXPECT_FALSE(a.host_dirty);
  double on_device[3];
  std::memcpy(on_device, state.memory.at(0x10000).data(), 24);
  EXPECT_EQ(on_device[0], 1.0);
  EXPECT_EQ(on_device[2], 3.0);
  device.to_device(a);  // clean: nothing
  EXPECT_EQ(state.calls.size(), before + 1);

  // A kernel writes the device copy.
  const double written[3] = {-1.0, -2.0, -3.0};
  std::memcpy(state.memory.at(0x10000).data(), written, 24);
  a.device_dirty = true;
  device.to_device(a);  // the host is not newer: nothing
  EXPECT_EQ(state.calls.size(), before + 1);
  device.to_host(a);
  ASSERT_EQ(state.calls.size(), before + 2);
  EXPECT_EQ(state.calls.back(), "cuMemcpyDtoH 0x10000 24");
  EXPECT_FALSE(a.device_dirty);
  EXPECT_EQ(x, (std::vector<double>{-1.0, -2.0, -3.0}));
  device.to_host(a);
  EXPECT_EQ(state.calls.size(), before + 2);

  // Written on both sides since they agreed: refused, nothing copied.
  a.host_dirty = a.device_dirty = true;
  EXPECT_THROW(device.to_device(a), std::logic_error);
  EXPECT_THROW(device.to_host(a), std::logic_error);
  EXPECT_EQ(state.calls.size(), before + 2);

  device.free(a);
  EXPECT_EQ(state.calls.back(), "cuMemFree 0x10000");
  EXPECT_EQ(a.device, 0u);
  EXPECT_TRUE(state.memory.empty());
}

TEST_F(CudaDriver, EmptyAndDeviceOnlyArrays) {
  Device device(fake_table());
  device.open();
  const std::size_t before = state.calls.size();
  double x = 0;
  DeviceArray empty = device.alloc(&x, 0);  // cuMemAlloc refuses 0 bytes: not called
  EXPECT_EQ(empty.device, 0u);
  empty.host_dirty = true;
  device.to_device(empty);
  EXPECT_FALSE(empty.host_dirty);
  device.free(empty);
  EXPECT_EQ(state.calls.size(), before);

  DeviceArray scratch = device.alloc(nullptr, 64);
  EXPECT_FALSE(scratch.host_dirty);
  scratch.device_dirty = true;
  EXPECT_THROW(device.to_host(scratch), std::logic_error);
  device.free(scratch);
}

TEST_F(CudaDriver, ErrorsNameTheCallAndTheDriversString) {
  Device device(fake_table());
  device.open();
  state.fail["cuMemAlloc"] = CUDA_ERROR_OUT_OF_MEMORY;
  try {
    device.alloc(nullptr, 1 << 20);
    FAIL() << "cuMemAlloc's failure went unnoticed";
  } catch (const CudaError& e) {
    EXPECT_EQ(e.call(), "cuMemAlloc");
    EXPECT_EQ(e.result(), CUDA_ERROR_OUT_OF_MEMORY);
    EXPECT_STREQ(e.what(), "cuMemAlloc of 1048576 bytes failed: out of memory (CUDA error 2)");
  }
  // A PTX the driver rejects: its JIT log is in the message.
  state.fail["cuModuleLoadDataEx"] = CUDA_ERROR_INVALID_PTX;
  state.jit_log = "ptxas application ptx input, line 3; error   : Unknown symbol 'x'\n";
  try {
    device.load_module("bad");
    FAIL() << "a rejected PTX loaded";
  } catch (const CudaError& e) {
    EXPECT_EQ(e.call(), "cuModuleLoadDataEx");
    EXPECT_STREQ(e.what(),
                 "cuModuleLoadDataEx of a PTX module failed: a PTX JIT compilation failed (CUDA "
                 "error 218): ptxas application ptx input, line 3; error   : Unknown symbol 'x'");
  }
  state.fail["cuModuleGetFunction"] = CUDA_ERROR_NOT_FOUND;
  try {
    device.function(reinterpret_cast<CUmodule>(0x100), "missing");
    FAIL() << "a missing kernel was found";
  } catch (const CudaError& e) {
    EXPECT_STREQ(
        e.what(),
        "cuModuleGetFunction of 'missing' failed: named symbol not found (CUDA error 500)");
  }
  // An error the driver has no string for still says which call and which code.
  state.fail["cuCtxSynchronize"] = 719;
  try {
    device.synchronize();
    FAIL() << "cuCtxSynchronize's failure went unnoticed";
  } catch (const CudaError& e) {
    EXPECT_STREQ(e.what(),
                 "cuCtxSynchronize failed: error not known to the driver (CUDA error 719)");
  }
  state.fail["cuMemcpyHtoD"] = CUDA_ERROR_OUT_OF_MEMORY;
  state.fail.erase("cuMemAlloc");
  double x = 1;
  DeviceArray a = device.alloc(&x, 8);
  EXPECT_THROW(device.to_device(a), CudaError);
  EXPECT_TRUE(a.host_dirty);  // not copied: still to be copied
}

TEST_F(CudaDriver, UnavailableReasonFromTheFirstFailure) {
  EXPECT_EQ(device_unavailable_reason(fake_table()), "");
  EXPECT_EQ(state.retained, 0);  // opened and released
  state.fail["cuInit"] = CUDA_ERROR_NO_DEVICE;
  EXPECT_EQ(device_unavailable_reason(fake_table()),
            "no usable CUDA device: cuInit failed: no CUDA-capable device is detected (CUDA "
            "error 100)");
  DriverTable t = fake_table();
  t.cuInit = nullptr;
  EXPECT_EQ(device_unavailable_reason(t), "CUDA driver table without cuInit");
}

// ---- Resolution through cuGetProcAddress

// Each entry the table needs, with the CUDA version of the ABI called (cudaTypedefs.h's
// PFN_<name>_v<version>: the _v2 memory entry points are 3020, cuDevicePrimaryCtxRelease_v2
// 11000, and cuCtxSynchronize stays 2000 because v13000 takes a context).
const std::map<std::string, int> kEntries = {
    {"cuInit", 2000},
    {"cuDriverGetVersion", 2020},
    {"cuGetErrorString", 6000},
    {"cuDeviceGet", 2000},
    {"cuDeviceGetCount", 2000},
    {"cuDeviceGetName", 2000},
    {"cuDeviceGetAttribute", 2000},
    {"cuDeviceTotalMem", 3020},
    {"cuDevicePrimaryCtxRetain", 7000},
    {"cuDevicePrimaryCtxRelease", 11000},
    {"cuCtxSetCurrent", 4000},
    {"cuCtxSynchronize", 2000},
    {"cuModuleLoadDataEx", 2010},
    {"cuModuleUnload", 2000},
    {"cuModuleGetFunction", 2000},
    {"cuMemAlloc", 3020},
    {"cuMemFree", 3020},
    {"cuMemcpyHtoD", 3020},
    {"cuMemcpyDtoH", 3020},
    {"cuLaunchKernel", 4000},
};

TEST(CudaDriverResolve, AsksForEachEntryByBaseNameAndAbiVersion) {
  // A distinct address per symbol, to see that each lands in its own slot.
  std::map<std::string, std::vector<char>> addresses;
  std::vector<std::string> asked;
  const GetProcAddress get = [&](const char* symbol, void** pfn, int version, cuuint64_t flags,
                                 CUdriverProcAddressQueryResult* status) {
    asked.push_back(symbol);
    EXPECT_EQ(flags, CU_GET_PROC_ADDRESS_DEFAULT) << symbol;
    const auto it = kEntries.find(symbol);
    if (it == kEntries.end() || it->second != version) {
      ADD_FAILURE() << symbol << " asked for CUDA " << version;
      *pfn = nullptr;
      *status = CU_GET_PROC_ADDRESS_SYMBOL_NOT_FOUND;
      return CUDA_SUCCESS;
    }
    addresses[symbol].resize(1);
    *pfn = addresses[symbol].data();
    *status = CU_GET_PROC_ADDRESS_SUCCESS;
    return CUDA_SUCCESS;
  };
  std::string why;
  const auto table = resolve_driver(get, why);
  ASSERT_TRUE(table) << why;
  EXPECT_EQ(asked.size(), kEntries.size());
  EXPECT_EQ(missing_entry(*table), nullptr);
  const auto at = [&](const char* s) { return static_cast<void*>(addresses.at(s).data()); };
  EXPECT_EQ(reinterpret_cast<void*>(table->cuMemAlloc), at("cuMemAlloc"));
  EXPECT_EQ(reinterpret_cast<void*>(table->cuMemcpyDtoH), at("cuMemcpyDtoH"));
  EXPECT_EQ(reinterpret_cast<void*>(table->cuLaunchKernel), at("cuLaunchKernel"));
  EXPECT_EQ(reinterpret_cast<void*>(table->cuDevicePrimaryCtxRelease),
            at("cuDevicePrimaryCtxRelease"));
}

TEST(CudaDriverResolve, AMissingEntryIsNamed) {
  std::vector<char> somewhere(1);
  const auto missing = [&](const char* gone, CUdriverProcAddressQueryResult how) {
    return [&somewhere, gone, how](const char* symbol, void** pfn, int, cuuint64_t,
                                   CUdriverProcAddressQueryResult* status) {
      const bool absent = std::strcmp(symbol, gone) == 0;
      *pfn = absent ? nullptr : somewhere.data();
      *status = absent ? how : CU_GET_PROC_ADDRESS_SUCCESS;
      return CUDA_SUCCESS;
    };
  };
  std::string why;
  EXPECT_FALSE(resolve_driver(missing("cuMemcpyHtoD", CU_GET_PROC_ADDRESS_SYMBOL_NOT_FOUND), why));
  EXPECT_EQ(why,
            "driver entry cuMemcpyHtoD (the CUDA 3.2 ABI) missing: the driver does not have it");
  EXPECT_FALSE(resolve_driver(
      missing("cuDevicePrimaryCtxRelease", CU_GET_PROC_ADDRESS_VERSION_NOT_SUFFICIENT), why));
  EXPECT_EQ(why,
            "driver entry cuDevicePrimaryCtxRelease (the CUDA 11.0 ABI) missing: the driver has "
            "only an older version");
  const GetProcAddress refuses = [](const char*, void** pfn, int, cuuint64_t,
                                    CUdriverProcAddressQueryResult*) {
    *pfn = nullptr;
    return CUDA_ERROR_INVALID_VALUE;
  };
  EXPECT_FALSE(resolve_driver(refuses, why));
  EXPECT_EQ(why, "cuGetProcAddress failed for cuInit (the CUDA 2.0 ABI): CUDA error 1");
}

// ---- This machine's driver

bool driver_present(std::string& dl_error) {
  void* lib = dlopen("libcuda.so.1", RTLD_NOW | RTLD_LOCAL);
  if (!lib) {
    const char* e = dlerror();
    dl_error = e ? e : "";
    return false;
  }
  dlclose(lib);
  return true;
}

TEST(CudaDriverLoad, WithoutADriverSaysLibcudaIsMissing) {
  std::string dl_error;
  if (driver_present(dl_error)) GTEST_SKIP() << "libcuda.so.1 loads on this machine";
  if (dl_error.find("No such file") == std::string::npos)
    GTEST_SKIP() << "libcuda.so.1 is there but does not load: " << dl_error;
  std::string why;
  EXPECT_FALSE(load_driver(why));
  EXPECT_EQ(why, "libcuda.so.1 not found: no NVIDIA driver on this machine");
  EXPECT_EQ(gpu_unavailable_reason(), why);
}

TEST(CudaDriverLoad, WithADriverEveryEntryResolves) {
  std::string dl_error;
  if (!driver_present(dl_error)) GTEST_SKIP() << "no libcuda.so.1 here: " << dl_error;
  std::string why;
  const auto table = load_driver(why);
  ASSERT_TRUE(table) << why;
  EXPECT_EQ(missing_entry(*table), nullptr);
  int version = 0;
  ASSERT_EQ(table->cuDriverGetVersion(&version), CUDA_SUCCESS);
  EXPECT_GE(version, 11030);  // cuGetProcAddress exists from CUDA 11.3
  std::cout << "driver supports CUDA " << version << "; "
            << (gpu_unavailable_reason().empty() ? "a GPU opens" : gpu_unavailable_reason())
            << "\n";
}

// A kernel adding `a` to each of n doubles: hand-written PTX, old enough (ISA 7.0, sm_60)
// for any driver and GPU this project supports; the driver JIT-compiles it for the device.
constexpr const char* kAddToEach = R"(.version 7.0
.target sm_60
.address_size 64

.visible .entry add_to_each(.param .u64 x, .param .f64 a, .param .u32 n)
{
  .reg .pred %p;
  .reg .b32 %r<5>;
  .reg .b64 %rd<5>;
  .reg .f64 %fd<3>;
  ld.param.u64 %rd1, [x];
  ld.param.f64 %fd1, [a];
  ld.param.u32 %r1, [n];
  mov.u32 %r2, %ctaid.x;
  mov.u32 %r3, %ntid.x;
  mov.u32 %r4, %tid.x;
  mad.lo.s32 %r2, %r2, %r3, %r4;
  setp.ge.u32 %p, %r2, %r1;
  @%p bra DONE;
  cvta.to.global.u64 %rd2, %rd1;
  mul.wide.u32 %rd3, %r2, 8;
  add.s64 %rd4, %rd2, %rd3;
  ld.global.f64 %fd2, [%rd4];
  add.rn.f64 %fd2, %fd2, %fd1;
  st.global.f64 [%rd4], %fd2;
DONE:
  ret;
}
)";

TEST(CudaDriverLoad, OnAGpuAKernelRunsAndItsResultComesBack) {
  const std::string why = gpu_unavailable_reason();
  if (!why.empty()) GTEST_SKIP() << why;
  std::string load_why;
  Device device(*load_driver(load_why));
  device.open(0);
  std::cout << device.name() << ", sm_" << device.compute_major() << device.compute_minor() << ", "
            << device.multiprocessors() << " multiprocessors, " << (device.total_memory() >> 20)
            << " MiB\n";
  const uint32_t n = 1000;
  std::vector<double> x(n);
  for (uint32_t i = 0; i < n; ++i) x[i] = i;
  DeviceArray a = device.alloc(x.data(), n * sizeof(double));
  device.to_device(a);
  const CUmodule m = device.load_module(kAddToEach);
  const CUfunction f = device.function(m, "add_to_each");
  const std::vector<KernelArg> args = {KernelArg::pointer(a), KernelArg::of(1.5), KernelArg::of(n)};
  device.launch(f, Dim3{(n + 255) / 256, 1, 1}, Dim3{256, 1, 1}, args);
  a.device_dirty = true;
  device.synchronize();
  device.to_host(a);
  for (uint32_t i = 0; i < n; ++i) ASSERT_EQ(x[i], i + 1.5) << i;
  device.free(a);
  // A PTX the driver rejects: the call, the driver's string and its JIT log.
  try {
    device.load_module(".version 7.0\n.target sm_60\n.address_size 64\nnot ptx\n");
    FAIL() << "a bad PTX loaded";
  } catch (const CudaError& e) {
    std::cout << e.what() << "\n";
    EXPECT_EQ(e.call(), "cuModuleLoadDataEx");
    EXPECT_NE(std::string(e.what()).find("line 4"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace simit::jit::cuda
