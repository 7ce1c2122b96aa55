// A device program's launch path (jit/ptx/gpu_executor.h, run_system) against the fake driver:
// the step kernels of the PTX target loaded by name and launched with the context and their
// units, the loop's iterations in batches of 1, 2, 4, ... ended by the stop word (which the
// thread that ends an iteration sets when the next condition fails), the scalars
// in and out through the context, an interrupt taken between two batches, and the batches as
// CUDA graphs. The fake's launches
// run the CPU target's step functions of the same trace on the fake's (host) memory.
#include <gtest/gtest.h>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "gpu_fake_driver.h"
#include "jit/device_program.h"
#include "jit/ptx/gpu_executor.h"
#include "jit/target.h"

namespace simit::jit::ptx::fake_gpu {
namespace {

ExprRef node(Expr e) { return std::make_shared<const Expr>(std::move(e)); }
ExprRef local(int slot, Ty ty) {
  Expr e;
  e.kind = ExprKind::Local;
  e.ty = ty;
  e.slot = slot;
  return node(e);
}
ExprRef number(double v) {
  Expr e;
  e.f = v;
  return node(e);
}
ExprRef integer(int v) {
  Expr e;
  e.ty = Ty::I32;
  e.i = v;
  return node(e);
}
ExprRef binary(BinOp op, ExprRef a, ExprRef b, Ty ty = Ty::F64) {
  Expr e;
  e.kind = ExprKind::Binary;
  e.ty = ty;
  e.op = static_cast<uint8_t>(op);
  e.ops = {std::move(a), std::move(b)};
  return node(e);
}
ExprRef x_here() {
  Expr k;
  k.kind = ExprKind::Element;
  k.ty = Ty::I32;
  Expr e;
  e.kind = ExprKind::Load;
  e.ops = {node(k)};
  return node(e);
}

// while k < 3: x = 0.5 * x and s = s + x' * x (one pass with a sum); k = k + 1.
SystemTrace halving() {
  SystemTrace t;
  t.name = "halving";
  t.scalars = 2;  // %0 k, %1 s
  t.locals = {Ty::I32, Ty::F64};
  t.sizes = {"components of x"};
  ArraySlot x;
  x.kind = ArraySlot::Kind::Vector;
  x.written = true;
  x.name = "x";
  t.arrays = {x};
  Expr less;
  less.kind = ExprKind::Compare;
  less.ty = Ty::Bool;
  less.op = static_cast<uint8_t>(CmpOp::Lt);
  less.ops = {local(0, Ty::I32), integer(3)};
  t.condition = node(less);
  VectorOp pass;
  pass.kind = VectorOp::Kind::Pass;
  pass.length = 0;
  pass.sums = {1};
  Stmt store;
  store.kind = StmtKind::Store;
  store.index = x_here()->ops[0];
  store.value = binary(BinOp::Mul, x_here(), number(0.5));
  Stmt sum;
  sum.kind = StmtKind::SetLocal;
  sum.slot = 1;
  sum.value = binary(BinOp::Add, local(1, Ty::F64), binary(BinOp::Mul, x_here(), x_here()));
  pass.body = {store, sum};
  VectorOp count;
  Stmt next;
  next.kind = StmtKind::SetLocal;
  next.slot = 0;
  next.value = binary(BinOp::Add, local(0, Ty::I32), integer(1), Ty::I32);
  count.body = {next};
  t.body = {pass, count};
  t.device = true;
  return t;
}

struct Compiled {
  std::unique_ptr<Kernel> cpu, gpu;
};

Compiled compile_both() {
  SystemTrace t = halving();
  EXPECT_EQ(verify(t), "");
  std::string error;
  Compiled c;
  auto cpu = make_cpu_target(HostCalls{}, "", error);
  EXPECT_TRUE(cpu) << error;
  auto gpu = make_ptx_target(kDefaultGpuArch, error);
  EXPECT_TRUE(gpu) << error;
  if (!cpu || !gpu) return c;
  c.cpu = cpu->compile(t, false, error);
  EXPECT_TRUE(c.cpu) << error;
  c.gpu = gpu->compile(t, false, error);
  EXPECT_TRUE(c.gpu) << error;
  return c;
}

struct Outcome {
  int32_t rc = 0;
  std::vector<double> x = {1, 2, 3, 4, 5};
  double scalars[2] = {0, 0};
};

Outcome run(Executor& exec, const Kernel& kernel, uint8_t interrupt) {
  Outcome r;
  void* arrays[] = {r.x.data()};
  const int64_t sizes[] = {5};
  const size_t bytes[] = {5 * sizeof(double)};
  const bool written[] = {true};
  SystemArgs a{arrays, r.scalars, sizes, &interrupt};
  a.array_count = 1;
  a.size_count = 1;
  a.scalar_count = 2;
  a.array_bytes = bytes;
  a.array_written = written;
  r.rc = exec.run_system(kernel, a);
  return r;
}

TEST_F(GpuExecutorFake, ADeviceProgramLaunchesItsStepsInBatchesUntilTheStopWord) {
  const Compiled c = compile_both();
  ASSERT_TRUE(c.cpu && c.gpu);
  const auto& ptx = dynamic_cast<const PtxKernel&>(*c.gpu);
  // Before the loop: the condition. The loop: lanes, tree, and one thread that combines the
  // sum, counts, and tests the condition for the next iteration.
  ASSERT_EQ(ptx.entries.size(), 4u);
  EXPECT_EQ(ptx.entries[0], "simit_step_step0");
  state.on_launch = [&](const Launch& l) {
    ASSERT_GE(l.step, 0);
    c.cpu->run_step(l.step, at<int64_t>(l.context), 0, l.units);
  };
  auto exec = make_gpu_executor_over(fake_table());
  const Outcome r = run(*exec, *c.gpu, 0);
  EXPECT_EQ(r.rc, 0);
  EXPECT_EQ(r.scalars[0], 3.0);
  // Squares of halves of small integers: every sum exact, whatever the order.
  EXPECT_EQ(r.scalars[1], 55.0 * (1.0 / 4 + 1.0 / 16 + 1.0 / 64));
  EXPECT_EQ(r.x, (std::vector<double>{0.125, 0.25, 0.375, 0.5, 0.625}));
  // The first condition, then batches of 1 and 2 iterations: the third iteration's thread
  // finds the condition false and sets the stop word.
  ASSERT_EQ(state.launches.size(), 1u + 3u * 3u);
  EXPECT_EQ(state.launches[0].step, 0);
  for (size_t i = 1; i < state.launches.size(); ++i)
    EXPECT_EQ(state.launches[i].step, int(1 + (i - 1) % 3));
  const Launch& lanes = state.launches[1];
  EXPECT_EQ(lanes.units, 32);  // one chunk of 5 elements: 32 lanes
  EXPECT_EQ(lanes.grid, 1u);
  EXPECT_EQ(lanes.block, 32u);
  EXPECT_EQ(state.launches[2].units, 1);  // the tree: one chunk
  EXPECT_EQ(state.launches[3].block, 1u);
  // The host read the context after each batch and at the end.
  EXPECT_EQ(gpu_traffic(*exec).system_batches, 3);
  EXPECT_EQ(gpu_traffic(*exec).system_runs, 1);
}

// An interrupt pending when the first batch (one iteration) ends: whole iterations have run
// and the scalars they left come back.
TEST_F(GpuExecutorFake, AnInterruptStopsADeviceProgramBetweenTwoBatches) {
  const Compiled c = compile_both();
  ASSERT_TRUE(c.cpu && c.gpu);
  state.on_launch = [&](const Launch& l) {
    c.cpu->run_step(l.step, at<int64_t>(l.context), 0, l.units);
  };
  auto exec = make_gpu_executor_over(fake_table());
  const Outcome r = run(*exec, *c.gpu, 1);
  EXPECT_EQ(r.rc, kSystemInterrupted);
  EXPECT_EQ(r.scalars[0], 1.0);
  EXPECT_EQ(r.scalars[1], 55.0 / 4);
  EXPECT_EQ(r.x, (std::vector<double>{0.5, 1, 1.5, 2, 2.5}));
  EXPECT_EQ(state.launches.size(), 1u + 3u);
}

// With the stream table, each batch is one graph launch: captured the first time a batch
// size comes (its steps recorded from the stream, not run), launched after; a second call
// with the same sizes reuses the graphs; the executor's end destroys them and the stream.
TEST_F(GpuExecutorFake, LoopBatchesRunAsCudaGraphsCapturedOnce) {
  const Compiled c = compile_both();
  ASSERT_TRUE(c.cpu && c.gpu);
  state.on_launch = [&](const Launch& l) {
    c.cpu->run_step(l.step, at<int64_t>(l.context), 0, l.units);
  };
  const StreamTable streams = fake_streams();
  {
    auto exec = make_gpu_executor_over(fake_table(), &streams);
    EXPECT_EQ(state.streams_created, 1);
    const Outcome r = run(*exec, *c.gpu, 0);
    EXPECT_EQ(r.rc, 0);
    EXPECT_EQ(r.scalars[0], 3.0);
    EXPECT_EQ(r.scalars[1], 55.0 * (1.0 / 4 + 1.0 / 16 + 1.0 / 64));
    EXPECT_EQ(r.x, (std::vector<double>{0.125, 0.25, 0.375, 0.5, 0.625}));
    // Batches of 1 and 2 iterations: two graphs of 3 and 6 step launches, each launched once;
    // the steps ran as without graphs (the condition first, then steps 1 2 3 three times).
    ASSERT_EQ(state.graphs.size(), 2u);
    EXPECT_EQ(state.graphs[0].size(), 3u);
    EXPECT_EQ(state.graphs[1].size(), 6u);
    EXPECT_EQ(state.graph_launches, 2);
    ASSERT_EQ(state.launches.size(), 1u + 3u * 3u);
    for (size_t i = 1; i < state.launches.size(); ++i)
      EXPECT_EQ(state.launches[i].step, int(1 + (i - 1) % 3));
    EXPECT_EQ(state.graphs_destroyed, 2);  // each graph once it is instantiated
    // Again, the same sizes: no capture, two graph launches.
    const Outcome again = run(*exec, *c.gpu, 0);
    EXPECT_EQ(again.x, r.x);
    EXPECT_EQ(state.graphs.size(), 2u);
    EXPECT_EQ(state.graph_launches, 4);
    EXPECT_EQ(gpu_traffic(*exec).graphs_captured, 2);
    EXPECT_EQ(gpu_traffic(*exec).graph_launches, 4);
  }
  EXPECT_EQ(state.execs_destroyed, 2);
  EXPECT_EQ(state.streams_destroyed, 1);
}

// The emulated executor runs the CPU's steps directly, to the same results.
TEST(GpuProgramEmulated, TheCpusStepsGiveTheSameResults) {
  const Compiled c = compile_both();
  ASSERT_TRUE(c.cpu);
  auto exec = make_emulated_gpu_executor();
  const Outcome r = run(*exec, *c.cpu, 0);
  EXPECT_EQ(r.rc, 0);
  EXPECT_EQ(r.scalars[0], 3.0);
  EXPECT_EQ(r.scalars[1], 55.0 * (1.0 / 4 + 1.0 / 16 + 1.0 / 64));
  EXPECT_EQ(r.x, (std::vector<double>{0.125, 0.25, 0.375, 0.5, 0.625}));
}

}  // namespace
}  // namespace simit::jit::ptx::fake_gpu
