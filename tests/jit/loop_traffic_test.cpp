// The bytes a solver loop moves (jit/loop_traffic.h): counted from a trace built by hand,
// whose arrays' sizes make every term of the count distinct.
#include "jit/loop_traffic.h"

#include <gtest/gtest.h>

#include <vector>

namespace simit::jit {
namespace {

ExprRef load(int slot) {
  auto e = std::make_shared<Expr>();
  e->kind = ExprKind::Load;
  e->slot = slot;
  auto at = std::make_shared<Expr>();
  at->kind = ExprKind::Element;
  at->ty = Ty::I32;
  e->ops.push_back(at);
  return e;
}

Stmt store(int slot, ExprRef value) {
  Stmt s;
  s.kind = StmtKind::Store;
  s.slot = slot;
  s.value = std::move(value);
  return s;
}

ExprRef add(ExprRef a, ExprRef b) {
  auto e = std::make_shared<Expr>();
  e->kind = ExprKind::Binary;
  e->op = static_cast<uint8_t>(BinOp::Add);
  e->ops = {std::move(a), std::move(b)};
  return e;
}

// Slots: 0 values, 1 cols, 2 row_ptr of the matrix; 3 x, 4 y (the product's), 5 r, 6 b.
const std::vector<size_t> kBytes = {1000000, 20000, 300, 4000, 50000, 600000, 7};

SystemTrace cg_like() {
  SystemTrace t;
  VectorOp product;
  product.kind = VectorOp::Kind::SpMV;
  product.values = 0;
  product.cols = 1;
  product.row_ptr = 2;
  product.x = 3;
  product.y = 4;
  product.body.push_back(store(4, add(load(4), load(3))));  // its row and x: counted once
  VectorOp pass;
  pass.kind = VectorOp::Kind::Pass;
  pass.body.push_back(store(5, add(load(5), load(4))));  // r read and written, y read
  pass.body.push_back(store(3, load(5)));                // x written
  VectorOp scalar;                                       // no arrays
  t.body = {product, pass, scalar};
  VectorOp set_up;
  set_up.kind = VectorOp::Kind::Pass;
  set_up.body.push_back(store(5, load(6)));  // r = b
  t.before = {set_up};
  VectorOp residual;
  residual.kind = VectorOp::Kind::Pass;
  residual.body.push_back(store(3, add(load(3), load(3))));
  t.after = {residual};
  return t;
}

TEST(LoopTraffic, EachOpReadsEveryArrayItTouchesOnceAndWritesEachOnce) {
  const LoopTraffic traffic = loop_traffic(cg_like(), kBytes);
  // The product: values, cols, row_ptr, x read; y written (its body's read of y is the row it
  // just computed). The pass: r and y read, r and x written.
  EXPECT_EQ(traffic.matrices, 1000000 + 20000 + 300);
  EXPECT_EQ(traffic.per_iteration,
            (1000000 + 20000 + 300 + 4000 + 50000) + (600000 + 50000) + (600000 + 4000));
  EXPECT_EQ(traffic.before, 7 + 600000);
  EXPECT_EQ(traffic.after, 4000 + 4000);
}

TEST(LoopTraffic, ACountAddsTheCallsThatCountedTheirIterations) {
  const LoopTraffic t = loop_traffic(cg_like(), kBytes);
  TrafficCount count;
  EXPECT_EQ(count.note(), "");
  count.add(t, 0, 5.0);  // a device program's call: not counted
  EXPECT_EQ(count.note(), "");
  count.add(t, 10, 1.0);
  count.add(t, 30, 3.0);
  EXPECT_EQ(count.iterations, 40);
  EXPECT_EQ(count.bytes, 2 * (t.before + t.after) + 40 * t.per_iteration);
  EXPECT_DOUBLE_EQ(count.ms, 4.0);
  // 2 * (600007 + 8000) + 40 * 2328300 bytes in 4 ms: 23.59 GB/s.
  EXPECT_NE(count.note().find("an iteration moves 2273.7 KB (its matrices 996.4 KB); 40 "
                              "iterations at 23.6 GB/s"),
            std::string::npos)
      << count.note();
}

}  // namespace
}  // namespace simit::jit
