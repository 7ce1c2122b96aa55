// The kernel cache: compiled kernels kept in a folder and linked by a later target without
// compiling, their keys, corrupt and concurrent entries, and host calls resolved by name.
// The traces are made by hand and compiled through make_cpu_target directly.
#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <latch>
#include <random>
#include <thread>

#include "jit/ir_build.h"
#include "jit/kernel_cache.h"
#include "jit/loop_ir.h"
#include "jit/target.h"

namespace simit::jit {
namespace {

namespace fs = std::filesystem;

// A fresh empty folder, removed with everything in it at the end of the test.
struct TempFolder {
  fs::path path;
  TempFolder() {
    std::random_device rd;
    path = fs::temp_directory_path() /
           ("simit_kernel_cache_test_" + std::to_string(::getpid()) + "_" + std::to_string(rd()));
    fs::create_directories(path);
  }
  ~TempFolder() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
  std::string str() const { return path.string(); }
  // The entry files (<hex>.o), and every file.
  std::vector<fs::path> entries() const {
    std::vector<fs::path> out;
    for (const auto& f : fs::directory_iterator(path))
      if (f.path().extension() == ".o" && f.path().filename().string()[0] != '.')
        out.push_back(f.path());
    return out;
  }
  size_t files() const {
    size_t n = 0;
    for ([[maybe_unused]] const auto& f : fs::directory_iterator(path)) ++n;
    return n;
  }
};

std::unique_ptr<Target> target(const std::string& folder, void* decompose = nullptr) {
  std::string error;
  HostCalls host;
  host.decompose = decompose;
  auto t = make_cpu_target(host, folder, error);
  EXPECT_TRUE(t) << error;
  return t;
}

// ---------------------------------------------------------------------------
// A fem-like map: a tetrahedron (4 endpoints) reads its vertices' positions, forms a 12 x 12
// "stiffness" whose entries are linear in them, and adds k * K x + sin(x) into a vector
// result at its endpoints (a lane kernel). `tweak` changes one constant.

constexpr int kArity = 4, kDofs = 12;

double coef(int i, int j, int m, double tweak) {
  const double c = ((i * 31 + j * 17 + m * 7) % 23 - 11) / 8.0;
  return i == 0 && j == 0 && m == 0 ? c + tweak : c;
}

ExprRef bin(BinOp op, ExprRef a, ExprRef b) {
  return node(ExprKind::Binary, Ty::F64, static_cast<uint8_t>(op), {std::move(a), std::move(b)});
}

Trace fem_like(double tweak, const std::string& name = "force@fem.sim:10") {
  Trace t;
  t.name = name;
  t.arity = kArity;
  t.reduce = true;
  ArraySlot pos;
  pos.kind = ArraySlot::Kind::Field;
  pos.member = 1;
  pos.components = 3;
  pos.name = "x";
  ArraySlot f;
  f.kind = ArraySlot::Kind::Result;
  f.components = 3;
  f.written = true;
  f.name = "f";
  t.arrays = {pos, f};
  t.scalars = {Ty::F64};
  std::vector<ExprRef> x;
  for (int j = 0; j < kArity; ++j) {
    Expr ep;
    ep.kind = ExprKind::Endpoint;
    ep.ty = Ty::I32;
    ep.slot = j;
    const ExprRef at = make(ep);
    for (int c = 0; c < 3; ++c) {
      Expr load;
      load.kind = ExprKind::Load;
      load.slot = 0;
      load.comp = c;
      load.ops = {at};
      x.push_back(make(load));
    }
  }
  Expr k;
  k.kind = ExprKind::Scalar;
  k.slot = 0;
  const ExprRef stiffness = make(k);
  for (int i = 0; i < kDofs; ++i) {
    ExprRef sum;
    for (int j = 0; j < kDofs; ++j) {
      ExprRef kij;
      for (int m = 0; m < kDofs; ++m) {
        ExprRef term = bin(BinOp::Mul, x[m], fconst(coef(i, j, m, tweak)));
        kij = kij ? bin(BinOp::Add, kij, term) : term;
      }
      ExprRef term = bin(BinOp::Mul, kij, x[j]);
      sum = sum ? bin(BinOp::Add, sum, term) : term;
    }
    const ExprRef sine = node(ExprKind::Math, Ty::F64, static_cast<uint8_t>(MathFn::Sin), {x[i]});
    Stmt s;
    s.kind = StmtKind::Assemble;
    s.slot = 1;
    s.comp = i % 3;
    Expr ep;
    ep.kind = ExprKind::Endpoint;
    ep.ty = Ty::I32;
    ep.slot = i / 3;
    s.index = make(ep);
    s.value = bin(BinOp::Add, bin(BinOp::Mul, stiffness, sum), sine);
    t.body.push_back(std::move(s));
  }
  return t;
}

// A small mesh for the map: vertex positions and each element's endpoints.
struct Mesh {
  static constexpr int kVertices = 9, kElements = 7;
  std::vector<double> x;
  std::vector<int32_t> ends;
  double k = 0.75;
  Mesh() {
    for (int v = 0; v < kVertices; ++v)
      for (int c = 0; c < 3; ++c) x.push_back(0.1 * v + 0.03 * c * c - 0.2 * (v % 2));
    for (int e = 0; e < kElements; ++e)
      for (int j = 0; j < kArity; ++j) ends.push_back((e + 2 * j) % kVertices);
  }
};

// The map run through a kernel: the result vector.
std::vector<double> run_map(const Kernel& kernel, const Mesh& mesh) {
  std::vector<double> f(Mesh::kVertices * 3, 0.0);
  void* arrays[] = {const_cast<double*>(mesh.x.data()), f.data()};
  MapArgs args;
  args.arrays = arrays;
  args.scalars = &mesh.k;
  args.endpoints = mesh.ends.data();
  int32_t failed = -1;
  EXPECT_EQ(kernel.run(args, ElementRange{0, Mesh::kElements}, &failed), 0);
  return f;
}

// The same map computed here, operation by operation in the trace's order.
std::vector<double> reference(const Mesh& mesh, double tweak) {
  std::vector<double> f(Mesh::kVertices * 3, 0.0);
  for (int e = 0; e < Mesh::kElements; ++e) {
    double x[kDofs];
    for (int m = 0; m < kDofs; ++m) x[m] = mesh.x[mesh.ends[e * kArity + m / 3] * 3 + m % 3];
    for (int i = 0; i < kDofs; ++i) {
      double sum = 0.0;
      for (int j = 0; j < kDofs; ++j) {
        double kij = x[0] * coef(i, j, 0, tweak);
        for (int m = 1; m < kDofs; ++m) kij = kij + x[m] * coef(i, j, m, tweak);
        sum = j == 0 ? kij * x[j] : sum + kij * x[j];
      }
      double& out = f[mesh.ends[e * kArity + i / 3] * 3 + i % 3];
      out = out + (mesh.k * sum + std::sin(x[i]));
    }
  }
  return f;
}

void expect_same_bits(const std::vector<double>& a, const std::vector<double>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i)
    EXPECT_EQ(std::memcmp(&a[i], &b[i], sizeof(double)), 0) << i << ": " << a[i] << " vs " << b[i];
}

std::unique_ptr<Kernel> compile(Target& t, const Trace& trace, bool keep_ir = false) {
  std::string error;
  auto k = t.compile(trace, keep_ir, error);
  EXPECT_TRUE(k) << error;
  return k;
}

std::string read_file(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}
// s with `bytes` written over it from `at`.
std::string overwrite(std::string s, size_t at, const std::string& bytes) {
  if (at + bytes.size() <= s.size()) s.replace(at, bytes.size(), bytes);
  return s;
}
// s with one bit of byte `at` flipped.
std::string flip(std::string s, size_t at) {
  if (at >= s.size()) return s;
  const std::string flipped(1, static_cast<char>(s[at] ^ 0x10));
  return overwrite(std::move(s), at, flipped);
}
void write_file(const fs::path& p, const std::string& s) {
  std::ofstream out(p, std::ios::binary | std::ios::trunc);
  out << s;
}

// ---------------------------------------------------------------------------

TEST(KernelCache, ASecondTargetLinksTheStoredKernelAndComputesTheSameBits) {
  TempFolder dir;
  const Mesh mesh;
  const Trace trace = fem_like(0.0);
  ASSERT_EQ(verify(trace), "");
  auto first = compile(*target(dir.str()), trace);
  ASSERT_TRUE(first);
  EXPECT_FALSE(first->cached);
  EXPECT_EQ(first->lanes, 4);
  ASSERT_EQ(dir.entries().size(), 1u);
  EXPECT_EQ(dir.files(), 1u);  // no temporary file left behind

  auto second = compile(*target(dir.str()), trace);
  ASSERT_TRUE(second);
  EXPECT_TRUE(second->cached);
  EXPECT_EQ(second->lanes, first->lanes);
  EXPECT_EQ(dir.entries().size(), 1u);
  const std::vector<double> want = reference(mesh, 0.0);
  expect_same_bits(run_map(*first, mesh), want);
  expect_same_bits(run_map(*second, mesh), want);
  // Both kernels stay linked side by side; dropping one leaves the other running.
  first.reset();
  expect_same_bits(run_map(*second, mesh), want);
}

TEST(KernelCache, CompileAndLoadTimesOfAFemLikeKernel) {
  TempFolder dir;
  const Trace trace = fem_like(0.0);
  auto fresh = compile(*target(dir.str()), trace);
  auto loaded = compile(*target(dir.str()), trace);
  ASSERT_TRUE(fresh && loaded);
  ASSERT_TRUE(loaded->cached);
  std::printf(
      "fem-like kernel (%zu loop-IR nodes, %zu-byte entry): compiled in %.2f ms, "
      "loaded from the cache in %.2f ms\n",
      node_count(trace), static_cast<size_t>(fs::file_size(dir.entries().at(0))), fresh->compile_ms,
      loaded->compile_ms);
  EXPECT_GT(fresh->compile_ms, 0.0);
  EXPECT_GT(loaded->compile_ms, 0.0);
}

TEST(KernelCache, NoFolderKeepsNothingAndAnUnwritableOneIsNoErrorToTheUser) {
  const Mesh mesh;
  auto k = compile(*target(""), fem_like(0.0));
  ASSERT_TRUE(k);
  EXPECT_FALSE(k->cached);

  TempFolder dir;
  write_file(dir.path / "file", "not a folder");
  const std::string below_a_file = (dir.path / "file" / "kernels").string();
  auto a = compile(*target(below_a_file), fem_like(0.0));
  auto b = compile(*target(below_a_file), fem_like(0.0));
  ASSERT_TRUE(a && b);
  EXPECT_FALSE(a->cached);
  EXPECT_FALSE(b->cached);
  EXPECT_EQ(dir.files(), 1u);
  expect_same_bits(run_map(*b, mesh), reference(mesh, 0.0));
}

TEST(KernelCache, AFullFolderLosesItsLeastRecentlyUsedEntries) {
  TempFolder dir;
  const KernelCache cache(dir.str());
  // Five entries of 1000 object bytes, made one after another, the first used last.
  std::vector<std::string> digests;
  const auto start = fs::file_time_type::clock::now() - std::chrono::minutes(10);
  for (int i = 0; i < 5; ++i) {
    std::string d(KernelCache::kDigestBytes, static_cast<char>('a' + i));
    std::string error;
    ASSERT_TRUE(cache.store(d, {"simit_k_" + std::to_string(i), std::string(1000, 'x')}, error))
        << error;
    fs::last_write_time(cache.path_of(d), start + std::chrono::seconds(i));
    digests.push_back(d);
  }
  ASSERT_TRUE(cache.load(digests[0]));  // now the most recently used
  const uint64_t entry_bytes = fs::file_size(cache.path_of(digests[1]));
  // A temporary file a killed writer left two hours ago, and one being written now.
  write_file(dir.path / (hex_of(digests[4]) + ".o.tmp.1.2.3"), "half");
  fs::last_write_time(dir.path / (hex_of(digests[4]) + ".o.tmp.1.2.3"),
                      fs::file_time_type::clock::now() - std::chrono::hours(2));
  write_file(dir.path / (hex_of(digests[3]) + ".o.tmp.4.5.6"), "half");

  // Room for four entries: down to three quarters, three entries; the oldest two go.
  EXPECT_EQ(cache.prune(4 * entry_bytes), 2);
  EXPECT_FALSE(cache.load(digests[1]));
  EXPECT_FALSE(cache.load(digests[2]));
  EXPECT_TRUE(cache.load(digests[0]));
  EXPECT_TRUE(cache.load(digests[3]));
  EXPECT_TRUE(cache.load(digests[4]));
  EXPECT_FALSE(fs::exists(dir.path / (hex_of(digests[4]) + ".o.tmp.1.2.3")));
  EXPECT_TRUE(fs::exists(dir.path / (hex_of(digests[3]) + ".o.tmp.4.5.6")));
  // Within the limit, nothing goes.
  EXPECT_EQ(cache.prune(100 * entry_bytes), 0);
  EXPECT_EQ(dir.entries().size(), 3u);
}

TEST(KernelCache, AMissingFolderIsMadeWithItsParents) {
  TempFolder dir;
  const std::string nested = (dir.path / "a" / "b" / "kernels").string();
  compile(*target(nested), fem_like(0.0));
  EXPECT_EQ(std::distance(fs::directory_iterator(nested), fs::directory_iterator{}), 1);
  auto k = compile(*target(nested), fem_like(0.0));
  ASSERT_TRUE(k);
  EXPECT_TRUE(k->cached);
}

TEST(KernelCache, AskingForTheIrCompilesAndStillWrites) {
  TempFolder dir;
  const Mesh mesh;
  const Trace trace = fem_like(0.0);
  auto with_ir = compile(*target(dir.str()), trace, /*keep_ir=*/true);
  ASSERT_TRUE(with_ir);
  EXPECT_FALSE(with_ir->cached);
  EXPECT_NE(with_ir->llvm_ir.find("define"), std::string::npos);
  ASSERT_EQ(dir.entries().size(), 1u);
  auto again = compile(*target(dir.str()), trace, /*keep_ir=*/true);
  ASSERT_TRUE(again);
  EXPECT_FALSE(again->cached);  // the IR is printed, so compiled again
  EXPECT_FALSE(again->llvm_ir.empty());
  auto plain = compile(*target(dir.str()), trace);
  ASSERT_TRUE(plain);
  EXPECT_TRUE(plain->cached);
  expect_same_bits(run_map(*plain, mesh), run_map(*with_ir, mesh));
}

TEST(KernelCache, CorruptEntriesAreCompiledAgainAndReplaced) {
  const Mesh mesh;
  const Trace trace = fem_like(0.0);
  const std::vector<double> want = reference(mesh, 0.0);
  using Damage = std::function<std::string(std::string)>;
  const std::vector<std::pair<const char*, Damage>> damages = {
      {"empty", [](std::string) { return std::string(); }},
      {"truncated header", [](std::string s) { return s.substr(0, 20); }},
      {"truncated object", [](std::string s) { return s.substr(0, s.size() - 7); }},
      {"trailing bytes", [](std::string s) { return s + "xyz"; }},
      {"garbage",
       [](std::string s) {
         std::mt19937 rng(7);
         for (char& c : s) c = static_cast<char>(rng());
         return s;
       }},
      {"one object byte flipped (checksum)",
       [](std::string s) {
         const size_t at = s.size() - 100;
         return flip(std::move(s), at);
       }},
      {"another key's digest", [](std::string s) { return flip(std::move(s), 40); }},
      {"huge object length",
       [](std::string s) { return overwrite(std::move(s), 16, std::string(8, '\xff')); }},
      {"another file format version",
       [](std::string s) { return overwrite(std::move(s), 8, std::string(1, '\x63')); }},
  };
  for (const auto& [what, damage] : damages) {
    SCOPED_TRACE(what);
    TempFolder dir;
    compile(*target(dir.str()), trace);
    ASSERT_EQ(dir.entries().size(), 1u);
    const fs::path entry = dir.entries()[0];
    const std::string good = read_file(entry);
    write_file(entry, damage(good));
    auto k = compile(*target(dir.str()), trace);
    ASSERT_TRUE(k);
    EXPECT_FALSE(k->cached);
    expect_same_bits(run_map(*k, mesh), want);
    // Replaced by the fresh compile: whole again, and loaded by the next target.
    EXPECT_EQ(read_file(entry).size(), good.size());
    auto next = compile(*target(dir.str()), trace);
    ASSERT_TRUE(next);
    EXPECT_TRUE(next->cached);
    expect_same_bits(run_map(*next, mesh), want);
    EXPECT_EQ(dir.files(), 1u);
  }
}

TEST(KernelCache, TwoThreadsCompilingTheSameTraceLeaveOneWholeEntry) {
  const Mesh mesh;
  const Trace trace = fem_like(0.0);
  const std::vector<double> want = reference(mesh, 0.0);
  for (int round = 0; round < 3; ++round) {
    TempFolder dir;
    auto shared = target(dir.str());
    std::latch start(3);
    std::unique_ptr<Kernel> kernels[3];
    auto work = [&](int i) {
      auto own = target(dir.str());
      start.arrive_and_wait();
      std::string error;
      // Two threads on targets of their own, one on the target the first shares.
      kernels[i] = (i == 2 ? *shared : *own).compile(trace, false, error);
      EXPECT_TRUE(kernels[i]) << error;
    };
    std::thread a(work, 0), b(work, 1), c(work, 2);
    a.join();
    b.join();
    c.join();
    for (auto& k : kernels) {
      ASSERT_TRUE(k);
      expect_same_bits(run_map(*k, mesh), want);
    }
    EXPECT_EQ(dir.entries().size(), 1u);
    EXPECT_EQ(dir.files(), 1u);
    auto later = compile(*target(dir.str()), trace);
    ASSERT_TRUE(later);
    EXPECT_TRUE(later->cached);
    expect_same_bits(run_map(*later, mesh), want);
  }
}

// A device program's key names its steps as the plan lays them out (a cached dispatcher whose
// step numbers name other steps would run the wrong code): the same trace as a host kernel
// and as a device program are other code.
TEST(KernelCache, ADeviceProgramsKeyNamesItsSteps) {
  SystemTrace t;
  t.sizes = {"n"};
  t.locals = {Ty::F64};
  VectorOp scalar, pass;
  pass.kind = VectorOp::Kind::Pass;
  pass.length = 0;
  t.before = {scalar};
  SystemTrace device = t;
  device.device = true;
  const std::string host_key = kernel_key_text(t), device_key = kernel_key_text(device);
  EXPECT_EQ(host_key.find("steps"), std::string::npos);
  EXPECT_NE(device_key.find("steps"), std::string::npos) << device_key;
  EXPECT_NE(host_key, device_key);
  // Its steps by kind: a Thread (0) of one Serial part (100 + 1), then a pass without sums
  // (Each: 4).
  device.before.push_back(pass);
  EXPECT_NE(kernel_key_text(device).find("steps 0 101 4"), std::string::npos)
      << kernel_key_text(device);
}

TEST(KernelCache, KeysFollowTheCodeNotTheNamesOrLines) {
  const Trace a = fem_like(0.0), renamed = fem_like(0.0, "force@other.sim:99");
  const Trace tweaked = fem_like(0.25);
  EXPECT_EQ(kernel_key_text(a), kernel_key_text(renamed));
  EXPECT_NE(kernel_key_text(a), kernel_key_text(tweaked));
  // A constant's last bit, and the sign of a zero, are other code.
  auto with_constant = [](Trace t, double v) {
    Stmt s;
    s.kind = StmtKind::Check;
    s.error = 0;
    s.value = node(ExprKind::Compare, Ty::Bool, static_cast<uint8_t>(CmpOp::Lt),
                   {t.body[0].value, fconst(v)});
    t.errors.push_back(ErrorSite{});
    t.body.push_back(s);
    return t;
  };
  EXPECT_NE(kernel_key_text(with_constant(a, 1.0)),
            kernel_key_text(with_constant(a, std::nextafter(1.0, 2.0))));
  EXPECT_NE(kernel_key_text(with_constant(a, 0.0)), kernel_key_text(with_constant(a, -0.0)));
  // Flags the printed loop IR does not show.
  Trace f32 = a;
  f32.float32 = true;
  EXPECT_NE(kernel_key_text(a), kernel_key_text(f32));

  TempFolder dir;
  const Mesh mesh;
  auto first = compile(*target(dir.str()), a);
  auto other = compile(*target(dir.str()), tweaked);
  auto same = compile(*target(dir.str()), renamed);
  ASSERT_TRUE(first && other && same);
  EXPECT_FALSE(other->cached);
  EXPECT_TRUE(same->cached);
  EXPECT_EQ(dir.entries().size(), 2u);
  expect_same_bits(run_map(*other, mesh), reference(mesh, 0.25));
  expect_same_bits(run_map(*same, mesh), reference(mesh, 0.0));
}

// A system trace: while %1 < 10 { %0 = %0 * 1.5 + 0.25; %1 = %1 + 1 }.
SystemTrace counting_loop(double step) {
  SystemTrace t;
  t.name = "loop";
  t.locals = {Ty::F64, Ty::I32};
  t.scalars = 2;
  auto local = [](int slot, Ty ty) {
    Expr e;
    e.kind = ExprKind::Local;
    e.ty = ty;
    e.slot = slot;
    return make(e);
  };
  t.condition = node(ExprKind::Compare, Ty::Bool, static_cast<uint8_t>(CmpOp::Lt),
                     {local(1, Ty::I32), iconst(10)});
  VectorOp op;
  Stmt x;
  x.kind = StmtKind::SetLocal;
  x.slot = 0;
  x.value = bin(BinOp::Add, bin(BinOp::Mul, local(0, Ty::F64), fconst(step)), fconst(0.25));
  Stmt i;
  i.kind = StmtKind::SetLocal;
  i.slot = 1;
  i.value = node(ExprKind::Binary, Ty::I32, static_cast<uint8_t>(BinOp::Add),
                 {local(1, Ty::I32), iconst(1)});
  op.body = {x, i};
  t.body.push_back(op);
  return t;
}

TEST(KernelCache, SystemKernelsAreCachedToo) {
  TempFolder dir;
  const SystemTrace trace = counting_loop(1.5);
  ASSERT_EQ(verify(trace), "");
  std::string error;
  auto first = target(dir.str())->compile(trace, false, error);
  ASSERT_TRUE(first) << error;
  auto second = target(dir.str())->compile(trace, false, error);
  ASSERT_TRUE(second) << error;
  EXPECT_FALSE(first->cached);
  EXPECT_TRUE(second->cached);
  auto other = target(dir.str())->compile(counting_loop(1.25), false, error);
  ASSERT_TRUE(other) << error;
  EXPECT_FALSE(other->cached);
  EXPECT_EQ(dir.entries().size(), 2u);
  double want = 1.0;
  for (int i = 0; i < 10; ++i) want = want * 1.5 + 0.25;
  for (Kernel* k : {first.get(), second.get()}) {
    double scalars[2] = {1.0, 0.0};
    const char interrupt = 0;
    SystemArgs args;
    args.scalars = scalars;
    args.interrupt = &interrupt;
    EXPECT_EQ(k->run(args), 0);
    EXPECT_EQ(scalars[0], want);
    EXPECT_EQ(scalars[1], 10.0);
  }
}

// Host calls: a kernel that decomposes calls the target's HostCalls::decompose. A cached
// kernel calls the function of the target that loads it (its address is linked at load).
std::atomic<int> first_calls{0}, second_calls{0};
int32_t fake_decompose(std::atomic<int>& calls, int32_t fn, int32_t n, const double* in,
                       double* out) {
  ++calls;
  // A "projection" that doubles the matrix.
  EXPECT_EQ(fn, static_cast<int32_t>(Decomposition::ProjectSpd));
  for (int i = 0; i < n * n; ++i) out[i] = 2.0 * in[i];
  return 0;
}
extern "C" int32_t first_decompose(int32_t fn, int32_t n, int32_t, const double* in, double* out) {
  return fake_decompose(first_calls, fn, n, in, out);
}
extern "C" int32_t second_decompose(int32_t fn, int32_t n, int32_t, const double* in, double* out) {
  return fake_decompose(second_calls, fn, n, in, out);
}

// An apply: each element's 2 x 2 field is projected, and the first entry stored back.
Trace decomposing() {
  Trace t;
  t.name = "project@p.sim:1";
  t.writes_fields = true;
  ArraySlot a;
  a.kind = ArraySlot::Kind::Field;
  a.components = 4;
  a.written = true;
  t.arrays = {a};
  t.locals = {Ty::F64, Ty::F64, Ty::F64, Ty::F64};
  t.local_mutable = {false, false, false, false};
  t.errors.push_back(ErrorSite{});
  Expr element;
  element.kind = ExprKind::Element;
  element.ty = Ty::I32;
  const ExprRef e = make(element);
  Stmt d;
  d.kind = StmtKind::Decompose;
  d.fn = static_cast<int>(Decomposition::ProjectSpd);
  d.n = 2;
  d.error = 0;
  for (int c = 0; c < 4; ++c) {
    Expr load;
    load.kind = ExprKind::Load;
    load.comp = c;
    load.ops = {e};
    d.args.push_back(make(load));
  }
  d.outs = {0, 1, 2, 3};
  t.body.push_back(d);
  Stmt s;
  s.kind = StmtKind::Store;
  s.index = e;
  Expr l;
  l.kind = ExprKind::Local;
  l.slot = 0;
  s.value = make(l);
  t.body.push_back(s);
  return t;
}

TEST(KernelCache, HostCallsResolveToTheLoadingTargetsFunctions) {
  TempFolder dir;
  const Trace trace = decomposing();
  ASSERT_EQ(verify(trace), "");
  auto run = [](const Kernel& k) {
    double field[8] = {1.5, 0, 0, 1, -2.0, 0, 0, 1};
    void* arrays[] = {field};
    MapArgs args;
    args.arrays = arrays;
    int32_t failed = -1;
    EXPECT_EQ(k.run(args, ElementRange{0, 2}, &failed), 0);
    EXPECT_EQ(field[0], 3.0);
    EXPECT_EQ(field[4], -4.0);
  };
  auto first = compile(*target(dir.str(), reinterpret_cast<void*>(&first_decompose)), trace);
  ASSERT_TRUE(first);
  run(*first);
  EXPECT_EQ(first_calls.load(), 2);
  // Code that holds the host's address is kept only where it calls the function by name.
  if (dir.entries().empty()) GTEST_SKIP() << "the emitter builds the host call's address in";
  auto second = compile(*target(dir.str(), reinterpret_cast<void*>(&second_decompose)), trace);
  ASSERT_TRUE(second);
  EXPECT_TRUE(second->cached);
  run(*second);
  EXPECT_EQ(second_calls.load(), 2);
  EXPECT_EQ(first_calls.load(), 2);
}

// Another process (this test binary again, other addresses under ASLR) links what this one
// stored: the fem-like map, the system loop and, where the emitter calls the host by name,
// the decomposing apply, whose call then reaches the other process's function.
constexpr const char* kChildFolder = "SIMIT_KERNEL_CACHE_TEST_FOLDER";

TEST(KernelCache, AnotherProcessLinksTheStoredKernels) {
  TempFolder dir;
  compile(*target(dir.str()), fem_like(0.0));
  std::string error;
  ASSERT_TRUE(target(dir.str())->compile(counting_loop(1.5), false, error)) << error;
  compile(*target(dir.str(), reinterpret_cast<void*>(&first_decompose)), decomposing());
  const size_t stored = dir.entries().size();
  ASSERT_GE(stored, 2u);
  const std::string self = fs::read_symlink("/proc/self/exe").string();
  const std::string command = kChildFolder + ("=" + dir.str()) + " " + self +
                              " --gtest_filter=KernelCache.ChildLinksTheStoredKernels > " +
                              (dir.path / "child.log").string() + " 2>&1";
  const int status = std::system(command.c_str());
  EXPECT_EQ(status, 0) << read_file(dir.path / "child.log");
  EXPECT_NE(read_file(dir.path / "child.log").find("[  PASSED  ] 1 test"), std::string::npos)
      << read_file(dir.path / "child.log");
  EXPECT_EQ(dir.entries().size(), stored);  // nothing compiled again
}

// The child's half: run only by the test above, in a process of its own.
TEST(KernelCache, ChildLinksTheStoredKernels) {
  const char* folder = std::getenv(kChildFolder);
  if (!folder) GTEST_SKIP() << "the child half of AnotherProcessLinksTheStoredKernels";
  const Mesh mesh;
  auto map = compile(*target(folder), fem_like(0.0));
  ASSERT_TRUE(map);
  EXPECT_TRUE(map->cached);
  expect_same_bits(run_map(*map, mesh), reference(mesh, 0.0));
  std::string error;
  auto loop = target(folder)->compile(counting_loop(1.5), false, error);
  ASSERT_TRUE(loop) << error;
  EXPECT_TRUE(loop->cached);
  double scalars[2] = {1.0, 0.0};
  const char interrupt = 0;
  SystemArgs args;
  args.scalars = scalars;
  args.interrupt = &interrupt;
  EXPECT_EQ(loop->run(args), 0);
  EXPECT_EQ(scalars[1], 10.0);
  auto apply = compile(*target(folder, reinterpret_cast<void*>(&second_decompose)), decomposing());
  ASSERT_TRUE(apply);
  // Stored where the emitter calls the host by name (then the three entries).
  size_t entries = 0;
  for (const auto& f : fs::directory_iterator(folder)) entries += f.path().extension() == ".o";
  if (entries == 3) {
    EXPECT_TRUE(apply->cached);
  }
  double field[4] = {1.5, 0, 0, 1};
  void* arrays[] = {field};
  MapArgs margs;
  margs.arrays = arrays;
  int32_t failed = -1;
  EXPECT_EQ(apply->run(margs, ElementRange{0, 1}, &failed), 0);
  EXPECT_EQ(field[0], 3.0);
  EXPECT_EQ(second_calls.load(), 1);
  EXPECT_EQ(first_calls.load(), 0);
}

}  // namespace
}  // namespace simit::jit
