// The GPU executor's residency (jit/ptx/gpu_executor.h) against the fake driver table
// (gpu_fake_driver.h): an array is copied to the device only when its host copy changed since
// the device last had it (by the stamps of jit/array_stamps.h, bound as the trace controller
// binds them), a result is zeroed on the device, a written field comes back after each call
// and is not copied in again until the host changes it; a field marked a runtime array
// (MapArgs::array_resident) stays on the device until the host touches it
// (runtime/residency.h).
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <vector>

#include "gpu_fake_driver.h"
#include "jit/array_stamps.h"
#include "jit/ptx/gpu_executor.h"
#include "runtime/residency.h"
#include "runtime/set.h"

namespace simit::jit::ptx {
namespace {

using namespace fake_gpu;

// A map over `edges` (4 edges of `verts`, 5 vertices) reading the vertex field x (two
// components) and the edge field k, reading and writing the vertex field y, assembling the
// result r (one value per vertex), with a pattern table and a vector argument. Bound as the
// trace controller binds a map on the GPU (site_kernel.cpp): a field's "in" stamp before the
// call's own mutable access, its "out" stamp after every access.
struct Scene {
  runtime::Set verts{"verts"};
  runtime::Set edges{"edges", {&verts, &verts}};
  std::vector<double> r = std::vector<double>(5, 0.0);
  std::vector<int32_t> table = {0, 1, 2, 3, 4, 0, 1, 2};
  std::vector<double> vec = {0.5, 1.5, 2.5};
  double scalar = 3.0;

  Scene() {
    verts.add_many(5);
    verts.add_field("x", runtime::FieldType{runtime::ComponentKind::Float, {2}, false});
    verts.add_field("y", runtime::FieldType{runtime::ComponentKind::Float, {}, false});
    edges.add_edges(std::vector<int32_t>{0, 1, 1, 2, 2, 3, 3, 4});
    edges.add_field("k", runtime::FieldType{runtime::ComponentKind::Float, {}, false});
    for (int i = 0; i < 5; ++i) verts.field(0).at<double>(i)[0] = 1.0 + i;
    for (int i = 0; i < 4; ++i) *edges.field(0).at<double>(i) = 0.25 * (i + 1);
  }

  // The slots, in this order.
  enum Slot { X, K, Y, R, Table, Vec, Slots };
  std::vector<void*> arrays = std::vector<void*>(Slots);
  std::vector<size_t> bytes = std::vector<size_t>(Slots);
  std::vector<uint8_t> written = {0, 0, 1, 1, 0, 0};
  std::vector<uint64_t> in = std::vector<uint64_t>(Slots), out = std::vector<uint64_t>(Slots);
  std::vector<ArrayFill> fill = {ArrayFill::Copy, ArrayFill::Copy, ArrayFill::Copy,
                                 ArrayFill::Zero, ArrayFill::Copy, ArrayFill::Copy};
  // Whether the fields are bound as runtime arrays the device may keep (the raw accessors,
  // MapArgs::array_resident), as the controller binds them for the GPU.
  bool lazy = false;
  std::vector<uint8_t> resident = {1, 1, 1, 0, 0, 0};

  MapArgs bind() {
    in[X] = field_stamp(verts, 0);
    in[K] = field_stamp(edges, 0);
    in[Y] = field_stamp(verts, 1);
    in[R] = in[Vec] = 0;
    in[Table] = stamp(StampKind::Pattern, {77});
    if (lazy) {
      arrays[Y] = verts.field(1).raw_bytes();  // for writing: counts as a write
      arrays[X] = const_cast<std::byte*>(std::as_const(verts).field(0).raw_bytes());
      arrays[K] = const_cast<std::byte*>(std::as_const(edges).field(0).raw_bytes());
    } else {
      arrays[Y] = verts.field(1).bytes();  // for writing: counts as a write
      arrays[X] = const_cast<std::byte*>(std::as_const(verts).field(0).bytes());
      arrays[K] = const_cast<std::byte*>(std::as_const(edges).field(0).bytes());
    }
    arrays[R] = r.data();
    arrays[Table] = table.data();
    arrays[Vec] = vec.data();
    bytes = {verts.size() * 2 * sizeof(double), edges.size() * sizeof(double),
             verts.size() * sizeof(double),     r.size() * sizeof(double),
             table.size() * sizeof(int32_t),    vec.size() * sizeof(double)};
    out = in;
    out[X] = field_stamp(verts, 0);
    out[Y] = field_stamp(verts, 1);
    MapArgs args{arrays.data(), &scalar, edges.endpoints()};
    args.array_count = Slots;
    args.array_bytes = bytes.data();
    args.array_written = written.data();
    args.scalar_count = 1;
    args.arity = 2;
    args.array_version_in = in.data();
    args.array_version_out = out.data();
    args.array_fill = fill.data();
    args.endpoints_version = endpoints_stamp(edges);
    if (lazy) args.array_resident = resident.data();
    return args;
  }
};

// What the device copies held when the kernel started.
struct Seen {
  std::vector<double> x, k, y, r;
};

class GpuResidency : public GpuExecutorFake {
 protected:
  // The kernel: y += 1 and r = y (before) + x(0) at every vertex, on the device copies.
  void SetUp() override {
    GpuExecutorFake::SetUp();
    kernel.ptx = "//";
    kernel.entry = kMapEntry;
    state.on_launch = [this](const Launch& l) {
      const CUdeviceptr* table = at<CUdeviceptr>(l.table);
      const double* x = at<double>(table[Scene::X]);
      const double* k = at<double>(table[Scene::K]);
      double* y = at<double>(table[Scene::Y]);
      double* r = at<double>(table[Scene::R]);
      seen.x.assign(x, x + 10);
      seen.k.assign(k, k + 4);
      seen.y.assign(y, y + 5);
      seen.r.assign(r, r + 5);
      for (int i = 0; i < 5; ++i) {
        r[i] = y[i] + x[2 * i];
        y[i] += 1.0;
      }
    };
  }
  // One call; the fake's and the executor's copies during it.
  struct Call {
    long long to_device = 0, to_host = 0, zeroed = 0;  // the fake's
    GpuTraffic traffic;                                // the executor's, this call's
  };
  Call call(Executor& executor, Scene& s) {
    const Fake before = state;
    const GpuTraffic t0 = gpu_traffic(executor);
    const MapOutcome o = executor.run_map(kernel, s.bind(), 4, 1, MapWrites::Disjoint, {});
    EXPECT_EQ(o.code, 0);
    const GpuTraffic t1 = gpu_traffic(executor);
    Call c;
    c.to_device = state.to_device - before.to_device;
    c.to_host = state.to_host - before.to_host;
    c.zeroed = state.zeroed - before.zeroed;
    c.traffic.uploads = t1.uploads - t0.uploads;
    c.traffic.uploads_skipped = t1.uploads_skipped - t0.uploads_skipped;
    c.traffic.bytes_to_device = t1.bytes_to_device - t0.bytes_to_device;
    c.traffic.bytes_skipped = t1.bytes_skipped - t0.bytes_skipped;
    c.traffic.bytes_to_host = t1.bytes_to_host - t0.bytes_to_host;
    c.traffic.zeroed = t1.zeroed - t0.zeroed;
    c.traffic.bytes_zeroed = t1.bytes_zeroed - t0.bytes_zeroed;
    return c;
  }
  PtxKernel kernel;
  Seen seen;
};

// The sizes of the scene's arrays, from its shape: 5 vertices, 4 edges of 2 endpoints.
constexpr long long kX = 5 * 2 * 8, kK = 4 * 8, kY = 5 * 8, kR = 5 * 8, kTable = 8 * 4,
                    kVec = 3 * 8, kEnds = 4 * 2 * 4, kScalars = 8;
// Besides the arguments, each launch copies in its pointer table (6 pointers) and failure
// word, and copies the failure word back.
constexpr long long kLaunchIn = 6 * 8 + 8, kLaunchOut = 8;

TEST_F(GpuResidency, ASecondCallCopiesInOnlyWhatChangedAndZeroesTheResult) {
  auto executor = make_gpu_executor_over(fake_table());
  Scene s;
  // First call: everything in but the result, which is zeroed on the device; y and r back.
  Call c = call(*executor, s);
  EXPECT_EQ(c.traffic.bytes_to_device, kX + kK + kY + kTable + kVec + kEnds + kScalars);
  EXPECT_EQ(c.traffic.uploads, 7);
  EXPECT_EQ(c.traffic.uploads_skipped, 0);
  EXPECT_EQ(c.traffic.bytes_zeroed, kR);
  EXPECT_EQ(c.zeroed, kR);
  EXPECT_EQ(c.to_device, c.traffic.bytes_to_device + kLaunchIn);
  EXPECT_EQ(c.traffic.bytes_to_host, kY + kR);
  EXPECT_EQ(c.to_host, kY + kR + kLaunchOut);
  EXPECT_EQ(seen.x[2], 2.0);
  EXPECT_EQ(seen.k[3], 1.0);
  for (int i = 0; i < 5; ++i) EXPECT_EQ(*std::as_const(s.verts).field(1).at<double>(i), 1.0);

  // Second call, nothing changed on the host: only what has no stamp (the vector argument,
  // the scalars) comes in; x, k, y (written by the last call and copied back), the table
  // and the endpoints are on the device already. The result is zeroed there, not copied:
  // the host's copy (here, against the contract, not zero) never reaches the device.
  std::fill(s.r.begin(), s.r.end(), std::numeric_limits<double>::quiet_NaN());
  c = call(*executor, s);
  EXPECT_EQ(c.traffic.bytes_to_device, kVec + kScalars);
  EXPECT_EQ(c.traffic.uploads, 2);
  EXPECT_EQ(c.traffic.uploads_skipped, 5);
  EXPECT_EQ(c.traffic.bytes_skipped, kX + kK + kY + kTable + kEnds);
  EXPECT_EQ(c.zeroed, kR);
  EXPECT_EQ(c.to_device, kVec + kScalars + kLaunchIn);
  EXPECT_EQ(c.to_host, kY + kR + kLaunchOut);  // the written field back, as after every call
  for (double r : seen.r) EXPECT_TRUE(r == 0.0 && !std::signbit(r));
  for (double y : seen.y) EXPECT_EQ(y, 1.0);  // the device's copy of y was current
  for (int i = 0; i < 5; ++i) EXPECT_EQ(*std::as_const(s.verts).field(1).at<double>(i), 2.0);
  EXPECT_EQ(s.r[1], 1.0 + 2.0);

  // The host writes x through the API (its write version counts it): x alone comes in
  // again, and the kernel sees the new value.
  s.verts.field(0).at<double>(1)[0] = 40.0;
  c = call(*executor, s);
  EXPECT_EQ(c.traffic.bytes_to_device, kX + kVec + kScalars);
  EXPECT_EQ(c.traffic.bytes_skipped, kK + kY + kTable + kEnds);
  EXPECT_EQ(seen.x[2], 40.0);
  EXPECT_EQ(s.r[1], 2.0 + 40.0);

  // The host writes y, which the device wrote last: y comes in again, and the kernel adds to
  // the host's value.
  *s.verts.field(1).at<double>(3) = 100.0;
  c = call(*executor, s);
  EXPECT_EQ(c.traffic.bytes_to_device, kY + kVec + kScalars);
  EXPECT_EQ(c.traffic.bytes_skipped, kX + kK + kTable + kEnds);
  EXPECT_EQ(seen.y[3], 100.0);
  EXPECT_EQ(*std::as_const(s.verts).field(1).at<double>(3), 101.0);
  EXPECT_EQ(*std::as_const(s.verts).field(1).at<double>(2), 4.0);

  // The host writes k; and the edges grow (a new endpoint table: its topology changed).
  *s.edges.field(0).at<double>(0) = -1.0;
  c = call(*executor, s);
  EXPECT_EQ(c.traffic.bytes_to_device, kK + kVec + kScalars);
  EXPECT_EQ(seen.k[0], -1.0);
  s.edges.add_edges(std::vector<int32_t>{4, 0});
  c = call(*executor, s);
  // k grew with the set (its write version counts that); the endpoints: 4 edges' worth is
  // what a 4-element call copies.
  EXPECT_EQ(c.traffic.bytes_to_device, kK + 8 + kEnds + kVec + kScalars);
  EXPECT_EQ(c.traffic.bytes_skipped, kX + kY + kTable);
  executor.reset();
  EXPECT_EQ(state.frees, state.allocations);
}

TEST_F(GpuResidency, AnArrayAtANewAddressOrSizeIsCopiedWhateverItsStamp) {
  auto executor = make_gpu_executor_over(fake_table());
  Scene s;
  call(*executor, s);
  // The table's stamp is fixed in Scene::bind; a longer table is a fresh device copy all
  // the same (a mirror holds one address and size).
  s.table.assign(16, 3);
  Call c = call(*executor, s);
  EXPECT_EQ(c.traffic.bytes_to_device, 16 * 4 + kVec + kScalars);
  EXPECT_EQ(c.traffic.bytes_skipped, kX + kK + kY + kEnds);
}

TEST_F(GpuResidency, WithoutStampsEveryArrayIsCopiedEveryCall) {
  auto executor = make_gpu_executor_over(fake_table());
  Scene s;
  call(*executor, s);
  MapArgs args = s.bind();
  args.array_version_in = args.array_version_out = nullptr;
  args.array_fill = nullptr;
  args.endpoints_version = 0;
  const GpuTraffic t0 = gpu_traffic(*executor);
  executor->run_map(kernel, args, 4, 1, MapWrites::Disjoint, {});
  const GpuTraffic t1 = gpu_traffic(*executor);
  EXPECT_EQ(t1.bytes_to_device - t0.bytes_to_device,
            kX + kK + kY + kR + kTable + kVec + kEnds + kScalars);
  EXPECT_EQ(t1.uploads_skipped, t0.uploads_skipped);
  EXPECT_EQ(t1.bytes_zeroed, t0.bytes_zeroed);
}

TEST_F(GpuResidency, AWrittenFieldStaysOnTheDeviceUntilTheHostTouchesIt) {
  namespace residency = runtime::residency;
  auto executor = make_gpu_executor_over(fake_table());
  Scene s;
  s.lazy = true;
  // y stays on the device; only the result (not a runtime array here) comes back.
  Call c = call(*executor, s);
  EXPECT_EQ(c.traffic.bytes_to_host, kR);
  EXPECT_EQ(c.to_host, kR + kLaunchOut);
  EXPECT_EQ(residency::count(), 1);
  EXPECT_EQ(gpu_traffic(*executor).kept_on_device, 1);
  const auto y_raw = [&s] {
    return reinterpret_cast<const double*>(std::as_const(s.verts).field(1).raw_bytes());
  };
  EXPECT_EQ(y_raw()[0], 0.0);  // the host's copy is still the old one

  // Second call: y is not copied in, the device's copy being the newest.
  c = call(*executor, s);
  EXPECT_EQ(c.traffic.bytes_to_device, kVec + kScalars);
  EXPECT_EQ(c.to_host, kR + kLaunchOut);
  for (double y : seen.y) EXPECT_EQ(y, 1.0);
  EXPECT_EQ(gpu_traffic(*executor).uploads_resident, 1);

  // The host reads y: brought back once, with the device's values.
  Fake before = state;
  EXPECT_EQ(*std::as_const(s.verts).field(1).at<double>(2), 2.0);
  EXPECT_EQ(*std::as_const(s.verts).field(1).at<double>(4), 2.0);
  EXPECT_EQ(state.to_host - before.to_host, kY);
  EXPECT_EQ(gpu_traffic(*executor).brought_back, 1);
  EXPECT_EQ(residency::count(), 0);

  // Read, not written: the device's copy is the host's, and is not copied in (its stamp).
  c = call(*executor, s);
  EXPECT_EQ(c.traffic.bytes_to_device, kVec + kScalars);
  for (double y : seen.y) EXPECT_EQ(y, 2.0);

  // The host writes one value of y: brought back first, so that the others are the device's;
  // then copied in whole.
  *s.verts.field(1).at<double>(0) = 50.0;
  EXPECT_EQ(*std::as_const(s.verts).field(1).at<double>(1), 3.0);
  c = call(*executor, s);
  EXPECT_EQ(c.traffic.bytes_to_device, kY + kVec + kScalars);
  EXPECT_EQ(seen.y[0], 50.0);
  EXPECT_EQ(seen.y[1], 3.0);

  // The executor goes: what only the device held comes home.
  before = state;
  executor.reset();
  EXPECT_EQ(residency::count(), 0);
  EXPECT_EQ(state.to_host - before.to_host, kY);
  EXPECT_EQ(y_raw()[0], 51.0);
  EXPECT_EQ(y_raw()[1], 4.0);
  EXPECT_EQ(state.frees, state.allocations);
}

TEST_F(GpuResidency, AFieldFreedWhileOnTheDeviceIsDroppedNotCopiedBack) {
  namespace residency = runtime::residency;
  auto executor = make_gpu_executor_over(fake_table());
  auto s = std::make_unique<Scene>();
  s->lazy = true;
  call(*executor, *s);
  EXPECT_EQ(residency::count(), 1);
  const Fake before = state;
  s.reset();
  EXPECT_EQ(residency::count(), 0);
  EXPECT_EQ(state.to_host, before.to_host);
  EXPECT_EQ(gpu_traffic(*executor).dropped, 1);
  EXPECT_EQ(gpu_traffic(*executor).brought_back, 0);
}

TEST_F(GpuResidency, ADriverTableWithoutMemorySetsIsRefused) {
  DriverTable t = fake_table();
  t.cuMemsetD32 = nullptr;
  EXPECT_THROW(make_gpu_executor_over(t), std::invalid_argument);
  t = fake_table();
  t.cuMemsetD2D32 = nullptr;
  EXPECT_THROW(make_gpu_executor_over(t), std::invalid_argument);
}

// The stamps themselves: a field's changes with every mutable access and differs between
// fields and sets; a pinned set's fields have none; a pattern's number is its own for good.
TEST(ArrayStamps, NameContentsForGood) {
  runtime::Set a("a"), b("b");
  for (runtime::Set* s : {&a, &b}) {
    s->add_many(3);
    s->add_field("u", runtime::FieldType{runtime::ComponentKind::Float, {}, false});
    s->add_field("w", runtime::FieldType{runtime::ComponentKind::Float, {}, false});
  }
  const uint64_t u = field_stamp(a, 0);
  EXPECT_NE(u, 0u);
  EXPECT_EQ(field_stamp(a, 0), u);
  EXPECT_NE(field_stamp(a, 1), u);
  EXPECT_NE(field_stamp(b, 0), u);  // the same field number and version in another set
  std::as_const(a).field(0).bytes();
  EXPECT_EQ(field_stamp(a, 0), u);  // a read
  a.field(0).bytes();
  EXPECT_NE(field_stamp(a, 0), u);  // a mutable access
  a.pin_fields();
  EXPECT_EQ(field_stamp(a, 0), 0u);

  runtime::Set e("e", {&b, &b});
  e.add_edges(std::vector<int32_t>{0, 1});
  const uint64_t ends = endpoints_stamp(e);
  EXPECT_EQ(endpoints_stamp(e), ends);
  e.add_edges(std::vector<int32_t>{1, 2});
  EXPECT_NE(endpoints_stamp(e), ends);

  runtime::PatternPtr p = runtime::MatrixPattern::assembled(e, b, b);
  const uint64_t n = pattern_number(p);
  EXPECT_EQ(pattern_number(p), n);
  runtime::PatternPtr q = runtime::MatrixPattern::assembled(e, b, b);
  EXPECT_NE(pattern_number(q), n);
  p.reset();
  p = runtime::MatrixPattern::assembled(e, b, b);  // perhaps at the freed one's address
  EXPECT_NE(pattern_number(p), n);
  EXPECT_NE(stamp(StampKind::Pattern, {n}), stamp(StampKind::Split, {n}));
}

}  // namespace
}  // namespace simit::jit::ptx
