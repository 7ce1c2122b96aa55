// The GPU executor (jit/ptx/gpu_executor.h) over host memory (the emulation: the host driver
// table and the CPU target's kernels, the gather kernel's host equivalent) giving the
// interpreter's bits for programs that assemble, apply and reduce, and failing as it fails.
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
#include "runtime/residency.h"
#include "runtime/set.h"

namespace simit::jit::ptx {
namespace {

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
  long elsewhere = 0;  // arrays whose newest copy was on the device after the last call
};

// Between frames: the host's changes to the sets (frame: the frame just run).
using Between = std::function<void(runtime::Set& verts, runtime::Set& edges, int frame)>;

Outcome run_program(api::ExecutorKind kind, int n, double blow_up_at = -1,
                    const Between& between = {}, bool host_uses_accessors = false) {
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
  o.host_uses_accessors = host_uses_accessors;
  api::Engine engine(compiled, o);
  engine.bind_set(*compiled->find_extern("verts"), v);
  engine.bind_set(*compiled->find_extern("edges"), e);
  Outcome out;
  try {
    for (int f = 0; f < 4; ++f) {
      out.s = engine.call(*compiled->find_func("step"), {})[0].as_float();
      if (between) between(v, e, f);
    }
  } catch (const interp::RuntimeError& err) {
    out.error = err.what();
  }
  out.elsewhere = runtime::residency::count();
  std::ostringstream stats;
  engine.print_jit_stats(stats);
  out.stats = stats.str();
  const runtime::Set& cv = v;  // read as the host reads (a mutable access counts as a write)
  out.fields.assign(cv.field(0).data<double>(), cv.field(0).data<double>() + 2 * n);
  out.fields.insert(out.fields.end(), cv.field(1).data<double>(),
                    cv.field(1).data<double>() + 2 * n);
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

// The device keeps its copies between calls and copies an array in only when the host's
// changed: edges.k, which only the host writes, and verts.y, which the apply writes on the
// device, changed by the host between frames, reach the next frame's kernels (a stale device
// copy would show in the bits). Without changes, the last call of the map finds k, the
// endpoint table and the pattern tables on the device already.
TEST_F(GpuEmulation, FieldsTheHostChangesBetweenCallsReachTheDevice) {
  const Between change = [](runtime::Set& verts, runtime::Set& edges, int frame) {
    if (frame == 3) return;
    for (int i = 0; i < edges.size(); i += 3)
      *edges.field(0).at<double>(i) = 0.5 + 0.125 * frame + 0.001 * i;
    if (frame == 1)
      for (int i = 0; i < verts.size(); i += 2) verts.field(1).at<double>(i)[1] = -0.5 * i;
  };
  const int n = 60;
  const Outcome interp = run_program(api::ExecutorKind::Interpreter, n, -1, change);
  const Outcome gpu = run_program(api::ExecutorKind::Gpu, n, -1, change);
  const Outcome unchanged = run_program(api::ExecutorKind::Gpu, n);
  ASSERT_EQ(interp.error, "");
  ASSERT_EQ(gpu.error, "");
  ASSERT_EQ(interp.fields.size(), gpu.fields.size());
  EXPECT_EQ(
      std::memcmp(interp.fields.data(), gpu.fields.data(), interp.fields.size() * sizeof(double)),
      0);
  EXPECT_EQ(std::memcmp(&interp.s, &gpu.s, sizeof gpu.s), 0);
  EXPECT_NE(std::memcmp(&unchanged.s, &gpu.s, sizeof gpu.s), 0);  // the changes mattered
  // --jit-stats: the map's last call found at least k (8 bytes an edge) and the endpoint
  // table (8 bytes an edge) on the device.
  const size_t at = unchanged.stats.find("last call to the device: ");
  ASSERT_NE(at, std::string::npos) << "STATS:" << unchanged.stats;
  const std::string there = unchanged.stats.substr(at);
  const size_t comma = there.find(" copied, ");
  ASSERT_NE(comma, std::string::npos) << there;
  const long long already = std::atoll(there.c_str() + comma + 9);
  const int edges = 2 * (n - 1);
  EXPECT_GE(already, 16LL * edges) << there;
}

// Residency across calls (runtime/residency.h): by default every array the device holds
// newer comes home when a call returns (a host may read through views of its own); a host
// that reads only through the accessors (a scene run) leaves them there, across calls and
// across its own writes between them, which bring them back first, and gets the same bits.
TEST_F(GpuEmulation, AHostThatReadsThroughAccessorsLeavesTheDevicesArraysThereAcrossCalls) {
  const Between change = [](runtime::Set& verts, runtime::Set&, int frame) {
    if (frame == 1)
      for (int i = 0; i < verts.size(); i += 2) verts.field(1).at<double>(i)[1] = -0.5 * i;
  };
  const int n = 60;
  const Outcome interp = run_program(api::ExecutorKind::Interpreter, n, -1, change);
  const Outcome home = run_program(api::ExecutorKind::Gpu, n, -1, change);
  const Outcome stay = run_program(api::ExecutorKind::Gpu, n, -1, change, true);
  ASSERT_EQ(home.error, "");
  ASSERT_EQ(stay.error, "");
  EXPECT_EQ(home.elsewhere, 0);
  EXPECT_GE(stay.elsewhere, 2);  // verts.x and verts.y at least
  for (const Outcome* o : {&home, &stay}) {
    ASSERT_EQ(interp.fields.size(), o->fields.size());
    EXPECT_EQ(
        std::memcmp(interp.fields.data(), o->fields.data(), interp.fields.size() * sizeof(double)),
        0);
    EXPECT_EQ(std::memcmp(&interp.s, &o->s, sizeof o->s), 0);
  }
  EXPECT_EQ(runtime::residency::count(), 0);  // the engines went, and brought them home
}

TEST_F(GpuEmulation, AFailedCheckNamesTheElementAsTheInterpreterDoes) {
  const Outcome interp = run_program(api::ExecutorKind::Interpreter, 300, 123);
  const Outcome gpu = run_program(api::ExecutorKind::Gpu, 300, 123);
  ASSERT_NE(interp.error, "");
  EXPECT_EQ(gpu.error, interp.error);
}

// A tet mesh where every tet holds vertex 0 and tets share their other vertices with their
// neighbours: vertex 0's blocks take one contribution per tet (one in place, the rest
// deferred), so the gather adds hundreds of deferred blocks into one block, in order.
const char* kFanProgram = R"(
element V
  x : vector[3](float);
end
element T
  k : float;
end
extern verts : set{V};
extern tets : set{T}(verts, verts, verts, verts);

func stiffness(t : T, v : (V*4)) -> (K : matrix[verts, verts](matrix[3,3](float)),
                                     f : vector[verts](vector[3](float)))
  for i in 0:4
    d = v(i).x - 0.5 * v(0).x;
    s = t.k / (d' * d + 0.3);
    f(v(i)) = s * d;
    for j in 0:4
      K(v(i), v(j)) = (s * sin(v(j).x(1) + 0.1)) * (d * d');
    end
  end
end

export func step() -> (s : float)
  K, f = map stiffness to tets reduce +;
  verts.x = verts.x + 1e-3 * (K * verts.x + f);
  s = verts.x' * verts.x;
end
)";

Outcome run_fan(api::ExecutorKind kind, int tets) {
  auto compiled = api::CompiledProgram::from_source("fan.sim", kFanProgram);
  EXPECT_TRUE(compiled->ok()) << compiled->compilation()->diagnostics.render_all();
  const int n = tets + 3;
  runtime::Set v("verts");
  runtime::Set t("tets", {&v, &v, &v, &v});
  v.add_many(n);
  v.add_field("x", runtime::FieldType{runtime::ComponentKind::Float, {3}, false});
  for (int i = 0; i < n; ++i)
    for (int c = 0; c < 3; ++c) v.field(0).at<double>(i)[c] = std::sin(0.7 * i + c) + 0.01 * c;
  std::vector<int32_t> ends;
  for (int i = 0; i < tets; ++i) ends.insert(ends.end(), {0, i + 1, i + 2, i + 3});
  t.add_edges(ends);
  t.add_field("k", runtime::FieldType{runtime::ComponentKind::Float, {}, false});
  for (int i = 0; i < t.size(); ++i) *t.field(0).at<double>(i) = 1.0 + 0.37 * std::cos(i);
  api::EngineOptions o;
  o.executor.kind = kind;
  o.executor.threshold = 0;
  o.executor.threads = 1;
  api::Engine engine(compiled, o);
  engine.bind_set(*compiled->find_extern("verts"), v);
  engine.bind_set(*compiled->find_extern("tets"), t);
  Outcome out;
  try {
    for (int f = 0; f < 3; ++f) out.s = engine.call(*compiled->find_func("step"), {})[0].as_float();
  } catch (const interp::RuntimeError& err) {
    out.error = err.what();
  }
  out.elsewhere = runtime::residency::count();
  std::ostringstream stats;
  engine.print_jit_stats(stats);
  out.stats = stats.str();
  out.fields.assign(v.field(0).data<double>(), v.field(0).data<double>() + 3 * n);
  return out;
}

TEST_F(GpuEmulation, ManyDeferredBlocksPerBlockGiveTheInterpretersBits) {
  const Outcome interp = run_fan(api::ExecutorKind::Interpreter, 400);
  const Outcome gpu = run_fan(api::ExecutorKind::Gpu, 400);
  ASSERT_EQ(interp.error, "");
  ASSERT_EQ(gpu.error, "");
  ASSERT_EQ(interp.fields.size(), gpu.fields.size());
  EXPECT_EQ(
      std::memcmp(interp.fields.data(), gpu.fields.data(), interp.fields.size() * sizeof(double)),
      0);
  EXPECT_EQ(std::memcmp(&interp.s, &gpu.s, sizeof gpu.s), 0);
  EXPECT_TRUE(std::isfinite(gpu.s));
  EXPECT_NE(gpu.stats.find("stiffness (line"), std::string::npos) << gpu.stats;
  EXPECT_NE(gpu.stats.find("on the GPU (emulated)"), std::string::npos) << gpu.stats;
  EXPECT_NE(gpu.stats.find("deferred blocks added on the device"), std::string::npos) << gpu.stats;
}

}  // namespace
}  // namespace simit::jit::ptx
