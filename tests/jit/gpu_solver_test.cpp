// Solver loops on the GPU as device programs (jit/device_program.h), emulated (the host
// driver table and the CPU target's step functions): a CG written in Simit, with a branch in
// its loop, an error statement and sets whose sums have one chunk, a part of one, or many,
// gives the interpreter's bits and iteration count; the loop's error statement is handed
// back to the interpreter, which reports it in its own words.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <sstream>
#include <string>
#include <vector>

#include "api/compiled_program.h"
#include "api/engine.h"
#include "interp/runtime_error.h"
#include "jit/device_program.h"
#include "runtime/set.h"

namespace simit::jit {
namespace {

const char* kProgram = R"(
element V
  x : vector[3](float);
end
element E
  k : float;
end
extern verts : set{V};
extern edges : set{E}(verts, verts);

func spring(e : E, v : (V*2)) -> K : matrix[verts, verts](matrix[3,3](float))
  d = v(0).x - v(1).x;
  s = e.k / (d' * d + 1.0);
  one = [1.0, 0.0, 0.0; 0.0, 1.0, 0.0; 0.0, 0.0, 1.0];
  K(v(0), v(0)) = s * (d * d') + one;
  K(v(0), v(1)) = -s * (d * d');
  K(v(1), v(0)) = -s * (d * d');
  K(v(1), v(1)) = s * (d * d') + one;
end

export func step(limit : int) -> (iterations : int, residual : float, odd : float)
  A = map spring to edges reduce +;
  b = 2.0 * verts.x;
  var x = 0.0 * b;
  var r = b - A * x;
  var p = r;
  var rr = r' * r;
  while (rr > 1e-24) and (iterations < 200)
    Ap = A * p;
    alpha = rr / (p' * Ap);
    x = x + alpha * p;
    r = r - alpha * Ap;
    rr_new = r' * r;
    p = r + (rr_new / rr) * p;
    rr = rr_new;
    if mod(iterations, 2) == 1
      odd = odd + x' * x;
    end
    iterations = iterations + 1;
    if iterations > limit
      error "too many iterations: ", iterations;
    end
  end
  residual = sqrt(rr);
  verts.x = x;
end
)";

struct Outcome {
  std::vector<double> x;
  int iterations = 0;
  double residual = 0, odd = 0;
  std::string error;
  std::string stats;
};

Outcome run(api::ExecutorKind kind, int n, int limit) {
  auto compiled = api::CompiledProgram::from_source("cg.sim", kProgram);
  EXPECT_TRUE(compiled->ok()) << compiled->compilation()->diagnostics.render_all();
  runtime::Set v("verts");
  runtime::Set e("edges", {&v, &v});
  v.add_many(n);
  v.add_field("x", runtime::FieldType{runtime::ComponentKind::Float, {3}, false});
  for (int i = 0; i < n; ++i)
    for (int c = 0; c < 3; ++c) v.field(0).at<double>(i)[c] = std::sin(0.37 * i + c);
  std::vector<int32_t> ends;
  for (int i = 0; i + 1 < n; ++i) ends.insert(ends.end(), {i, i + 1, (7 * i + 3) % n, i});
  e.add_edges(ends);
  e.add_field("k", runtime::FieldType{runtime::ComponentKind::Float, {}, false});
  for (int i = 0; i < e.size(); ++i) *e.field(0).at<double>(i) = 2.0 + std::cos(0.1 * i);
  api::EngineOptions o;
  o.executor.kind = kind;
  o.executor.threshold = 0;
  o.executor.threads = 1;
  api::Engine engine(compiled, o);
  engine.bind_set(*compiled->find_extern("verts"), v);
  engine.bind_set(*compiled->find_extern("edges"), e);
  Outcome out;
  try {
    for (int f = 0; f < 2; ++f) {
      auto results = engine.call(*compiled->find_func("step"), {interp::Value::of_int(limit)});
      out.iterations = results[0].as_int();
      out.residual = results[1].as_float();
      out.odd = results[2].as_float();
    }
  } catch (const interp::RuntimeError& err) {
    out.error = err.what();
  }
  std::ostringstream stats;
  engine.print_jit_stats(stats);
  out.stats = stats.str();
  const runtime::Set& cv = v;
  out.x.assign(cv.field(0).data<double>(), cv.field(0).data<double>() + 3 * n);
  return out;
}

class GpuSolver : public ::testing::Test {
 protected:
  void SetUp() override { setenv("SIMIT_TEST_GPU_EMULATION", "1", 1); }
  void TearDown() override { unsetenv("SIMIT_TEST_GPU_EMULATION"); }
};

bool same(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

// 5 vertices: a sum of 5 elements (the tree alone); 300: two chunks, the second partial;
// 1100: five chunks (and over 1024 components, more than one block of threads).
TEST_F(GpuSolver, ACgLoopGivesTheInterpretersBitsAndIterationCount) {
  for (int n : {5, 300, 1100}) {
    const Outcome interp = run(api::ExecutorKind::Interpreter, n, 1000);
    const Outcome gpu = run(api::ExecutorKind::Gpu, n, 1000);
    ASSERT_EQ(interp.error, "") << n;
    ASSERT_EQ(gpu.error, "") << n;
    EXPECT_GT(interp.iterations, 3) << n;
    EXPECT_EQ(gpu.iterations, interp.iterations) << n;
    EXPECT_TRUE(same(gpu.residual, interp.residual)) << n << ": " << gpu.residual;
    EXPECT_TRUE(same(gpu.odd, interp.odd)) << n << ": " << gpu.odd;
    EXPECT_GT(interp.odd, 0.0) << n;  // the branch ran
    ASSERT_EQ(gpu.x.size(), interp.x.size());
    EXPECT_EQ(std::memcmp(gpu.x.data(), interp.x.data(), gpu.x.size() * sizeof(double)), 0) << n;
    // The loop ran as a device program.
    EXPECT_NE(gpu.stats.find("statements (lines"), std::string::npos) << gpu.stats;
    const size_t loop = gpu.stats.find("statements (lines");
    const std::string line = gpu.stats.substr(loop, gpu.stats.find('\n', loop) - loop);
    EXPECT_NE(line.find("compiled for the GPU"), std::string::npos) << gpu.stats;
    EXPECT_NE(gpu.stats.find("on the GPU (emulated)", loop), std::string::npos) << gpu.stats;
  }
}

// The loop reaches its error statement on the device: the call is put back and run by the
// interpreter, which stops with its own message; the GPU run's message is the same.
TEST_F(GpuSolver, AnErrorStatementInTheLoopIsReportedAsTheInterpreterReportsIt) {
  const Outcome interp = run(api::ExecutorKind::Interpreter, 300, 4);
  const Outcome gpu = run(api::ExecutorKind::Gpu, 300, 4);
  ASSERT_NE(interp.error, "");
  EXPECT_NE(interp.error.find("too many iterations: 5"), std::string::npos) << interp.error;
  EXPECT_EQ(gpu.error, interp.error);
  EXPECT_NE(gpu.stats.find("reached an error statement and ran again interpreted"),
            std::string::npos)
      << gpu.stats;
}

// The steps a device program is cut into, and their units: a sum over 3-component elements
// (the CG's inner products of vectors of blocks) takes 32 lanes per chunk of 256 elements.
TEST(DeviceProgram, ASumIsLanesTreeAndCombineWithTheContractsChunks) {
  SystemTrace t;
  t.scalars = 1;
  t.locals = {Ty::F64, Ty::F64};
  t.sizes = {"components of x"};
  VectorOp pass;
  pass.kind = VectorOp::Kind::Pass;
  pass.length = 0;
  pass.group = 3;
  pass.sums = {1};
  VectorOp scalar;
  t.before = {scalar, pass};
  DeviceProgram p = plan_device_program(t);
  ASSERT_EQ(p.before.size(), 4u);
  EXPECT_EQ(p.before[0].kind, DeviceStep::Kind::Thread);
  ASSERT_EQ(p.before[0].parts.size(), 1u);
  EXPECT_EQ(p.before[0].parts[0].kind, DeviceStep::Kind::Serial);
  EXPECT_EQ(p.before[1].kind, DeviceStep::Kind::Lanes);
  EXPECT_EQ(p.before[2].kind, DeviceStep::Kind::Tree);
  EXPECT_EQ(p.before[3].kind, DeviceStep::Kind::Thread);
  ASSERT_EQ(p.before[3].parts.size(), 1u);
  EXPECT_EQ(p.before[3].parts[0].kind, DeviceStep::Kind::Combine);
  EXPECT_FALSE(p.has_loop);
  // 3 * 600 components: 600 elements, three chunks (256, 256, 88).
  const std::vector<int64_t> sizes = {1800};
  EXPECT_EQ(p.units(p.before[0], sizes), 1);
  EXPECT_EQ(p.units(p.before[1], sizes), 3 * 32);
  EXPECT_EQ(p.units(p.before[2], sizes), 3);
  EXPECT_EQ(p.units(p.before[3], sizes), 1);
  EXPECT_EQ(p.lane_doubles(sizes), 3 * 32);
  EXPECT_EQ(p.partial_doubles(sizes), 3);
  EXPECT_EQ(p.context_words(), kContextHead + 2);
  EXPECT_EQ(device_refusal(t), "");
  // A pass that sets a program scalar other than its sums could not run its units apart.
  Stmt set;
  set.kind = StmtKind::SetLocal;
  set.slot = 0;
  Expr one;
  one.f = 1.0;
  set.value = std::make_shared<const Expr>(one);
  t.before[1].body.push_back(set);
  EXPECT_EQ(device_refusal(t), "a pass or product sets a program scalar");
}

// The loop rotated: the condition shares a launch with the one-thread work before and after
// it. A body that starts by setting temporaries (a CG's sums set to zero) has that work run
// after the condition, for the next iteration; one that starts by setting a program scalar
// keeps it in place, so that an interrupt between two batches finds whole iterations.
TEST(DeviceProgram, TheConditionSharesALaunchWithTheOneThreadWorkAroundIt) {
  SystemTrace t;
  t.scalars = 1;  // %0: a program scalar; %1: a temporary
  t.locals = {Ty::F64, Ty::F64};
  t.sizes = {"n"};
  Expr truth;
  truth.ty = Ty::Bool;
  truth.i = 1;
  t.condition = std::make_shared<const Expr>(truth);
  auto setting = [](int local) {
    VectorOp op;
    Stmt set;
    set.kind = StmtKind::SetLocal;
    set.slot = local;
    Expr zero;
    set.value = std::make_shared<const Expr>(zero);
    op.body.push_back(set);
    return op;
  };
  VectorOp pass;
  pass.kind = VectorOp::Kind::Pass;
  pass.length = 0;
  pass.sums = {1};
  t.body = {setting(1), pass, setting(0)};
  DeviceProgram p = plan_device_program(t);
  using K = DeviceStep::Kind;
  auto kinds = [](const DeviceStep& s) {
    std::vector<K> out;
    for (const DeviceStep& part : s.parts) out.push_back(part.kind);
    return out;
  };
  ASSERT_EQ(p.before.size(), 1u);
  EXPECT_EQ(kinds(p.before[0]), (std::vector<K>{K::Condition, K::Serial}));
  EXPECT_EQ(p.before[0].parts[1].op, &t.body[0]);
  ASSERT_EQ(p.loop.size(), 3u);
  EXPECT_EQ(p.loop[0].kind, K::Lanes);
  EXPECT_EQ(p.loop[1].kind, K::Tree);
  EXPECT_EQ(kinds(p.loop[2]), (std::vector<K>{K::Combine, K::Serial, K::Condition, K::Serial}));
  EXPECT_TRUE(p.loop[2].in_loop);
  EXPECT_EQ(p.loop[2].parts[3].op, &t.body[0]);
  // Starting with a program scalar's update: not moved.
  t.body = {setting(0), pass};
  p = plan_device_program(t);
  ASSERT_EQ(p.before.size(), 1u);
  EXPECT_EQ(kinds(p.before[0]), (std::vector<K>{K::Condition}));
  ASSERT_EQ(p.loop.size(), 4u);
  EXPECT_EQ(kinds(p.loop[0]), (std::vector<K>{K::Serial}));
  EXPECT_EQ(kinds(p.loop[3]), (std::vector<K>{K::Combine, K::Condition}));
}

}  // namespace
}  // namespace simit::jit
