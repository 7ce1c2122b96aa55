// The GPU executor (jit/ptx/gpu_executor.h) without a GPU: its launch path and copies against
// a fake driver table, and its whole data path over host memory (the emulation) giving the
// interpreter's bits for a program that assembles, applies and reduces.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <sstream>
#include <string>
#include <vector>

#include "api/compiled_program.h"
#include "api/engine.h"
#include "interp/runtime_error.h"
#include "jit/ptx/cuda_driver.h"
#include "jit/ptx/gpu_executor.h"
#include "jit/ptx/ptx_target.h"
#include "runtime/set.h"

namespace simit::jit::ptx {
namespace {

using namespace simit::jit::cuda;

// A driver whose device memory is host memory and whose launches call `on_launch`.
struct Launch {
  unsigned grid = 0, block = 0;
  CUdeviceptr table = 0, scalars = 0, endpoints = 0, failure = 0;
  int32_t begin = 0, end = 0;
};
struct Fake {
  int allocations = 0, frees = 0;
  long long to_device = 0, to_host = 0;
  std::string ptx;
  std::vector<Launch> launches;
  std::function<void(const Launch&)> on_launch;
};
Fake* fake = nullptr;

template <class T>
T param(void** params, int i) {
  T v;
  std::memcpy(&v, params[i], sizeof v);
  return v;
}

DriverTable fake_table() {
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
    static int module;
    *m = reinterpret_cast<CUmodule>(&module);
    return CUDA_SUCCESS;
  };
  t.cuModuleUnload = [](CUmodule) { return CUDA_SUCCESS; };
  t.cuModuleGetFunction = [](CUfunction* f, CUmodule, const char* name) {
    if (std::string(name) != kMapEntry) return CUDA_ERROR_NOT_FOUND;
    static int function;
    *f = reinterpret_cast<CUfunction>(&function);
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
  t.cuLaunchKernel = [](CUfunction, unsigned gx, unsigned, unsigned, unsigned bx, unsigned,
                        unsigned, unsigned, CUstream, void** params, void**) {
    Launch l;
    l.grid = gx;
    l.block = bx;
    l.table = param<CUdeviceptr>(params, 0);
    l.scalars = param<CUdeviceptr>(params, 1);
    l.endpoints = param<CUdeviceptr>(params, 2);
    l.begin = param<int32_t>(params, 3);
    l.end = param<int32_t>(params, 4);
    l.failure = param<CUdeviceptr>(params, 5);
    fake->launches.push_back(l);
    if (fake->on_launch) fake->on_launch(l);
    return CUDA_SUCCESS;
  };
  return t;
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

TEST_F(GpuExecutorFake, CopiesInLaunchesOneThreadPerElementAndCopiesWritesBack) {
  auto executor = make_gpu_executor_over(fake_table());
  EXPECT_TRUE(is_gpu_executor(*executor));
  EXPECT_FALSE(is_emulated_gpu_executor(*executor));
  EXPECT_EQ(executor->chunk_for(1000), 1);
  EXPECT_TRUE(executor->parallel());
  PtxKernel kernel;
  kernel.ptx = "// the kernel's PTX";
  kernel.entry = kMapEntry;

  double in[4] = {1, 2, 3, 4}, out[3] = {0, 0, 0};
  const double scalars[1] = {2.5};
  void* arrays[2] = {in, out};
  const size_t bytes[2] = {sizeof in, sizeof out};
  const uint8_t written[2] = {0, 1};
  MapArgs args{arrays, scalars, nullptr};
  args.array_count = 2;
  args.array_bytes = bytes;
  args.array_written = written;
  args.scalar_count = 1;

  double seen_scalar = 0, seen_in = 0;
  state.on_launch = [&](const Launch& l) {
    CUdeviceptr* table = at<CUdeviceptr>(l.table);
    seen_in = at<double>(table[0])[3];
    seen_scalar = at<double>(l.scalars)[0];
    at<double>(table[0])[0] = 99;  // a read-only array's device copy: never copied back
    for (int i = 0; i < 3; ++i) at<double>(table[1])[i] = 10 + i;
    *at<uint64_t>(l.failure) = (uint64_t{7} << 32) | 2;  // element 7 failed check 2
  };
  const MapOutcome o = executor->run_map(kernel, args, 300, 1, MapWrites::Deferred, {});
  EXPECT_EQ(state.ptx, kernel.ptx);
  ASSERT_EQ(state.launches.size(), 1u);
  EXPECT_EQ(state.launches[0].grid, 3u);  // 300 elements in blocks of 128 threads
  EXPECT_EQ(state.launches[0].block, 128u);
  EXPECT_EQ(state.launches[0].begin, 0);
  EXPECT_EQ(state.launches[0].end, 300);
  EXPECT_EQ(seen_in, 4.0);
  EXPECT_EQ(seen_scalar, 2.5);
  EXPECT_EQ(o.code, 3);
  EXPECT_EQ(o.element, 7);
  EXPECT_EQ(in[0], 1.0);
  EXPECT_EQ(out[0], 10.0);
  EXPECT_EQ(out[2], 12.0);
  const GpuTraffic t = gpu_traffic(*executor);
  EXPECT_EQ(t.launches, 1);
  EXPECT_EQ(t.bytes_to_device, static_cast<long long>(sizeof in + sizeof out + sizeof scalars));
  EXPECT_EQ(t.bytes_to_host, static_cast<long long>(sizeof out));

  // Again: the device memory is reused, the arrays copied in again (the host may have
  // changed them), and no check failed this time.
  const int allocations = state.allocations;
  in[3] = -4;
  state.on_launch = [&](const Launch& l) { seen_in = at<double>(at<CUdeviceptr>(l.table)[0])[3]; };
  const MapOutcome again = executor->run_map(kernel, args, 300, 1, MapWrites::Deferred, {});
  EXPECT_EQ(again.code, 0);
  EXPECT_EQ(again.element, -1);
  EXPECT_EQ(seen_in, -4.0);
  EXPECT_EQ(state.allocations, allocations);
  executor.reset();
  EXPECT_EQ(state.frees, state.allocations);  // everything freed with the executor
}

TEST_F(GpuExecutorFake, SharedBlocksWithoutDeferredWritesRunOneElementAtATimeInOrder) {
  auto executor = make_gpu_executor_over(fake_table());
  PtxKernel kernel;
  kernel.ptx = "//";
  kernel.entry = kMapEntry;
  double out[2] = {0, 0};
  void* arrays[1] = {out};
  const size_t bytes[1] = {sizeof out};
  const uint8_t written[1] = {1};
  MapArgs args{arrays, nullptr, nullptr};
  args.array_count = 1;
  args.array_bytes = bytes;
  args.array_written = written;
  executor->run_map(kernel, args, 5, 1, MapWrites::Shared, {});
  ASSERT_EQ(state.launches.size(), 5u);
  for (int e = 0; e < 5; ++e) {
    EXPECT_EQ(state.launches[e].begin, e);
    EXPECT_EQ(state.launches[e].end, e + 1);
    EXPECT_EQ(state.launches[e].grid, 1u);
  }
}

TEST_F(GpuExecutorFake, AnInterruptBeforeTheLaunchStopsIt) {
  auto executor = make_gpu_executor_over(fake_table());
  PtxKernel kernel;
  MapArgs args;
  const size_t bytes[1] = {0};
  const uint8_t written[1] = {0};
  args.array_bytes = bytes;
  args.array_written = written;
  const MapOutcome o =
      executor->run_map(kernel, args, 10, 1, MapWrites::Disjoint, [] { return true; });
  EXPECT_TRUE(o.interrupted);
  EXPECT_TRUE(state.launches.empty());
}

TEST_F(GpuExecutorFake, ACpuKernelIsRefused) {
  auto executor = make_gpu_executor_over(fake_table());
  struct CpuKernel : Kernel {
    int32_t run(const MapArgs&, ElementRange, int32_t*) const override { return 0; }
    int32_t run(const SystemArgs&) const override { return 0; }
  } cpu;
  MapArgs args;
  const size_t bytes[1] = {0};
  const uint8_t written[1] = {0};
  args.array_bytes = bytes;
  args.array_written = written;
  EXPECT_THROW(executor->run_map(cpu, args, 10, 1, MapWrites::Disjoint, {}), std::logic_error);
}

// ---- The emulation: a program's bits under `gpu` over host memory against the interpreter.

const char* kProgram = R"(
element V
  x : vector[2](float);
  y : vector[2](float);
end
element E
  k : float;
end
extern verts : set{V};
extern edges : set{E}(verts, verts);

func spring(e : E, v : (V*2)) -> (K : matrix[verts, verts](matrix[2,2](float)),
                                   f : vector[verts](vector[2](float)))
  d = v(0).x - v(1).x;
  l = sqrt(d' * d) + 0.5;
  if l > 1000.0
    error "spring too long: ", l;
  end
  s = e.k * atan2(d(1), d(0)) / l;
  K(v(0), v(0)) = s * (d * d');
  K(v(0), v(1)) = -s * (d * d');
  K(v(1), v(1)) = exp(-l) * (d * d');
  f(v(0)) = s * d;
  f(v(1)) = -s * d;
end

func move(inout v : V)
  v.y = v.y + 0.25 * v.x * v.x(1) - v.y * 0.5;
end

export func step() -> (s : float)
  K, f = map spring to edges reduce +;
  apply move to verts;
  verts.x = verts.x + 0.01 * (K * verts.y + f);
  s = verts.x' * verts.x;
end
)";

struct Outcome {
  std::vector<double> fields;
  double s = 0;
  std::string error;
  std::string stats;
};

Outcome run_program(api::ExecutorKind kind, int n, double blow_up_at = -1) {
  auto compiled = api::CompiledProgram::from_source("gpu.sim", kProgram);
  EXPECT_TRUE(compiled->ok());
  runtime::Set v("verts");
  runtime::Set e("edges", {&v, &v});
  v.add_many(n);
  v.add_field("x", runtime::FieldType{runtime::ComponentKind::Float, {2}, false});
  v.add_field("y", runtime::FieldType{runtime::ComponentKind::Float, {2}, false});
  for (int i = 0; i < n; ++i) {
    v.field(0).at<double>(i)[0] = std::sin(0.37 * i);
    v.field(0).at<double>(i)[1] = 0.3 + 0.01 * (i % 17);
    v.field(1).at<double>(i)[0] = 0.1;
  }
  std::vector<int32_t> ends;
  for (int i = 0; i + 1 < n; ++i) ends.insert(ends.end(), {i, i + 1, (7 * i) % n, i});
  e.add_edges(ends);
  e.add_field("k", runtime::FieldType{runtime::ComponentKind::Float, {}, false});
  for (int i = 0; i < e.size(); ++i) *e.field(0).at<double>(i) = 1.0 + 0.001 * i;
  if (blow_up_at >= 0) v.field(0).at<double>(static_cast<int>(blow_up_at))[0] = 1e6;
  api::EngineOptions o;
  o.executor.kind = kind;
  o.executor.threshold = 0;
  o.executor.threads = 1;
  api::Engine engine(compiled, o);
  engine.bind_set(*compiled->find_extern("verts"), v);
  engine.bind_set(*compiled->find_extern("edges"), e);
  Outcome out;
  try {
    for (int f = 0; f < 4; ++f) out.s = engine.call(*compiled->find_func("step"), {})[0].as_float();
  } catch (const interp::RuntimeError& err) {
    out.error = err.what();
  }
  std::ostringstream stats;
  engine.print_jit_stats(stats);
  out.stats = stats.str();
  out.fields.assign(v.field(0).data<double>(), v.field(0).data<double>() + 2 * n);
  out.fields.insert(out.fields.end(), v.field(1).data<double>(), v.field(1).data<double>() + 2 * n);
  return out;
}

class GpuEmulation : public ::testing::Test {
 protected:
  void SetUp() override { setenv("SIMIT_TEST_GPU_EMULATION", "1", 1); }
  void TearDown() override { unsetenv("SIMIT_TEST_GPU_EMULATION"); }
};

TEST_F(GpuEmulation, AProgramGivesTheInterpretersBits) {
  for (int n : {2, 50, 700}) {
    const Outcome interp = run_program(api::ExecutorKind::Interpreter, n);
    const Outcome gpu = run_program(api::ExecutorKind::Gpu, n);
    ASSERT_EQ(interp.error, "");
    ASSERT_EQ(gpu.error, "");
    ASSERT_EQ(interp.fields.size(), gpu.fields.size());
    EXPECT_EQ(
        std::memcmp(interp.fields.data(), gpu.fields.data(), interp.fields.size() * sizeof(double)),
        0)
        << n;
    EXPECT_EQ(std::memcmp(&interp.s, &gpu.s, sizeof gpu.s), 0) << n;
    EXPECT_TRUE(std::isfinite(gpu.s));
    // The map and the apply ran through the GPU executor.
    EXPECT_NE(gpu.stats.find("spring (line"), std::string::npos) << gpu.stats;
    EXPECT_NE(gpu.stats.find("on the GPU (emulated)"), std::string::npos) << gpu.stats;
    EXPECT_NE(gpu.stats.find("compiled for the GPU"), std::string::npos) << gpu.stats;
  }
}

TEST_F(GpuEmulation, AFailedCheckNamesTheElementAsTheInterpreterDoes) {
  const Outcome interp = run_program(api::ExecutorKind::Interpreter, 300, 123);
  const Outcome gpu = run_program(api::ExecutorKind::Gpu, 300, 123);
  ASSERT_NE(interp.error, "");
  EXPECT_EQ(gpu.error, interp.error);
}

}  // namespace
}  // namespace simit::jit::ptx
