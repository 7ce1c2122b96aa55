// The loop IR (jit/loop_ir.h): its verifier and printer, the deciders of guarded writes, and
// a pass moved up to the loop it can join.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <future>
#include <limits>
#include <sstream>
#include <thread>

#include "api/engine.h"
#include "jit/loop_ir.h"
#include "jit/write_guard.h"
#include "jit_test_support.h"

namespace simit::jit {
namespace {

using namespace test_support;  // also ast, Value and the engine API's names

// ---------------------------------------------------------------------------
// The loop IR

ExprRef c(double v) {
  Expr e;
  e.f = v;
  return std::make_shared<const Expr>(e);
}

TEST(LoopIr, VerifierAcceptsAWellFormedTraceAndPrintsIt) {
  Trace t;
  t.name = "demo";
  t.locals = {Ty::F64};
  Stmt s;
  s.kind = StmtKind::SetLocal;
  s.slot = 0;
  s.value = c(2.5);
  t.body.push_back(s);
  EXPECT_EQ(verify(t), "");
  std::ostringstream os;
  print(os, t);
  EXPECT_NE(os.str().find("%0 = 2.5"), std::string::npos) << os.str();
  EXPECT_EQ(node_count(t), 2u);
}

TEST(LoopIr, VerifierRejectsALocalReadBeforeItIsSetOnEveryPath) {
  Trace t;
  t.locals = {Ty::F64, Ty::F64};
  Expr cond;
  cond.ty = Ty::Bool;
  cond.i = 1;
  Stmt branch;
  branch.kind = StmtKind::If;
  branch.value = std::make_shared<const Expr>(cond);
  Stmt set;
  set.kind = StmtKind::SetLocal;
  set.slot = 0;
  set.value = c(1.0);
  branch.body.push_back(set);  // only the then-branch sets %0
  t.body.push_back(branch);
  Expr read;
  read.kind = ExprKind::Local;
  read.slot = 0;
  Stmt use;
  use.kind = StmtKind::SetLocal;
  use.slot = 1;
  use.value = std::make_shared<const Expr>(read);
  t.body.push_back(use);
  EXPECT_EQ(verify(t), "local %0 read before it is set");
  t.body[0].orelse.push_back(set);  // now both paths set it
  EXPECT_EQ(verify(t), "");
}

ExprRef node(ExprKind kind, Ty ty, int slot, std::vector<ExprRef> ops = {}) {
  Expr e;
  e.kind = kind;
  e.ty = ty;
  e.slot = slot;
  e.ops = std::move(ops);
  return std::make_shared<const Expr>(e);
}
ExprRef load(int slot, Ty ty) {
  return node(ExprKind::Load, ty, slot, {node(ExprKind::Element, Ty::I32, 0)});
}
Stmt set_local(int slot, ExprRef value) {
  Stmt s;
  s.kind = StmtKind::SetLocal;
  s.slot = slot;
  s.value = std::move(value);
  return s;
}
Stmt if_then(ExprRef cond, std::vector<Stmt> body, std::vector<Stmt> orelse = {}) {
  Stmt s;
  s.kind = StmtKind::If;
  s.value = std::move(cond);
  s.body = std::move(body);
  s.orelse = std::move(orelse);
  return s;
}
Stmt assemble(ExprRef value) {
  Stmt s;
  s.kind = StmtKind::Assemble;
  s.slot = 3;
  s.pair = 0;
  s.value = std::move(value);
  return s;
}

// The inputs that decide a map's matrix writes: what the conditions around them read,
// through locals assigned under other conditions; not what the written values read.
TEST(WriteGuard, TheDecidersAreWhatTheConditionsAroundTheWritesRead) {
  Trace t;
  t.arrays = {{ArraySlot::Kind::Field, 1, 3, Ty::Bool, false, false, 1, "pinned", {}},
              {ArraySlot::Kind::Field, 1, 0, Ty::F64, false, false, 3, "x", {}},
              {ArraySlot::Kind::Vector, 0, 0, Ty::F64, false, false, 3, "p", {}},
              {ArraySlot::Kind::Result, 0, 0, Ty::F64, false, true, 9, "K", {}},
              {ArraySlot::Kind::Table, 0, 0, Ty::I32, false, false, 1, "K.table", {}}};
  t.scalars = {Ty::F64};
  t.locals = {Ty::F64, Ty::Bool};
  t.local_mutable = {false, true};
  ExprRef pinned = load(0, Ty::Bool), x = load(1, Ty::F64);
  // %1 = pinned ? false : true (assigned in branches: control-dependent on `pinned`).
  t.body.push_back(set_local(0, x));
  Expr no;
  no.ty = Ty::Bool;
  t.body.push_back(if_then(pinned, {set_local(1, std::make_shared<const Expr>(no))},
                           {set_local(1, node(ExprKind::Unary, Ty::Bool, 0, {pinned}))}));
  t.body.push_back(
      if_then(node(ExprKind::Local, Ty::Bool, 1), {assemble(node(ExprKind::Local, Ty::F64, 0))}));
  WriteDeciders d = write_deciders(t);
  EXPECT_EQ(d.fields, std::vector<int>{0});
  EXPECT_TRUE(d.scalars.empty());
  EXPECT_EQ(d.unguardable, "");
  // A write under a condition on the scalar argument, inside one on x.
  ExprRef positive =
      node(ExprKind::Compare, Ty::Bool, 0, {node(ExprKind::Scalar, Ty::F64, 0), c(0.0)});
  t.body.push_back(if_then(node(ExprKind::Compare, Ty::Bool, 0, {x, c(1.0)}),
                           {if_then(positive, {assemble(c(1.0))})}));
  d = write_deciders(t);
  EXPECT_EQ(d.fields, (std::vector<int>{0, 1}));
  EXPECT_EQ(d.scalars, std::vector<int>{0});
  // A condition on a global vector: no write version to guard it with.
  t.body.push_back(if_then(node(ExprKind::Compare, Ty::Bool, 0, {load(2, Ty::F64), c(0.0)}),
                           {assemble(c(2.0))}));
  EXPECT_EQ(write_deciders(t).unguardable, "the writes depend on 'p', which has no write version");
}

TEST(LoopIr, VerifierRejectsMismatchedTypes) {
  Trace t;
  t.locals = {Ty::I32};
  Stmt s;
  s.kind = StmtKind::SetLocal;
  s.slot = 0;
  s.value = c(1.0);
  t.body.push_back(s);
  EXPECT_EQ(verify(t), "set local: operand is f64, expected i32");
}

// A tiled product's loop: its local is set inside the loop only, and scratch arrays must exist.
TEST(LoopIr, VerifierChecksLoopsAndScratchArrays) {
  Trace t;
  t.locals = {Ty::I32, Ty::F64};
  t.scratch = {4};
  Expr k;
  k.kind = ExprKind::Local;
  k.ty = Ty::I32;
  k.slot = 0;
  Stmt put;
  put.kind = StmtKind::Put;
  put.slot = 0;
  put.index = std::make_shared<const Expr>(k);
  put.value = c(1.5);
  Stmt loop;
  loop.kind = StmtKind::For;
  loop.slot = 0;
  loop.n = 4;
  loop.body.push_back(put);
  t.body.push_back(loop);
  Expr read;
  read.kind = ExprKind::Scratch;
  read.slot = 0;
  read.ops = {std::make_shared<const Expr>(k)};
  Stmt use;
  use.kind = StmtKind::SetLocal;
  use.slot = 1;
  use.value = std::make_shared<const Expr>(read);
  t.body.push_back(use);  // reads the loop's local after the loop
  EXPECT_EQ(verify(t), "local %0 read before it is set");
  Expr two;
  two.ty = Ty::I32;
  two.i = 2;
  read.ops = {std::make_shared<const Expr>(two)};
  t.body[1].value = std::make_shared<const Expr>(read);
  EXPECT_EQ(verify(t), "");
  std::ostringstream os;
  print(os, t);
  EXPECT_NE(os.str().find("for %0 < 4"), std::string::npos) << os.str();
  EXPECT_NE(os.str().find("s0[%0] = 1.5"), std::string::npos) << os.str();
  EXPECT_NE(os.str().find("%1 = s0[2]"), std::string::npos) << os.str();
  t.scratch.clear();
  EXPECT_EQ(verify(t), "put: scratch array 0 out of range");
  t.scratch = {4};
  t.locals[0] = Ty::F64;
  EXPECT_EQ(verify(t), "for over a local that is not an i32");
}

// A system trace's ops under a guard (a branch of an if): what they set is set for the later
// ops under the same guard, not for the ops under another guard or none.
TEST(LoopIr, VerifierFollowsGuardsInASystemTrace) {
  SystemTrace t;
  t.scalars = 1;  // %0: a program scalar, the guard
  t.locals = {Ty::Bool, Ty::F64, Ty::F64};
  Expr tru;
  tru.ty = Ty::Bool;
  tru.i = 1;
  t.condition = std::make_shared<const Expr>(tru);
  auto op = [&](int guard, int set, int read) {
    VectorOp o;
    o.guard = guard;
    Stmt s;
    s.kind = StmtKind::SetLocal;
    s.slot = set;
    s.value = c(1.0);
    if (read >= 0) {
      Expr r;
      r.kind = ExprKind::Local;
      r.slot = read;
      s.value = std::make_shared<const Expr>(r);
    }
    o.body.push_back(s);
    return o;
  };
  t.body = {op(0, 1, -1), op(-1, 2, -1), op(0, 2, 1)};  // %1 set and read under %0
  EXPECT_EQ(verify(t), "");
  t.body[2].guard = -1;  // read where %0 may not hold
  EXPECT_EQ(verify(t), "local %1 read before it is set");
}

// A pass moves up past a scalar op it does not depend on and joins the pass before it: r'r
// after `rz = r'r_old` (a scalar op that waits for the update's sum) joins the update.
TEST(LoopIr, APassMovesUpToTheLoopItCanJoin) {
  SystemTrace t;
  t.scalars = 2;  // %0, %1: program scalars; %2, %3: sums
  t.locals = {Ty::F64, Ty::F64, Ty::F64, Ty::F64};
  t.sizes = {"n"};
  t.arrays.resize(1);
  t.arrays[0].written = true;
  Expr tru;
  tru.ty = Ty::Bool;
  tru.i = 1;
  t.condition = std::make_shared<const Expr>(tru);
  auto local = [](int l) {
    Expr e;
    e.kind = ExprKind::Local;
    e.slot = l;
    return std::make_shared<const Expr>(e);
  };
  Expr k;
  k.kind = ExprKind::Element;
  k.ty = Ty::I32;
  Expr r;
  r.kind = ExprKind::Load;
  r.ops = {std::make_shared<const Expr>(k)};
  auto load_r = std::make_shared<const Expr>(r);
  auto set = [](int l, ExprRef v) {
    Stmt s;
    s.kind = StmtKind::SetLocal;
    s.slot = l;
    s.value = std::move(v);
    return s;
  };
  auto binary = [](BinOp op, ExprRef a, ExprRef b) {
    Expr e;
    e.kind = ExprKind::Binary;
    e.op = static_cast<uint8_t>(op);
    e.ops = {std::move(a), std::move(b)};
    return std::make_shared<const Expr>(e);
  };
  VectorOp start, update, scalar, sum;
  start.body = {set(2, c(0.0)), set(3, c(0.0))};
  update.kind = VectorOp::Kind::Pass;
  update.length = 0;
  Stmt store;
  store.kind = StmtKind::Store;
  store.index = load_r->ops[0];
  store.value = binary(BinOp::Mul, load_r, c(0.5));  // r = 0.5 * r, and %3 = r'r
  update.sums = {3};
  update.body = {store, set(3, binary(BinOp::Add, local(3), binary(BinOp::Mul, load_r, load_r)))};
  scalar.body = {set(1, local(3)), set(0, local(1))};
  sum.kind = VectorOp::Kind::Pass;
  sum.length = 0;
  sum.sums = {2};
  sum.body = {set(2, binary(BinOp::Add, local(2), binary(BinOp::Mul, load_r, load_r)))};
  t.body = {start, update, scalar, sum};
  ASSERT_EQ(verify(t), "");
  EXPECT_EQ(fuse_passes(t), 1);
  ASSERT_EQ(t.body.size(), 3u);
  EXPECT_EQ(t.body[1].kind, VectorOp::Kind::Pass);
  EXPECT_EQ(t.body[1].body.size(), 3u);  // the update, then the two sums' terms
  EXPECT_EQ(t.body[1].sums, (std::vector<int>{3, 2}));
  EXPECT_EQ(t.body[2].kind, VectorOp::Kind::Scalar);
  EXPECT_EQ(verify(t), "");
  // A pass that reads what the scalar op writes stays after it.
  scalar.body = {set(1, local(3)), set(2, c(0.0))};
  t.body = {start, update, scalar, sum};
  EXPECT_EQ(fuse_passes(t), 0);
}

}  // namespace
}  // namespace simit::jit
