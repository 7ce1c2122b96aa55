// The GPU probe (jit/ptx/gpu_probe.h) and the driver layer's stream table, without a GPU: a fake
// driver behind a fake cuGetProcAddress runs the whole probe (its kernels emulated by name,
// its memory on the host), which must release all it made, capture the graph it launches and
// print the device's properties; the command line's usage errors, the exit status 77 with the
// reason where no driver loads or no device opens, and the probe's PTX assembled by ptxas.
#include <gtest/gtest.h>

#include <chrono>
#include <cstdint>
#include <cstring>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "jit/ptx/cuda_driver.h"
#include "jit/ptx/gpu_probe.h"
#include "jit/ptx/ptx_check.h"

namespace simit::jit::cuda {
namespace {

constexpr CUresult kInvalidHandle = 400;  // CUDA_ERROR_INVALID_HANDLE

// One fake device. Handles are small integers; every call a driver would refuse (an unknown
// handle, a copy out of bounds) returns an error and is listed in `misuse`.
struct FakeGpu {
  std::map<std::string, std::pair<int, void*>> entries;  // name -> (ABI version, function)
  std::map<std::string, int> asked;                      // name -> the version asked for
  std::set<std::string> withheld;                        // reported as not found
  std::map<std::string, CUresult> fail;                  // name -> the result it returns
  std::vector<std::string> misuse;

  int device_count = 1;
  bool initialised = false;
  int retained = 0;
  std::vector<std::string> ptx_loaded;
  int modules_loaded = 0;
  std::vector<std::string> functions;  // a CUfunction is its index + 1
  std::map<CUdeviceptr, std::vector<unsigned char>> memory;
  CUdeviceptr next_pointer = 0x100000;
  std::set<void*> pinned;
  std::uintptr_t next_handle = 0x10;
  std::set<CUstream> streams;
  CUstream capturing = nullptr;
  std::vector<std::size_t> captured;
  std::map<CUgraph, std::vector<std::size_t>> graphs;
  std::map<CUgraphExec, std::vector<std::size_t>> execs;
  std::map<CUevent, std::optional<std::chrono::steady_clock::time_point>> events;
  std::map<std::string, long> kernels_run;  // by name
  long graph_launches = 0;
  std::uint32_t fill_wrong_at = UINT32_MAX;  // the fill kernel writes a wrong value here

  CUresult refuse(const std::string& what) {
    misuse.push_back(what);
    return CUDA_ERROR_INVALID_VALUE;
  }
  CUresult failure(const char* name) {
    const auto it = fail.find(name);
    return it == fail.end() ? CUDA_SUCCESS : it->second;
  }
  // Runs kernel `f` (its index) as the GPU would.
  CUresult run(std::size_t f, unsigned grid, unsigned block, void** params) {
    const std::string& name = functions.at(f);
    ++kernels_run[name];
    if (name == "simit_probe_empty") return CUDA_SUCCESS;
    if (name != "simit_probe_fill" || !params) return refuse("launch of " + name);
    CUdeviceptr out;
    std::uint32_t value, n;
    std::memcpy(&out, params[0], sizeof out);
    std::memcpy(&value, params[1], sizeof value);
    std::memcpy(&n, params[2], sizeof n);
    const auto it = memory.find(out);
    if (it == memory.end() || it->second.size() < std::size_t{n} * 4)
      return refuse("fill out of bounds");
    if (std::uint64_t{grid} * block < n) return refuse("fill with too few threads");
    for (std::uint32_t i = 0; i < n; ++i) {
      const std::uint32_t v = value + i + (i == fill_wrong_at ? 1 : 0);
      std::memcpy(it->second.data() + std::size_t{i} * 4, &v, 4);
    }
    return CUDA_SUCCESS;
  }
  std::vector<unsigned char>* block(CUdeviceptr p, std::size_t bytes) {
    const auto it = memory.find(p);
    return it == memory.end() || it->second.size() < bytes ? nullptr : &it->second;
  }
  template <class Handle>
  Handle new_handle() {
    return reinterpret_cast<Handle>(next_handle++);
  }
};
FakeGpu* fake = nullptr;

template <class Pfn, class Lambda>
void put(const char* name, int version, Lambda lambda) {
  const Pfn pfn = lambda;
  fake->entries[name] = {version, reinterpret_cast<void*>(pfn)};
}

void install_driver_entries() {
  put<PFN_cuInit_v2000>("cuInit", 2000, [](unsigned) {
    fake->initialised = true;
    return fake->failure("cuInit");
  });
  put<PFN_cuDriverGetVersion_v2020>("cuDriverGetVersion", 2020, [](int* v) {
    *v = 13000;
    return CUDA_SUCCESS;
  });
  put<PFN_cuGetErrorString_v6000>("cuGetErrorString", 6000, [](CUresult r, const char** s) {
    *s = r == CUDA_ERROR_OUT_OF_MEMORY ? "out of memory" : "some error";
    return CUDA_SUCCESS;
  });
  put<PFN_cuDeviceGet_v2000>("cuDeviceGet", 2000, [](CUdevice* d, int ordinal) {
    *d = ordinal;
    return fake->initialised ? CUDA_SUCCESS : CUDA_ERROR_NOT_INITIALIZED;
  });
  put<PFN_cuDeviceGetCount_v2000>("cuDeviceGetCount", 2000, [](int* n) {
    *n = fake->device_count;
    return CUDA_SUCCESS;
  });
  put<PFN_cuDeviceGetName_v2000>("cuDeviceGetName", 2000, [](char* name, int len, CUdevice) {
    std::snprintf(name, static_cast<std::size_t>(len), "Fake H200");
    return CUDA_SUCCESS;
  });
  put<PFN_cuDeviceGetAttribute_v2000>("cuDeviceGetAttribute", 2000,
                                      [](int* v, CUdevice_attribute a, CUdevice) {
                                        *v = a == CU_DEVICE_ATTRIBUTE_COMPUTE_CAPABILITY_MAJOR   ? 9
                                             : a == CU_DEVICE_ATTRIBUTE_COMPUTE_CAPABILITY_MINOR ? 0
                                             : a == CU_DEVICE_ATTRIBUTE_MULTIPROCESSOR_COUNT ? 132
                                                                                             : -1;
                                        return CUDA_SUCCESS;
                                      });
  put<PFN_cuDeviceTotalMem_v3020>("cuDeviceTotalMem", 3020, [](std::size_t* bytes, CUdevice) {
    *bytes = std::size_t{80} << 30;
    return CUDA_SUCCESS;
  });
  put<PFN_cuDevicePrimaryCtxRetain_v7000>("cuDevicePrimaryCtxRetain", 7000,
                                          [](CUcontext* c, CUdevice) {
                                            *c = reinterpret_cast<CUcontext>(0xC0);
                                            ++fake->retained;
                                            return CUDA_SUCCESS;
                                          });
  put<PFN_cuDevicePrimaryCtxRelease_v11000>("cuDevicePrimaryCtxRelease", 11000, [](CUdevice) {
    --fake->retained;
    return CUDA_SUCCESS;
  });
  put<PFN_cuCtxSetCurrent_v4000>("cuCtxSetCurrent", 4000, [](CUcontext) { return CUDA_SUCCESS; });
  put<PFN_cuCtxSynchronize_v2000>("cuCtxSynchronize", 2000, [] { return CUDA_SUCCESS; });
  put<PFN_cuModuleLoadDataEx_v2010>(
      "cuModuleLoadDataEx", 2010,
      [](CUmodule* m, const void* image, unsigned, CUjit_option*, void**) {
        fake->ptx_loaded.push_back(static_cast<const char*>(image));
        ++fake->modules_loaded;
        *m = reinterpret_cast<CUmodule>(0x900);
        return CUDA_SUCCESS;
      });
  put<PFN_cuModuleUnload_v2000>("cuModuleUnload", 2000, [](CUmodule) {
    --fake->modules_loaded;
    return CUDA_SUCCESS;
  });
  put<PFN_cuModuleGetFunction_v2000>("cuModuleGetFunction", 2000,
                                     [](CUfunction* f, CUmodule, const char* name) {
                                       fake->functions.push_back(name);
                                       *f = reinterpret_cast<CUfunction>(fake->functions.size());
                                       return CUDA_SUCCESS;
                                     });
  put<PFN_cuMemAlloc_v3020>("cuMemAlloc", 3020, [](CUdeviceptr* p, std::size_t bytes) {
    *p = fake->next_pointer;
    fake->next_pointer += (bytes + 0xFFFF) & ~std::size_t{0xFFFF};
    fake->memory[*p].assign(bytes, 0xEE);
    return CUDA_SUCCESS;
  });
  put<PFN_cuMemFree_v3020>("cuMemFree", 3020, [](CUdeviceptr p) {
    return fake->memory.erase(p) ? CUDA_SUCCESS : fake->refuse("cuMemFree of an unknown pointer");
  });
  put<PFN_cuMemcpyHtoD_v3020>("cuMemcpyHtoD", 3020,
                              [](CUdeviceptr dst, const void* src, std::size_t bytes) {
                                auto* m = fake->block(dst, bytes);
                                if (!m) return fake->refuse("cuMemcpyHtoD out of bounds");
                                std::memcpy(m->data(), src, bytes);
                                return CUDA_SUCCESS;
                              });
  put<PFN_cuMemcpyDtoH_v3020>("cuMemcpyDtoH", 3020,
                              [](void* dst, CUdeviceptr src, std::size_t bytes) {
                                const auto* m = fake->block(src, bytes);
                                if (!m) return fake->refuse("cuMemcpyDtoH out of bounds");
                                std::memcpy(dst, m->data(), bytes);
                                return CUDA_SUCCESS;
                              });
  put<PFN_cuLaunchKernel_v4000>(
      "cuLaunchKernel", 4000,
      [](CUfunction f, unsigned gx, unsigned gy, unsigned gz, unsigned bx, unsigned by, unsigned bz,
         unsigned, CUstream stream, void** params, void**) {
        const auto index = reinterpret_cast<std::uintptr_t>(f) - 1;
        if (index >= fake->functions.size()) return fake->refuse("launch of an unknown function");
        if (gy * gz * by * bz != 1) return fake->refuse("launch in more than one dimension");
        if (stream && !fake->streams.count(stream)) return fake->refuse("launch on a bad stream");
        if (stream && stream == fake->capturing) {
          fake->captured.push_back(index);
          return CUDA_SUCCESS;
        }
        return fake->run(index, gx, bx, params);
      });
}

void install_stream_entries() {
  put<PFN_cuStreamCreate_v2000>("cuStreamCreate", 2000, [](CUstream* s, unsigned flags) {
    if (flags != CU_STREAM_NON_BLOCKING) fake->misuse.push_back("a blocking stream");
    *s = fake->new_handle<CUstream>();
    fake->streams.insert(*s);
    return CUDA_SUCCESS;
  });
  put<PFN_cuStreamDestroy_v4000>("cuStreamDestroy", 4000, [](CUstream s) {
    return fake->streams.erase(s) ? CUDA_SUCCESS : kInvalidHandle;
  });
  put<PFN_cuStreamSynchronize_v2000>("cuStreamSynchronize", 2000, [](CUstream s) {
    return fake->streams.count(s) ? CUDA_SUCCESS : kInvalidHandle;
  });
  put<PFN_cuEventCreate_v2000>("cuEventCreate", 2000, [](CUevent* e, unsigned) {
    *e = fake->new_handle<CUevent>();
    fake->events[*e];
    return CUDA_SUCCESS;
  });
  put<PFN_cuEventDestroy_v4000>("cuEventDestroy", 4000, [](CUevent e) {
    return fake->events.erase(e) ? CUDA_SUCCESS : kInvalidHandle;
  });
  put<PFN_cuEventRecord_v2000>("cuEventRecord", 2000, [](CUevent e, CUstream) {
    if (!fake->events.count(e)) return kInvalidHandle;
    fake->events[e] = std::chrono::steady_clock::now();
    return CUDA_SUCCESS;
  });
  put<PFN_cuEventSynchronize_v2000>("cuEventSynchronize", 2000, [](CUevent e) {
    return fake->events.count(e) ? CUDA_SUCCESS : kInvalidHandle;
  });
  put<PFN_cuEventElapsedTime_v2000>(
      "cuEventElapsedTime", 2000, [](float* ms, CUevent a, CUevent b) {
        if (!fake->events.count(a) || !fake->events.count(b) || !fake->events[a] ||
            !fake->events[b])
          return fake->refuse("elapsed time of an event not recorded");
        *ms = std::chrono::duration<float, std::milli>(*fake->events[b] - *fake->events[a]).count();
        return CUDA_SUCCESS;
      });
  put<PFN_cuStreamBeginCapture_v10010>("cuStreamBeginCapture", 10010,
                                       [](CUstream s, CUstreamCaptureMode) {
                                         if (!fake->streams.count(s) || fake->capturing)
                                           return fake->refuse("a bad capture");
                                         fake->capturing = s;
                                         fake->captured.clear();
                                         return CUDA_SUCCESS;
                                       });
  put<PFN_cuStreamEndCapture_v10000>("cuStreamEndCapture", 10000, [](CUstream s, CUgraph* g) {
    if (s != fake->capturing) return fake->refuse("end of a capture not begun");
    fake->capturing = nullptr;
    *g = fake->new_handle<CUgraph>();
    fake->graphs[*g] = fake->captured;
    return CUDA_SUCCESS;
  });
  put<PFN_cuGraphInstantiateWithFlags_v11040>("cuGraphInstantiateWithFlags", 11040,
                                              [](CUgraphExec* e, CUgraph g, unsigned long long) {
                                                if (!fake->graphs.count(g)) return kInvalidHandle;
                                                *e = fake->new_handle<CUgraphExec>();
                                                fake->execs[*e] = fake->graphs[g];
                                                return CUDA_SUCCESS;
                                              });
  put<PFN_cuGraphLaunch_v10000>("cuGraphLaunch", 10000, [](CUgraphExec e, CUstream s) {
    if (!fake->execs.count(e) || !fake->streams.count(s)) return kInvalidHandle;
    ++fake->graph_launches;
    for (std::size_t f : fake->execs[e])
      if (const CUresult r = fake->run(f, 1, 1, nullptr); r != CUDA_SUCCESS) return r;
    return CUDA_SUCCESS;
  });
  put<PFN_cuGraphExecDestroy_v10000>("cuGraphExecDestroy", 10000, [](CUgraphExec e) {
    return fake->execs.erase(e) ? CUDA_SUCCESS : kInvalidHandle;
  });
  put<PFN_cuGraphDestroy_v10000>("cuGraphDestroy", 10000, [](CUgraph g) {
    return fake->graphs.erase(g) ? CUDA_SUCCESS : kInvalidHandle;
  });
  put<PFN_cuMemcpyDtoD_v3020>("cuMemcpyDtoD", 3020,
                              [](CUdeviceptr dst, CUdeviceptr src, std::size_t bytes) {
                                auto* d = fake->block(dst, bytes);
                                const auto* s = fake->block(src, bytes);
                                if (!d || !s) return fake->refuse("cuMemcpyDtoD out of bounds");
                                std::memcpy(d->data(), s->data(), bytes);
                                return CUDA_SUCCESS;
                              });
  put<PFN_cuMemAllocHost_v3020>("cuMemAllocHost", 3020, [](void** p, std::size_t bytes) {
    if (const CUresult r = fake->failure("cuMemAllocHost"); r != CUDA_SUCCESS) return r;
    *p = ::operator new(bytes);
    fake->pinned.insert(*p);
    return CUDA_SUCCESS;
  });
  put<PFN_cuMemFreeHost_v2000>("cuMemFreeHost", 2000, [](void* p) {
    if (!fake->pinned.erase(p)) return fake->refuse("cuMemFreeHost of an unknown pointer");
    ::operator delete(p);
    return CUDA_SUCCESS;
  });
}

// The fake's cuGetProcAddress: the entry of that name, whatever version is asked (the versions
// asked are checked apart).
CUresult fake_get(const char* symbol, void** pfn, int version, cuuint64_t,
                  CUdriverProcAddressQueryResult* status) {
  fake->asked[symbol] = version;
  const auto it = fake->entries.find(symbol);
  if (it == fake->entries.end() || fake->withheld.count(symbol)) {
    *pfn = nullptr;
    *status = CU_GET_PROC_ADDRESS_SYMBOL_NOT_FOUND;
    return CUDA_SUCCESS;
  }
  *pfn = it->second.second;
  *status = CU_GET_PROC_ADDRESS_SUCCESS;
  return CUDA_SUCCESS;
}

// A quick probe: 20 launches, a graph of 12 kernels, 1 MiB buffers, 3 repetitions.
const std::vector<std::string> kQuick = {"--launches", "20", "--graph-kernels", "12",
                                         "--copy-mib", "1",  "--reps",          "3"};

class GpuProbe : public ::testing::Test {
 protected:
  void SetUp() override {
    fake = &state;
    install_driver_entries();
    install_stream_entries();
  }
  void TearDown() override {
    for (void* p : state.pinned) ::operator delete(p);
    fake = nullptr;
  }
  int probe(const std::vector<std::string>& args) {
    const GetProcAddress get = fake_get;
    return run_probe(args, out, err, &get);
  }
  // Everything the probe made was released.
  void expect_all_released() {
    EXPECT_EQ(state.retained, 0);
    EXPECT_EQ(state.modules_loaded, 0);
    EXPECT_TRUE(state.memory.empty());
    EXPECT_TRUE(state.pinned.empty());
    EXPECT_TRUE(state.streams.empty());
    EXPECT_TRUE(state.events.empty());
    EXPECT_TRUE(state.graphs.empty());
    EXPECT_TRUE(state.execs.empty());
    EXPECT_EQ(state.capturing, nullptr);
  }

  FakeGpu state;
  std::ostringstream out, err;
};

// The samples column of the row whose name matches `name` (a regex), or -1 when there is none.
long samples_of(const std::string& table, const std::string& name) {
  std::smatch m;
  const std::regex row("\\| " + name + " \\| [^|]+ \\| [^|]+ \\| [^|]+ \\| ([0-9]+) \\|");
  return std::regex_search(table, m, row) ? std::stol(m[1]) : -1;
}

TEST_F(GpuProbe, MeasuresEverythingOnAFakeGpuAndReleasesAll) {
  ASSERT_EQ(probe(kQuick), kProbeOk) << out.str() << err.str();
  const std::string t = out.str();
  EXPECT_TRUE(state.misuse.empty()) << ::testing::PrintToString(state.misuse);
  expect_all_released();
  EXPECT_NE(t.find("| driver | CUDA 13.0 (13000) |\n"), std::string::npos) << t;
  EXPECT_NE(t.find("| device 0 | Fake H200 |\n"), std::string::npos);
  EXPECT_NE(t.find("| memory | 80.0 GiB (85899345920 bytes) |\n"), std::string::npos);
  EXPECT_NE(t.find("| multiprocessors | 132 |\n"), std::string::npos);
  EXPECT_NE(t.find("| compute capability | 9.0 |\n"), std::string::npos);
  // The module loaded is the probe's PTX, once; both kernels were looked up in it.
  ASSERT_EQ(state.ptx_loaded.size(), 1u);
  EXPECT_EQ(state.ptx_loaded[0], probe_ptx());
  EXPECT_EQ(state.functions, (std::vector<std::string>{"simit_probe_empty", "simit_probe_fill"}));
  // The graph held the 12 empty kernels, launched once to upload it and then 3 times timed.
  EXPECT_EQ(state.graph_launches, 4);
  // Empty kernels: 20 warm-ups, 20 one by one, 3 x 20 back to back, 3 x 12 on the stream,
  // 4 x 12 in the graph; the fill kernel once to warm up and 3 times timed.
  EXPECT_EQ(state.kernels_run["simit_probe_empty"], 20 + 20 + 3 * 20 + 3 * 12 + 4 * 12);
  EXPECT_EQ(state.kernels_run["simit_probe_fill"], 4);
  // Every row, with its sample count.
  EXPECT_EQ(samples_of(t, "empty kernel: launch, then synchronize"), 20) << t;
  EXPECT_EQ(samples_of(t,
                       "empty kernel: 20 launches back to back, then one synchronize "
                       "\\(per launch\\)"),
            3);
  EXPECT_EQ(samples_of(t,
                       "empty kernel: 12 launches back to back on a stream, then one "
                       "synchronize \\(per launch\\)"),
            3);
  EXPECT_EQ(samples_of(t, "graph of 12 empty kernels: instantiate"), 1);
  EXPECT_EQ(samples_of(t, "graph of 12 empty kernels: launch, then synchronize"), 3);
  EXPECT_EQ(samples_of(t, "graph of 12 empty kernels: launch, then synchronize \\(per kernel\\)"),
            3);
  EXPECT_EQ(samples_of(t, "fill kernel: write 1 MiB \\(4 bytes per thread\\)"), 3);
  for (const char* copy : {"host to device, pageable", "device to host, pageable",
                           "host to device, pinned", "device to host, pinned"})
    EXPECT_EQ(samples_of(t, std::string(copy) + " host memory, 1 MiB"), 3) << copy;
  EXPECT_EQ(samples_of(t, "device to device, 1 MiB \\(bytes copied; twice as many move\\)"), 3);
  EXPECT_NE(t.find("The fill kernel and the device-to-device copy are timed between two events "
                   "on the GPU;"),
            std::string::npos);
  EXPECT_EQ(t.find("WRONG"), std::string::npos);
  EXPECT_EQ(t.find("Not measured"), std::string::npos);
}

TEST_F(GpuProbe, AskedForEachStreamEntryByItsAbiVersion) {
  ASSERT_EQ(probe(kQuick), kProbeOk) << out.str() << err.str();
  // The versions of cudaTypedefs.h's typedefs (PFN_<name>_v<version>) these entries have.
  const std::map<std::string, int> expected = {{"cuStreamCreate", 2000},
                                               {"cuStreamDestroy", 4000},
                                               {"cuStreamSynchronize", 2000},
                                               {"cuEventCreate", 2000},
                                               {"cuEventDestroy", 4000},
                                               {"cuEventRecord", 2000},
                                               {"cuEventSynchronize", 2000},
                                               {"cuEventElapsedTime", 2000},
                                               {"cuStreamBeginCapture", 10010},
                                               {"cuStreamEndCapture", 10000},
                                               {"cuGraphInstantiateWithFlags", 11040},
                                               {"cuGraphLaunch", 10000},
                                               {"cuGraphExecDestroy", 10000},
                                               {"cuGraphDestroy", 10000},
                                               {"cuMemcpyDtoD", 3020},
                                               {"cuMemAllocHost", 3020},
                                               {"cuMemFreeHost", 2000}};
  for (const auto& [name, version] : expected) {
    ASSERT_TRUE(state.asked.count(name)) << name;
    EXPECT_EQ(state.asked[name], version) << name;
  }
}

TEST_F(GpuProbe, AWrongValueFromTheFillKernelFailsTheProbe) {
  state.fill_wrong_at = 5;
  EXPECT_EQ(probe(kQuick), kProbeFailed);
  // The last fill wrote 0x9E3779B9 * 4 + i (mod 2^32): 2654435769 * 4 = 10617743076, minus
  // 2^32 twice = 2027808484; at index 5 the fake wrote one more.
  EXPECT_NE(out.str().find("WRONG: the fill kernel wrote 2027808490 at index 5, not 2027808489"),
            std::string::npos)
      << out.str();
  expect_all_released();
}

TEST_F(GpuProbe, WithoutTheStreamEntriesTheRestIsStillMeasured) {
  state.withheld.insert("cuGraphLaunch");
  ASSERT_EQ(probe(kQuick), kProbeOk) << out.str() << err.str();
  const std::string t = out.str();
  EXPECT_NE(t.find("Not measured: no graph, pinned copies or device-to-device copy: driver entry "
                   "cuGraphLaunch (the CUDA 10.0 ABI) missing: the driver does not have it"),
            std::string::npos)
      << t;
  EXPECT_EQ(t.find("graph of"), std::string::npos);
  EXPECT_EQ(t.find("pinned host memory"), std::string::npos);
  EXPECT_EQ(samples_of(t, "host to device, pageable host memory, 1 MiB"), 3);
  EXPECT_EQ(samples_of(t, "fill kernel: write 1 MiB \\(4 bytes per thread\\)"), 3);
  EXPECT_NE(t.find("The fill kernel and the device-to-device copy are timed by the host's clock"),
            std::string::npos);
  expect_all_released();
}

TEST_F(GpuProbe, AFailedCallStopsItWithTheRowsMeasuredSoFar) {
  state.fail["cuMemAllocHost"] = CUDA_ERROR_OUT_OF_MEMORY;
  EXPECT_EQ(probe(kQuick), kProbeFailed);
  const std::string t = out.str();
  EXPECT_NE(t.find("Stopped: cuMemAllocHost failed: out of memory (CUDA error 2)"),
            std::string::npos)
      << t;
  EXPECT_EQ(samples_of(t, "device to host, pageable host memory, 1 MiB"), 3);
  EXPECT_EQ(t.find("pinned host memory"), std::string::npos);
  expect_all_released();
}

TEST_F(GpuProbe, NoDeviceExits77WithTheReason) {
  state.device_count = 0;
  EXPECT_EQ(probe({}), kProbeNoGpu);
  EXPECT_EQ(out.str(),
            "No GPU probed: no usable CUDA device: cuDeviceGet failed: no CUDA device 0 (the "
            "driver found 0)\n");
  EXPECT_EQ(state.retained, 0);
}

TEST_F(GpuProbe, AMissingDriverEntryExits77WithTheReason) {
  state.withheld.insert("cuLaunchKernel");
  EXPECT_EQ(probe({}), kProbeNoGpu);
  EXPECT_EQ(out.str(),
            "No GPU probed: driver entry cuLaunchKernel (the CUDA 4.0 ABI) missing: the driver "
            "does not have it\n");
}

TEST_F(GpuProbe, TheStreamTableResolvesWholeOrNamesWhatIsMissing) {
  std::string why;
  const GetProcAddress get = fake_get;
  const auto streams = resolve_streams(get, why);
  ASSERT_TRUE(streams) << why;
  EXPECT_EQ(missing_stream_entry(*streams), nullptr);
  EXPECT_STREQ(missing_stream_entry(StreamTable{}), "cuStreamCreate");
  StreamTable partial = *streams;
  partial.cuMemFreeHost = nullptr;
  EXPECT_STREQ(missing_stream_entry(partial), "cuMemFreeHost");
  state.withheld.insert("cuStreamBeginCapture");
  EXPECT_FALSE(resolve_streams(get, why));
  EXPECT_EQ(why,
            "driver entry cuStreamBeginCapture (the CUDA 10.1 ABI) missing: the driver does not "
            "have it");
}

// ---- The command line, with no driver at all

TEST(GpuProbeCommandLine, HelpAndUsageErrors) {
  std::ostringstream out, err;
  EXPECT_EQ(run_probe({"--help"}, out, err), kProbeOk);
  EXPECT_NE(out.str().find("Usage: gpu_probe [OPTIONS]"), std::string::npos);
  EXPECT_NE(out.str().find("77 when there is no driver"), std::string::npos);
  const std::vector<std::pair<std::vector<std::string>, std::string>> cases = {
      {{"--bogus"}, "gpu_probe: unknown argument '--bogus' (see --help)\n"},
      {{"--launches"}, "gpu_probe: --launches needs a value (see --help)\n"},
      {{"--reps", "0"}, "gpu_probe: --reps takes a whole number from 1 to 1000, not '0'\n"},
      {{"--copy-mib=4097"},
       "gpu_probe: --copy-mib takes a whole number from 1 to 4096, not '4097'\n"},
      {{"--device", "1x"}, "gpu_probe: --device takes a whole number from 0 to 1023, not '1x'\n"},
      {{"--driver="}, "gpu_probe: --driver needs a library path\n"}};
  for (const auto& [args, message] : cases) {
    std::ostringstream o, e;
    EXPECT_EQ(run_probe(args, o, e), kProbeUsage) << message;
    EXPECT_EQ(e.str(), message);
    EXPECT_EQ(o.str(), "");
  }
}

TEST(GpuProbeCommandLine, ADriverLibraryThatDoesNotLoadExits77WithTheReason) {
  std::ostringstream out, err;
  EXPECT_EQ(run_probe({"--driver", "/nonexistent/libcuda.so.1"}, out, err), kProbeNoGpu);
  EXPECT_EQ(out.str(), "No GPU probed: /nonexistent/libcuda.so.1 not found\n");
  // A library that loads but is no driver: libm.so.6 (glibc's) has no cuGetProcAddress.
  std::ostringstream out2;
  EXPECT_EQ(run_probe({"--driver=libm.so.6"}, out2, err), kProbeNoGpu);
  EXPECT_EQ(out2.str(),
            "No GPU probed: cuGetProcAddress missing: driver too old (CUDA 11.3 or newer is "
            "needed)\n");
}

// This machine's driver: without one, 77 and the driver layer's own reason; with a GPU, a
// quick probe that measures everything.
TEST(GpuProbeCommandLine, ThisMachine) {
  std::ostringstream out, err;
  const std::string reason = gpu_unavailable_reason();
  if (!reason.empty()) {
    EXPECT_EQ(run_probe({}, out, err), kProbeNoGpu);
    EXPECT_EQ(out.str(), "No GPU probed: " + reason + "\n");
    return;
  }
  ASSERT_EQ(run_probe(kQuick, out, err), kProbeOk) << out.str() << err.str();
  EXPECT_NE(samples_of(out.str(), "graph of 12 empty kernels: launch, then synchronize"), -1)
      << out.str();
}

// The hand-written PTX is valid for the H200 (sm_90) and the oldest target it names (sm_75).
TEST(GpuProbePtx, AssemblesWithPtxas) {
  std::string why;
  const std::string ptxas = ptx::find_ptxas(why);
  if (ptxas.empty()) GTEST_SKIP() << why;
  for (const char* arch : {"sm_75", "sm_90"}) {
    std::string message;
    EXPECT_TRUE(ptx::assemble(ptxas, probe_ptx(), arch, message)) << arch << ": " << message;
  }
}

}  // namespace
}  // namespace simit::jit::cuda
