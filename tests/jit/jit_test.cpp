// The tracing JIT against the interpreter: the loop IR's verifier, traces of map and apply
// sites compiled with LLVM and run bit for bit like the interpreter, the fallbacks with their
// reasons, errors reported in the interpreter's words, and switching executors mid-run.
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
#include "jit/pruned_matrix.h"
#include "jit/tunables.h"
#include "jit/write_guard.h"

namespace simit::jit {
namespace {

namespace ast = frontend::ast;
using api::CompiledProgram;
using api::Engine;
using api::EngineOptions;
using api::ExecutorKind;
using interp::Value;

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

// ---------------------------------------------------------------------------
// The compiled products' copy of a matrix

// A solver loop's copy of a matrix drops its zero blocks (of either sign; a block with a
// subnormal, a NaN or an infinity is kept), holds the others by columns, and is padded so that
// a 3-component column loads as one 4-lane vector.
TEST(PrunedMatrix, TheCopyDropsZeroBlocksHoldsColumnsAndIsPadded) {
  std::vector<int32_t> row_ptr{0}, cols;
  for (int r = 0; r < 5; ++r) {
    for (int c = std::max(0, r - 1); c <= std::min(4, r + 1); ++c) cols.push_back(c);
    row_ptr.push_back(static_cast<int32_t>(cols.size()));
  }
  runtime::SystemMatrix k(runtime::MatrixPattern::from_csr(5, 5, row_ptr, cols), 3, 3);
  for (size_t i = 0; i < k.value_count(); ++i)
    k.values()[i] = 0.1 * static_cast<double>(i % 17) - 0.7;
  for (int i = 0; i < 9; ++i) k.block(1)[i] = i == 4 ? -0.0 : 0.0;  // block (0, 1): dropped
  // Zeros but for one subnormal, one NaN, one -infinity: kept; all -0.0: dropped.
  const double odd[3] = {std::numeric_limits<double>::denorm_min(),
                         std::numeric_limits<double>::quiet_NaN(),
                         -std::numeric_limits<double>::infinity()};
  for (int b = 0; b < 3; ++b)
    for (int i = 0; i < 9; ++i) k.block(3 + b)[i] = i == 8 - b ? odd[b] : -0.0;
  for (int i = 0; i < 9; ++i) k.block(6)[i] = -0.0;  // block (2, 2): dropped
  PrunedMatrix p;
  p.assign(k);
  EXPECT_EQ(p.total, 13);
  EXPECT_EQ(p.kept, 11);
  EXPECT_EQ(p.row_ptr, (std::vector<int32_t>{0, 1, 4, 6, 9, 11}));
  EXPECT_EQ(p.cols[0], 0);
  EXPECT_EQ(p.cols[1], 0);        // row 1 starts with block (1, 0)
  ASSERT_EQ(p.cols.size(), 11u);  // the kept blocks only
  ASSERT_EQ(p.values.size(), 11u * 9 + 1);
  // Block (1, 0), by columns: component (i, j) at 3 j + i.
  const double* b = k.block(2);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) EXPECT_EQ(p.values[9 + 3 * j + i], b[3 * i + j]) << i << j;
}

// ---------------------------------------------------------------------------
// Compiled sites against the interpreter

const char* kProgram = R"(
element Vertex
  x : vector[3](float);
  v : vector[3](float);
  m : float;
  pinned : bool;
end
element Tet
  B : matrix[3,3](float);
  W : float;
end
extern verts : set{Vertex};
extern tets : set{Tet}(verts, verts, verts, verts);
extern gain : float;

const eye3 = [1.0, 0.0, 0.0; 0.0, 1.0, 0.0; 0.0, 0.0, 1.0];

func edge_matrix(v : (Vertex * 4)) -> D : matrix[3,3](float)
  for j in 0:3
    e = v(j).x - v(3).x;
    for i in 0:3
      D(i, j) = e(i);
    end
  end
end

func rest(inout t : Tet, v : (Vertex * 4)) -> m : vector[verts](float)
  Dm = edge_matrix(v);
  t.B = inv(Dm);
  t.W = -det(Dm) / 6.0;
  for j in 0:4
    m(v(j)) = 0.25 * t.W;
  end
end

func hold(inout p : Vertex)
  if p.pinned
    p.v = 0.0;
  else
    p.v = gain * p.v + [0.0, -1.0, 0.0]';
  end
end

func force(mu : float, t : Tet, v : (Vertex * 4)) -> f : vector[verts](vector[3](float))
  F = edge_matrix(v) * t.B;
  FinvT = inv(F)';
  P = mu * (F - FinvT) + log(det(F)) * FinvT;
  for j in 0:3
    f(v(j)) = -t.W * (P * t.B(j, :)');
  end
  f(v(3)) = t.W * (P * (t.B(0, :) + t.B(1, :) + t.B(2, :))');
end

func stiffness(t : Tet, v : (Vertex * 4)) -> K : matrix[verts,verts](matrix[3,3](float))
  F = edge_matrix(v) * t.B;
  var s = 0.0;
  if det(F) > 0.5
    s = sqrt(det(F));
  elif v(0).m > 100.0
    s = -1.0;
  else
    s = max(0.25, v(1).m);
  end
  for i in 0:4
    for j in 0:4
      if not (v(i).pinned or v(j).pinned)
        K(v(i), v(j)) = (s * t.W) * (F' * F) + eye3;
        K(v(i), v(j))(0, 1) = t.W;
      end
    end
  end
end

func mass(p : Vertex) -> M : matrix[verts,verts](matrix[3,3](float))
  M(p, p) = p.m * eye3;
end

func rhs(f : vector[verts](vector[3](float)), p : Vertex) -> b : vector[verts](vector[3](float))
  if not p.pinned
    b(p) = p.m * p.v + 0.01 * f(p);
  end
end

func count(p : Vertex) -> n : vector[verts](float)
  var k = 0.0;
  while k < 2.0
    k = k + 1.0;
  end
  n(p) = k;
end

export func init()
  verts.m = map rest to tets reduce +;
end

export func step() -> (A : matrix[verts,verts](matrix[3,3](float)), b : vector[verts](vector[3](float)),
                       n : vector[verts](float))
  apply hold to verts;
  f = map force(2.0) to tets reduce +;
  K = map stiffness to tets reduce +;
  M = map mass to verts reduce +;
  A = M - 0.01 * K;
  b = map rhs(f) to verts reduce +;
  n = map count to verts reduce +;
end
)";

// Two tets sharing a face, one vertex pinned; coordinates not on a lattice so that every
// operation rounds.
struct Mesh {
  runtime::Set verts{"verts"};
  runtime::Set tets{"tets", {&verts, &verts, &verts, &verts}};

  explicit Mesh(bool inverted = false) {
    verts.add_many(5);
    using runtime::ComponentKind;
    verts.add_field("x", runtime::FieldType{ComponentKind::Float, {3}, false});
    verts.add_field("v", runtime::FieldType{ComponentKind::Float, {3}, false});
    verts.add_field("m", runtime::FieldType{ComponentKind::Float, {}, false});
    verts.add_field("pinned", runtime::FieldType{ComponentKind::Bool, {}, false});
    const double x[5][3] = {
        {0.1, 0.0, 0.03}, {1.07, 0.11, 0.0}, {0.0, 0.93, 0.2}, {0.05, 0.1, 1.13}, {1.2, 1.1, 0.9}};
    for (int i = 0; i < 5; ++i)
      for (int k = 0; k < 3; ++k) {
        verts.field(0).at<double>(i)[k] = inverted && i == 2 && k == 1 ? 0.0 : x[i][k];
        verts.field(1).at<double>(i)[k] = 0.1 * (i + 1) - 0.07 * k;
      }
    verts.field(3).at<bool>(0)[0] = true;
    const int32_t ends[] = {0, 1, 2, 3, 1, 2, 3, 4};
    tets.add_edges(ends);
    tets.add_field("B", runtime::FieldType{ComponentKind::Float, {3, 3}, false});
    tets.add_field("W", runtime::FieldType{ComponentKind::Float, {}, false});
  }
};

struct Program {
  std::shared_ptr<const CompiledProgram> compiled =
      CompiledProgram::from_source("jit_test.sim", kProgram);
  Mesh mesh;
  std::unique_ptr<Engine> engine;

  Program(ExecutorKind kind, bool inverted = false) : mesh(inverted) {
    EXPECT_TRUE(compiled->ok());
    EngineOptions o;
    o.executor.kind = kind;
    o.executor.threshold = 0;
    engine = std::make_unique<Engine>(compiled, o);
    engine->bind_set(*compiled->find_extern("verts"), mesh.verts);
    engine->bind_set(*compiled->find_extern("tets"), mesh.tets);
    engine->set_global(*compiled->find_extern("gain"), Value::of_float(0.75));
  }
  std::vector<Value> call(const char* f) { return engine->call(*compiled->find_func(f), {}); }
  std::string stats() const {
    std::ostringstream os;
    engine->print_jit_stats(os);
    return os.str();
  }
};

// Bit-for-bit equality of two doubles arrays.
void expect_same_bits(const double* a, const double* b, size_t n, const std::string& what) {
  for (size_t i = 0; i < n; ++i)
    EXPECT_EQ(std::memcmp(&a[i], &b[i], sizeof(double)), 0)
        << what << "[" << i << "]: " << a[i] << " vs " << b[i];
}

// Matrices on one pattern compare value by value; a JIT result on a specialised pattern
// (fewer blocks, jit/specialise.h) compares as the dense matrix it means, entry by entry.
void expect_same(const Value& a, const Value& b, const std::string& what) {
  ASSERT_EQ(a.kind(), b.kind()) << what;
  if (a.kind() == Value::Kind::Matrix) {
    const runtime::SystemMatrix &x = *a.matrix(), &y = *b.matrix();
    if (x.shared_pattern() == y.shared_pattern()) {
      expect_same_bits(x.values(), y.values(), x.value_count(), what);
      return;
    }
    EXPECT_LE(y.pattern().nnz(), x.pattern().nnz()) << what;
    for (int64_t i = 0; i < x.scalar_rows(); ++i)
      for (int64_t j = 0; j < x.scalar_cols(); ++j) {
        const double u = x.component(i, j), v = y.component(i, j);
        EXPECT_TRUE(std::memcmp(&u, &v, sizeof u) == 0 || (u == 0.0 && v == 0.0))
            << what << "(" << i << ", " << j << "): " << u << " vs " << v;
      }
  } else {
    ASSERT_EQ(a.tensor().size(), b.tensor().size()) << what;
    expect_same_bits(a.tensor().floats(), b.tensor().floats(), a.tensor().size(), what);
  }
}

void expect_same_fields(const runtime::Set& a, const runtime::Set& b) {
  for (int f = 0; f < a.field_count(); ++f) {
    const runtime::Field& fa = a.field(f);
    if (fa.type().kind != runtime::ComponentKind::Float) continue;
    expect_same_bits(fa.data<double>(), b.field(f).data<double>(), a.size() * fa.components(),
                     a.name() + "." + fa.name());
  }
}

TEST(Jit, CompiledSitesComputeTheInterpretersBits) {
  if (!api::jit_available()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  Program in(ExecutorKind::Interpreter), jit(ExecutorKind::Jit);
  in.call("init");
  jit.call("init");
  expect_same_fields(in.mesh.verts, jit.mesh.verts);
  expect_same_fields(in.mesh.tets, jit.mesh.tets);
  std::vector<Value> a, b;
  for (int frame = 0; frame < 3; ++frame) {
    a = in.call("step");
    b = jit.call("step");
    ASSERT_EQ(a.size(), 3u);
    expect_same(a[0], b[0], "A");
    expect_same(a[1], b[1], "b");
    expect_same(a[2], b[2], "n");
    expect_same_fields(in.mesh.verts, jit.mesh.verts);
  }
  // The values are real ones: a block of A away from the pinned vertex is not zero.
  const runtime::SystemMatrix& A = *a[0].matrix();
  const int32_t at = A.pattern().find(1, 2);
  ASSERT_GE(at, 0);
  EXPECT_NE(A.block(at)[0], 0.0);
  EXPECT_NE(A.block(at)[4], 0.0);
  const std::string stats = jit.stats();
  for (const char* site : {"rest", "hold", "force", "stiffness", "mass", "rhs"})
    EXPECT_NE(stats.find(std::string(site) + " (line"), std::string::npos) << stats;
  EXPECT_NE(stats.find("interpreted: While statements are not compiled"), std::string::npos)
      << stats;
  // Every site but `count` compiled.
  size_t compiled = 0;
  for (size_t at = stats.find(" compiled\n"); at != std::string::npos;
       at = stats.find(" compiled\n", at + 1))
    ++compiled;
  EXPECT_EQ(compiled, 6u) << stats;
}

// The stiffness writes no block of the pinned vertex 0: after its first compiled run its
// result keeps only the written blocks, guarded by the version of `pinned` (the only field
// its write conditions read); unpinning the vertex fails the guard, the blocks are recorded
// again, and now that every block is written the site stays on the full pattern, with the
// interpreter's values throughout.
TEST(Jit, MatrixResultsAreSpecialisedToTheBlocksWrittenWhileTheirDecidingFieldsAreUnchanged) {
  if (!api::jit_available()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  Program in(ExecutorKind::Interpreter), jit(ExecutorKind::Jit);
  in.call("init");
  jit.call("init");
  for (int frame = 0; frame < 3; ++frame) {
    std::vector<Value> a = in.call("step"), b = jit.call("step");
    expect_same(a[0], b[0], "A");
    expect_same(a[1], b[1], "b");
    expect_same_fields(in.mesh.verts, jit.mesh.verts);
    if (frame > 0) {
      // The union with the mass matrix's diagonal: the blocks between vertex 0 and the
      // others (6 of the 17 pairs of tet 0's and tet 1's vertices) are gone.
      EXPECT_LT(b[0].matrix()->pattern().nnz(), a[0].matrix()->pattern().nnz());
      EXPECT_LT(b[0].matrix()->pattern().find(0, 1), 0);
      EXPECT_GE(a[0].matrix()->pattern().find(0, 1), 0);
    }
  }
  std::string stats = jit.stats();
  EXPECT_NE(stats.find("result 0 specialised to"), std::string::npos) << stats;
  EXPECT_NE(stats.find("guard: 1 field version and 0 scalars compared per call"), std::string::npos)
      << stats;
  EXPECT_EQ(stats.find("the guard failed"), std::string::npos) << stats;
  in.mesh.verts.field(3).at<bool>(0)[0] = false;
  jit.mesh.verts.field(3).at<bool>(0)[0] = false;
  for (int frame = 0; frame < 2; ++frame) {
    std::vector<Value> a = in.call("step"), b = jit.call("step");
    expect_same(a[0], b[0], "A after unpinning");
    EXPECT_EQ(b[0].matrix()->pattern().nnz(), a[0].matrix()->pattern().nnz());
    EXPECT_NE(b[0].matrix()->component(0, 3), 0.0);
    expect_same_fields(in.mesh.verts, jit.mesh.verts);
  }
  stats = jit.stats();
  EXPECT_NE(stats.find("the guard failed on 1 call (blocks recorded again); full patterns: "
                       "nearly every block is written"),
            std::string::npos)
      << stats;
}

// Springs on a chain of six vertices; a spring writes its two off-diagonal entries only while
// both its ends are on, and a vertex's k scales them (a written entry may be zero).
const char* kChainProgram = R"(
element V
  k : float;
  on : bool;
end
element E
end
extern verts : set{V};
extern edges : set{E}(verts, verts);

func spring(e : E, v : (V * 2)) -> K : matrix[verts,verts](float)
  if v(0).on and v(1).on
    K(v(0), v(1)) = v(0).k * v(1).k;
    K(v(1), v(0)) = v(0).k;
  end
end

export func step() -> K : matrix[verts,verts](float)
  K = map spring to edges reduce +;
end
)";

struct Chain {
  std::shared_ptr<const CompiledProgram> compiled =
      CompiledProgram::from_source("chain.sim", kChainProgram);
  runtime::Set verts{"verts"};
  runtime::Set edges{"edges", {&verts, &verts}};
  std::unique_ptr<Engine> engine;

  explicit Chain(ExecutorKind kind) {
    EXPECT_TRUE(compiled->ok());
    verts.add_many(6);
    verts.add_field("k", runtime::FieldType{runtime::ComponentKind::Float, {}, false});
    verts.add_field("on", runtime::FieldType{runtime::ComponentKind::Bool, {}, false});
    for (int i = 0; i < 6; ++i) {
      verts.field(0).at<double>(i)[0] = i == 0 ? 0.0 : 0.5 + 0.25 * i;
      verts.field(1).at<bool>(i)[0] = i != 2;
    }
    const int32_t ends[] = {0, 1, 1, 2, 2, 3, 3, 4, 4, 5};
    edges.add_edges(ends);
    EngineOptions o;
    o.executor.kind = kind;
    o.executor.threshold = 0;
    engine = std::make_unique<Engine>(compiled, o);
    engine->bind_set(*compiled->find_extern("verts"), verts);
    engine->bind_set(*compiled->find_extern("edges"), edges);
  }
  Value step() { return engine->call(*compiled->find_func("step"), {})[0]; }
  void set_on(int i, bool on) { verts.field(1).at<bool>(i)[0] = on; }
  double k(int i) { return verts.field(0).at<double>(i)[0]; }
  std::string stats() const {
    std::ostringstream os;
    engine->print_jit_stats(os);
    return os.str();
  }
};

// The blocks kept are the blocks written, zeros included; the guard holds while only values
// change, fails when `on` is written, and a recording that finds the same blocks keeps the
// same pattern.
TEST(Jit, ASpecialisedPatternKeepsTheBlocksWrittenAndIsRebuiltWhenItsGuardFails) {
  if (!api::jit_available()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  Chain in(ExecutorKind::Interpreter), jit(ExecutorKind::Jit);
  // 6 diagonal and 10 off-diagonal blocks; the springs (1,2) and (2,3) are off: 6 written.
  Value a = in.step(), b = jit.step();
  expect_same(a, b, "K");
  b = jit.step();
  const runtime::PatternPtr kept = b.matrix()->shared_pattern();
  EXPECT_EQ(kept->nnz(), 6);
  EXPECT_EQ(b.matrix()->pattern().find(0, 1), 0);  // written as 0 * k1: kept
  EXPECT_LT(b.matrix()->pattern().find(1, 2), 0);
  EXPECT_EQ(b.matrix()->component(0, 1), 0.0);
  // Values change, the blocks do not: the guard holds and the zero block fills.
  for (Chain* c : {&in, &jit}) c->verts.field(0).at<double>(0)[0] = 2.0;
  a = in.step(), b = jit.step();
  expect_same(a, b, "K with k0 = 2");
  EXPECT_EQ(b.matrix()->shared_pattern(), kept);
  EXPECT_EQ(b.matrix()->component(0, 1), 2.0 * jit.k(1));
  EXPECT_EQ(b.matrix()->component(1, 0), 2.0);
  std::string stats = jit.stats();
  EXPECT_NE(stats.find("result 0 specialised to 37.5% of its blocks (6 of 16"), std::string::npos)
      << stats;
  EXPECT_NE(stats.find("guard: 1 field version and 0 scalars compared per call"), std::string::npos)
      << stats;
  // Vertex 2 on: every spring writes, 10 of 16 blocks.
  for (Chain* c : {&in, &jit}) c->set_on(2, true);
  for (int call = 0; call < 2; ++call) {
    a = in.step(), b = jit.step();
    expect_same(a, b, "K with vertex 2 on");
  }
  EXPECT_EQ(b.matrix()->pattern().nnz(), 10);
  EXPECT_EQ(b.matrix()->component(2, 3), jit.k(2) * jit.k(3));
  const runtime::PatternPtr all_on = b.matrix()->shared_pattern();
  // `on` written with the values it holds: the guard fails, the blocks recorded are the same
  // and so is the pattern.
  for (Chain* c : {&in, &jit}) c->set_on(2, true);
  for (int call = 0; call < 2; ++call) {
    a = in.step(), b = jit.step();
    expect_same(a, b, "K after rewriting on");
  }
  EXPECT_EQ(b.matrix()->shared_pattern(), all_on);
  stats = jit.stats();
  EXPECT_NE(stats.find("the guard failed on 2 calls"), std::string::npos) << stats;
  EXPECT_EQ(stats.find("full patterns"), std::string::npos) << stats;
  // Written before two calls in a row: the deciding field changes with every call, and the
  // result stays on the full pattern.
  for (int call = 0; call < 3; ++call) {
    for (Chain* c : {&in, &jit}) c->set_on(2, call % 2 == 0);
    a = in.step(), b = jit.step();
    expect_same(a, b, "K with vertex 2 toggled");
  }
  EXPECT_EQ(b.matrix()->pattern().nnz(), 16);
  stats = jit.stats();
  EXPECT_NE(stats.find("full patterns: the inputs that decide the writes changed on two calls in "
                       "a row"),
            std::string::npos)
      << stats;
}

TEST(Jit, ASingularMatrixIsReportedAsTheInterpreterReportsIt) {
  if (!api::jit_available()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  std::string messages[2];
  for (int k = 0; k < 2; ++k) {
    Program r(k ? ExecutorKind::Jit : ExecutorKind::Interpreter, /*inverted=*/false);
    r.call("init");
    // Flatten tet 1 (vertices 1, 2, 3, 4) onto a plane: its F is singular.
    for (int i = 1; i <= 4; ++i) r.mesh.verts.field(0).at<double>(i)[2] = 0.0;
    r.mesh.verts.field(0).at<double>(0)[2] = 0.5;
    try {
      r.call("step");
      ADD_FAILURE() << "no error";
    } catch (const interp::RuntimeError& e) {
      messages[k] = e.render();
    }
  }
  EXPECT_NE(messages[0].find("singular"), std::string::npos) << messages[0];
  EXPECT_EQ(messages[0], messages[1]);
}

TEST(Jit, SwitchingExecutorsMidRunCopiesNothingAndAgrees) {
  if (!api::jit_available()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  Program in(ExecutorKind::Interpreter), mixed(ExecutorKind::Interpreter);
  in.call("init");
  mixed.call("init");
  for (int frame = 0; frame < 4; ++frame) {
    mixed.engine->set_executor(frame % 2 ? ExecutorKind::Interpreter : ExecutorKind::Jit);
    std::vector<Value> a = in.call("step"), b = mixed.call("step");
    expect_same(a[0], b[0], "A");
    expect_same_fields(in.mesh.verts, mixed.mesh.verts);
  }
}

TEST(Jit, CheckModeRunsBothAndNamesTheFirstDifference) {
  if (!api::jit_available()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  for (bool corrupt : {false, true}) {
    auto compiled = CompiledProgram::from_source("jit_test.sim", kProgram);
    Mesh mesh;
    EngineOptions o;
    o.executor.kind = ExecutorKind::Jit;
    o.executor.threshold = 0;
    o.executor.check = true;
    o.corrupt_for_test = corrupt;
    Engine engine(compiled, o);
    engine.bind_set(*compiled->find_extern("verts"), mesh.verts);
    engine.bind_set(*compiled->find_extern("tets"), mesh.tets);
    engine.set_global(*compiled->find_extern("gain"), Value::of_float(0.75));
    std::string error;
    try {
      engine.call(*compiled->find_func("init"), {});
      engine.call(*compiled->find_func("step"), {});
    } catch (const interp::RuntimeError& e) {
      error = e.render();
    }
    if (!corrupt) {
      EXPECT_EQ(error, "");
      continue;
    }
    // `rest` is the first compiled map: its result m at vertex 0 differs in the last bit.
    EXPECT_NE(
        error.find(
            "--check-jit: the compiled rest (line 93) differs from the interpreter in result 'm' "
            "component 0 (entry 0 of the vector): interpreted 0.041078749999999997, "
            "compiled 0.041078750000000004"),
        std::string::npos)
        << error;
  }
}

// The decompositions of docs/intrinsics.md, called from compiled code into the runtime's own
// functions: the same bits as the interpreter, on ordinary, inverted and degenerate elements.
const char* kDecompositions = R"(
element Vertex
  x : vector[3](float);
end
element Tet
  e : float;
end
extern verts : set{Vertex};
extern tets : set{Tet}(verts, verts, verts, verts);

func measures(t : Tet, v : (Vertex * 4)) -> (f : vector[verts](vector[3](float)),
                                              K : matrix[verts,verts](matrix[3,3](float)))
  var F : matrix[3,3](float);
  for j in 0:3
    e = v(j).x - v(3).x;
    for i in 0:3
      F(i, j) = e(i);
    end
  end
  U, s, V = svd(F);
  R, S = polar(F);
  w, Q = eig(F' * F);
  f(v(0)) = s;
  f(v(1)) = w;
  f(v(2)) = U * [1.0, 2.0, 3.0]' + V * [0.5, 0.25, 0.125]';
  f(v(3)) = Q * [1.0, -1.0, 2.0]';
  K(v(0), v(0)) = R;
  K(v(1), v(1)) = S;
  K(v(2), v(2)) = project_spd(S);
  K(v(3), v(3)) = project_spd_abs(S);
end

export func step() -> (f : vector[verts](vector[3](float)), K : matrix[verts,verts](matrix[3,3](float)))
  f, K = map measures to tets reduce +;
end
)";

TEST(Jit, DecompositionsComputeTheInterpretersBits) {
  if (!api::jit_available()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  std::vector<Value> results[2];
  std::string stats;
  for (int k = 0; k < 2; ++k) {
    auto compiled = CompiledProgram::from_source("decompositions.sim", kDecompositions);
    ASSERT_TRUE(compiled->ok());
    runtime::Set verts("verts");
    runtime::Set tets("tets", {&verts, &verts, &verts, &verts});
    verts.add_many(6);
    verts.add_field("x", runtime::FieldType{runtime::ComponentKind::Float, {3}, false});
    // A regular tet, an inverted one, and a flat one (repeated and zero singular values).
    const double x[6][3] = {{0.1, 0.0, 0.03},  {1.07, 0.11, 0.0}, {0.0, 0.93, 0.2},
                            {0.05, 0.1, 1.13}, {0.5, 0.5, 0.0},   {0.0, 0.0, 0.0}};
    for (int i = 0; i < 6; ++i)
      for (int c = 0; c < 3; ++c) verts.field(0).at<double>(i)[c] = x[i][c];
    const int32_t ends[] = {0, 1, 2, 3, 1, 0, 2, 3, 5, 4, 5, 5};
    tets.add_edges(ends);
    tets.add_field("e", runtime::FieldType{runtime::ComponentKind::Float, {}, false});
    EngineOptions o;
    o.executor.kind = k ? ExecutorKind::Jit : ExecutorKind::Interpreter;
    o.executor.threshold = 0;
    Engine engine(compiled, o);
    engine.bind_set(*compiled->find_extern("verts"), verts);
    engine.bind_set(*compiled->find_extern("tets"), tets);
    results[k] = engine.call(*compiled->find_func("step"), {});
    std::ostringstream os;
    engine.print_jit_stats(os);
    if (k) stats = os.str();
  }
  EXPECT_NE(stats.find("measures (line 34)"), std::string::npos) << stats;
  EXPECT_NE(stats.find(" compiled\n"), std::string::npos) << stats;
  expect_same(results[0][0], results[1][0], "f");
  expect_same(results[0][1], results[1][1], "K");
  // Real values: the first tet's singular values are positive and descending.
  const double* s = results[0][0].tensor().floats();
  EXPECT_GT(s[0], s[1]);
  EXPECT_GT(s[1], 0.0);
}

// A Newton step's element Hessian as examples/fem/fem_newton.sim builds it: a blocked local
// of 4 x 4 blocks of 3 x 3 written component by component, projected to positive
// semi-definite as one 12 x 12 matrix when `project`, and assembled by blocks; then the
// block-Jacobi preconditioner reads each vertex's diagonal block of the assembled matrix.
// lambda < 0 makes the element matrices indefinite, so that the projection changes them.
const char* kBlocked = R"(
element Vertex
  x : vector[3](float);
  v : vector[3](float);
  m : float;
  pinned : bool;
end
element Tet
  B : matrix[3,3](float);
  W : float;
end
extern verts : set{Vertex};
extern tets : set{Tet}(verts, verts, verts, verts);

const eye3 = [1.0, 0.0, 0.0; 0.0, 1.0, 0.0; 0.0, 0.0, 1.0];

func edge_matrix(v : (Vertex * 4)) -> D : matrix[3,3](float)
  for j in 0:3
    e = v(j).x - v(3).x;
    for i in 0:3
      D(i, j) = e(i);
    end
  end
end

func rest(inout t : Tet, v : (Vertex * 4)) -> m : vector[verts](float)
  Dm = edge_matrix(v);
  t.B = inv(Dm);
  t.W = -det(Dm) / 6.0;
  for j in 0:4
    m(v(j)) = 0.25 * t.W;
  end
end

func gradient(B : matrix[3,3](float), j : int) -> g : vector[3](float)
  if j < 3
    g = B(j, :)';
  else
    g = -(B(0, :) + B(1, :) + B(2, :))';
  end
end

func unit(d : int) -> u : vector[3](float)
  u(d) = 1.0;
end

func derivatives(mu : float, lambda : float, project : bool, t : Tet, v : (Vertex * 4))
    -> (g : vector[verts](vector[3](float)), H : matrix[verts,verts](matrix[3,3](float)))
  F = edge_matrix(v) * t.B;
  var He : matrix[4,4](matrix[3,3](float));
  for j in 0:4
    gj = gradient(t.B, j);
    if not v(j).pinned
      g(v(j)) = t.W * ((F - eye3) * gj);
    end
    for d in 0:3
      for i in 0:4
        gi = gradient(t.B, i);
        col = t.W * (mu * dot(gi, gj) * unit(d) + (mu * gi(d)) * gj + (lambda * gj(d)) * gi);
        for a in 0:3
          He(i, j)(a, d) = col(a);
        end
      end
    end
  end
  if project
    He = project_spd(He);
  end
  for i in 0:4
    for j in 0:4
      if not (v(i).pinned or v(j).pinned)
        H(v(i), v(j)) = He(i, j);
      end
    end
  end
end

func jacobi(H : matrix[verts,verts](matrix[3,3](float)), p : Vertex)
    -> Pc : matrix[verts,verts](matrix[3,3](float))
  Pc(p, p) = inv(project_spd_abs(p.m * eye3 + 0.01 * H(p, p)));
end

export func init()
  verts.m = map rest to tets reduce +;
end

export func step() -> (g : vector[verts](vector[3](float)), H : matrix[verts,verts](matrix[3,3](float)),
                       Pc : matrix[verts,verts](matrix[3,3](float)),
                       H2 : matrix[verts,verts](matrix[3,3](float)))
  g, H = map derivatives(1.5, -4.0, true) to tets reduce +;
  Pc = map jacobi(H) to verts reduce +;
  g2, H2 = map derivatives(1.5, -4.0, false) to tets reduce +;
end
)";

TEST(Jit, BlockedElementMatricesAndMatrixBlockReadsComputeTheInterpretersBits) {
  if (!api::jit_available()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  std::vector<Value> results[2];
  std::string stats;
  for (int k = 0; k < 2; ++k) {
    auto compiled = CompiledProgram::from_source("blocked.sim", kBlocked);
    ASSERT_TRUE(compiled->ok());
    Mesh mesh;
    EngineOptions o;
    o.executor.kind = k ? ExecutorKind::Jit : ExecutorKind::Interpreter;
    o.executor.threshold = 0;
    Engine engine(compiled, o);
    engine.bind_set(*compiled->find_extern("verts"), mesh.verts);
    engine.bind_set(*compiled->find_extern("tets"), mesh.tets);
    engine.call(*compiled->find_func("init"), {});
    for (int frame = 0; frame < 2; ++frame)
      results[k] = engine.call(*compiled->find_func("step"), {});
    std::ostringstream os;
    engine.print_jit_stats(os);
    if (k) stats = os.str();
  }
  for (const char* site : {"derivatives (line 90)", "jacobi (line 91)", "derivatives (line 92)"}) {
    const size_t at = stats.find(site);
    ASSERT_NE(at, std::string::npos) << site << "\n" << stats;
    EXPECT_NE(stats.substr(at, stats.find('\n', at) - at).find(" compiled"), std::string::npos)
        << site << "\n"
        << stats;
  }
  const char* names[] = {"g", "H", "Pc", "H2"};
  for (int r = 0; r < 4; ++r) expect_same(results[0][r], results[1][r], names[r]);
  // The projection changed the indefinite element matrices: H and H2 differ off vertex 0's
  // rows and columns (pinned, left out of both).
  const runtime::SystemMatrix &h = *results[0][1].matrix(), &h2 = *results[0][3].matrix();
  double change = 0.0;
  for (int64_t i = 3; i < h.scalar_rows(); ++i)
    for (int64_t j = 3; j < h.scalar_cols(); ++j)
      change = std::max(change, std::fabs(h.component(i, j) - h2.component(i, j)));
  EXPECT_GT(change, 1e-3);
}

// The 1-based line of the first line of `text` that contains `what`.
int line_of(const std::string& s, const std::string& what) {
  const size_t at = s.find(what);
  return 1 + static_cast<int>(std::count(s.begin(), s.begin() + static_cast<long>(at), '\n'));
}

// A program whose `step` maps over a set `points` of `count` elements, whose fields `fill`
// adds, run interpreted and then by the JIT at threshold 0: both runs' results, the JIT's
// loop-IR dump and its stats.
struct PointsRuns {
  std::vector<Value> results[2];
  std::string dump, stats;
};
PointsRuns run_points_both_ways(const char* file, const char* program, int count,
                                const std::function<void(runtime::Set&)>& fill) {
  PointsRuns out;
  for (int k = 0; k < 2; ++k) {
    auto compiled = CompiledProgram::from_source(file, program);
    EXPECT_TRUE(compiled->ok());
    if (!compiled->ok()) return out;
    runtime::Set points("points");
    points.add_many(count);
    fill(points);
    std::ostringstream dumped;
    EngineOptions o;
    o.executor.kind = k ? ExecutorKind::Jit : ExecutorKind::Interpreter;
    o.executor.threshold = 0;
    o.dump = &dumped;
    o.executor.dump_loop_ir = true;
    Engine engine(compiled, o);
    engine.bind_set(*compiled->find_extern("points"), points);
    out.results[k] = engine.call(*compiled->find_func("step"), {});
    std::ostringstream os;
    engine.print_jit_stats(os);
    if (k) out.stats = os.str(), out.dump = dumped.str();
  }
  return out;
}

// The loops (For statements) of a loop-IR dump.
size_t count_loops(const std::string& dump) {
  size_t loops = 0;
  for (size_t at = dump.find("for %"); at != std::string::npos; at = dump.find("for %", at + 1))
    ++loops;
  return loops;
}

// Products too large to unroll run as loops over tiles of scratch arrays: a 26 x 7 by 7 x 13
// product (tiles of 2 x 1: the largest extents up to 12 that divide 26 and 13), in one branch
// of an if, or its transpose's transpose in the other (the same bits: each term is a
// product of the same two factors), then P'P, 0.5 * Q + Q and zeros plus that as loops over
// the arrays (169 components), minus an unrolled diagonal matrix (put into an array beside
// them), and that matrix, and its transpose, times a vector. Each component
// is summed from +0.0 in ascending k like the interpreter's, so the bits equal both the
// interpreter's and a plain C++ loop's.
TEST(Jit, ProductsTooLargeToUnrollRunTiledWithTheInterpretersBits) {
  if (!api::jit_available()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  const char* program = R"(
element Point
  a : float;
end
extern points : set{Point};
func tiles(p : Point) -> r : vector[points](vector[6](float))
  var L : matrix[26,7](float);
  var R : matrix[7,13](float);
  var w = 0.0;
  for i in 0:26
    for k in 0:7
      w = w + 0.37;
      L(i, k) = sin(w) * p.a;
    end
  end
  for k in 0:7
    for j in 0:13
      w = w - 0.29;
      R(k, j) = cos(w) + p.a;
    end
  end
  var P : matrix[26,13](float);
  if p.a > 0.0
    P = L * R;
  else
    P = (R' * L')';
  end
  Q = P' * P;
  S = 0.5 * Q + Q;
  var D : matrix[13,13](float);
  for i in 0:13
    D(i, i) = p.a;
  end
  var Z : matrix[13,13](float);
  Z = Z + (S - D);
  var x : vector[13](float);
  for k in 0:13
    x(k) = R(3, k) - p.a;
  end
  y = Z * x;
  u = Z' * x;
  var v : vector[6](float);
  v(0) = P(25, 12);
  v(1) = P(3, 7);
  v(2) = Q(12, 12);
  v(3) = Z(0, 5);
  v(4) = y(11);
  v(5) = u(4);
  r(p) = v;
end
export func step() -> r : vector[points](vector[6](float))
  r = map tiles to points;
end
)";
  const double as[] = {0.5, -1.25, 3.0};
  const auto [results, dump, stats] =
      run_points_both_ways("tiles.sim", program, 3, [&](runtime::Set& points) {
        points.add_field("a", runtime::FieldType{runtime::ComponentKind::Float, {}, false});
        for (int i = 0; i < 3; ++i) points.field(0).at<double>(i)[0] = as[i];
      });
  EXPECT_NE(stats.find("tiles (line " + std::to_string(line_of(program, "map tiles")) + ")"),
            std::string::npos)
      << stats;
  EXPECT_EQ(stats.find("interpreted"), std::string::npos) << stats;
  // Four loops per product (tiles down, tiles across, a tile's rows, k), one per element-wise
  // operation (S - D, D put into an array; Z + (S - D) too: Z's zeros are one value for every
  // component) and one per matrix-vector product (Z * x, and Z' * x reading Z's array
  // transposed).
  EXPECT_EQ(count_loops(dump), 4u * 3u + 4u + 2u) << dump;
  expect_same(results[0][0], results[1][0], "r");
  // The reference: the same sums in plain C++.
  for (int e = 0; e < 3; ++e) {
    double L[26][7], R[7][13], P[26][13], Q[13][13], w = 0.0;
    for (auto& row : L)
      for (double& x : row) w = w + 0.37, x = std::sin(w) * as[e];
    for (auto& row : R)
      for (double& x : row) w = w - 0.29, x = std::cos(w) + as[e];
    for (int i = 0; i < 26; ++i)
      for (int j = 0; j < 13; ++j) {
        P[i][j] = 0.0;
        for (int k = 0; k < 7; ++k) P[i][j] = P[i][j] + L[i][k] * R[k][j];
      }
    for (int i = 0; i < 13; ++i)
      for (int j = 0; j < 13; ++j) {
        Q[i][j] = 0.0;
        for (int k = 0; k < 26; ++k) Q[i][j] = Q[i][j] + P[k][i] * P[k][j];
      }
    double Z[13][13], wv[13], y = 0.0, u = 0.0;
    for (int i = 0; i < 13; ++i)
      for (int j = 0; j < 13; ++j)
        Z[i][j] = 0.0 + ((0.5 * Q[i][j] + Q[i][j]) - (i == j ? as[e] : 0.0));
    for (int k = 0; k < 13; ++k) wv[k] = R[3][k] - as[e];
    for (int k = 0; k < 13; ++k) y = y + Z[11][k] * wv[k];
    for (int k = 0; k < 13; ++k) u = u + Z[k][4] * wv[k];
    const double want[6] = {P[25][12], P[3][7], Q[12][12], Z[0][5], y, u};
    expect_same_bits(results[1][0].tensor().floats() + 6 * e, want, 6,
                     "element " + std::to_string(e));
  }
}

// Tensors of more than 144 components that come from fields, outer products and element-wise
// operations lie in scratch arrays and run as loops: a 13 x 13 field is loaded by one loop
// (binary64 and binary32 storage; a second read of it reuses the array), the outer product
// u w' is one loop over u, and the sums, differences, scaling and both kinds of
// matrix-vector product (T u, w' T, A' w, u' S') one loop each. The bits equal the interpreter's
// and a plain C++ loop's.
TEST(Jit, LargeTensorsFromFieldsAndOuterProductsRunAsLoops) {
  if (!api::jit_available()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  const char* program = R"(
element Point
  A : matrix[13,13](float);
  B : matrix[13,13](float);
  u : vector[13](float);
  w : vector[13](float);
  a : float;
end
extern points : set{Point};
func big(p : Point) -> r : vector[points](vector[8](float))
  O = p.u * p.w';
  S = p.A + O;
  T = p.a * p.B - S;
  y = T * p.u;
  z = p.w' * T;
  q = p.A' * p.w;
  t = p.u' * S';
  var v : vector[8](float);
  v(0) = T(12, 3);
  v(1) = y(7);
  v(2) = z(11);
  v(3) = q(5);
  v(4) = O(4, 9);
  v(5) = S(0, 12) + p.A(3, 3);
  v(6) = p.B(2, 11);
  v(7) = t(4);
  r(p) = v;
end
export func step() -> r : vector[points](vector[8](float))
  r = map big to points;
end
)";
  constexpr int n = 13, count = 3;
  // The fields' values: A, B (binary32), u, w, a per element.
  auto value = [](int field, int e, int k) {
    return std::sin(0.37 * (k + 1) + 1.3 * field + 0.71 * e) * (1.0 + field);
  };
  double stored_b[count][n * n];
  const auto [results, dump, stats] =
      run_points_both_ways("big.sim", program, count, [&](runtime::Set& points) {
        points.add_field("A", runtime::FieldType{runtime::ComponentKind::Float, {n, n}, false});
        points.add_field("B", runtime::FieldType{runtime::ComponentKind::Float, {n, n}, true});
        points.add_field("u", runtime::FieldType{runtime::ComponentKind::Float, {n}, false});
        points.add_field("w", runtime::FieldType{runtime::ComponentKind::Float, {n}, false});
        points.add_field("a", runtime::FieldType{runtime::ComponentKind::Float, {}, false});
        auto field = [&](const char* name) -> runtime::Field& {
          return points.field(points.field_index(name));
        };
        for (int e = 0; e < count; ++e) {
          for (int k = 0; k < n * n; ++k) {
            field("A").at<double>(e)[k] = value(0, e, k);
            field("B").at<float>(e)[k] = static_cast<float>(value(1, e, k));
            // The reference reads B back as stored (rounded to binary32).
            stored_b[e][k] = field("B").at<float>(e)[k];
          }
          for (int k = 0; k < n; ++k) {
            field("u").at<double>(e)[k] = value(2, e, k);
            field("w").at<double>(e)[k] = value(3, e, k);
          }
          field("a").at<double>(e)[0] = value(4, e, 0);
        }
      });
  EXPECT_NE(stats.find("big (line " + std::to_string(line_of(program, "map big")) + ")"),
            std::string::npos)
      << stats;
  EXPECT_EQ(stats.find("interpreted"), std::string::npos) << stats;
  // Loads of A and B, the outer product, A + O, a * B, minus S, T u, w' T, A' w and u' S'.
  EXPECT_EQ(count_loops(dump), 10u) << dump;
  // No component of the 13 x 13 fields is loaded one by one.
  EXPECT_EQ(dump.find("].168"), std::string::npos) << dump;
  expect_same(results[0][0], results[1][0], "r");
  // The reference: the same operations in plain C++.
  for (int e = 0; e < count; ++e) {
    double A[n][n], B[n][n], u[n], w[n], O[n][n], S[n][n], T[n][n];
    for (int i = 0; i < n; ++i) {
      u[i] = value(2, e, i);
      w[i] = value(3, e, i);
      for (int j = 0; j < n; ++j) {
        A[i][j] = value(0, e, i * n + j);
        B[i][j] = stored_b[e][i * n + j];
      }
    }
    const double a = value(4, e, 0);
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) {
        O[i][j] = u[i] * w[j];
        S[i][j] = A[i][j] + O[i][j];
        T[i][j] = a * B[i][j] - S[i][j];
      }
    double y = 0.0, z = 0.0, q = 0.0, t = 0.0;
    for (int k = 0; k < n; ++k) {
      y = y + T[7][k] * u[k];
      z = z + w[k] * T[k][11];
      q = q + A[k][5] * w[k];
      t = t + u[k] * S[4][k];
    }
    const double want[8] = {T[12][3], y, z, q, O[4][9], S[0][12] + A[3][3], B[2][11], t};
    expect_same_bits(results[1][0].tensor().floats() + 8 * e, want, 8,
                     "element " + std::to_string(e));
  }
}

// Every component of a dense local becomes a value of its own: a tensor of more than
// kMaxDenseComponents stays interpreted, saying why, and computes what the interpreter does.
// The mapped function's two writes to its result are no run of statements of their own.
TEST(Jit, ADenseLocalAboveTheComponentLimitStaysInterpreted) {
  if (!api::jit_available()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  const char* program = R"(
element Point
  a : float;
end
extern points : set{Point};
func fill(p : Point) -> r : vector[points](float)
  var A : matrix[8,8](matrix[8,8](float));
  A(7, 7)(7, 7) = p.a;
  r(p) = 0.0;
  r(p) = A(7, 7)(7, 7) + 1.0;
end
export func step() -> r : vector[points](float)
  r = map fill to points;
end
)";
  auto compiled = CompiledProgram::from_source("limit.sim", program);
  ASSERT_TRUE(compiled->ok());
  runtime::Set points("points");
  points.add_many(3);
  points.add_field("a", runtime::FieldType{runtime::ComponentKind::Float, {}, false});
  for (int i = 0; i < 3; ++i) points.field(0).at<double>(i)[0] = 0.5 * i;
  EngineOptions o;
  o.executor.kind = ExecutorKind::Jit;
  o.executor.threshold = 0;
  Engine engine(compiled, o);
  engine.bind_set(*compiled->find_extern("points"), points);
  const std::vector<Value> r = engine.call(*compiled->find_func("step"), {});
  std::ostringstream os;
  engine.print_jit_stats(os);
  const std::string limit = std::to_string(kMaxDenseComponents);
  EXPECT_NE(os.str().find("interpreted: a dense tensor of 4096 components (more than " + limit +
                          ") is not compiled (line 7)"),
            std::string::npos)
      << os.str();
  for (int i = 0; i < 3; ++i) EXPECT_EQ(r[0].tensor().floats()[i], 0.5 * i + 1.0);
  EXPECT_EQ(os.str().find("statement"), std::string::npos) << os.str();
}

// The matrix of a chain of links between points (springs and a diagonal), for the solver
// tests: the program declares Point (with b and d), Link (with k), points and links.
const char* const kChainMatrix = R"(
func stiffness(l : Link, p : (Point * 2)) -> A : matrix[points,points](float)
  A(p(0), p(0)) = l.k;
  A(p(1), p(1)) = l.k;
  A(p(0), p(1)) = -0.5 * l.k;
  A(p(1), p(0)) = -0.5 * l.k;
end

func diagonal(q : Point) -> D : matrix[points,points](float)
  D(q, q) = q.d;
end
)";

// A CG loop compiled whole: three loops per iteration after fusion, the interpreter's bits.
const std::string kSolver = R"(
element Point
  b : float;
  d : float;
end
element Link
  k : float;
end
extern points : set{Point};
extern links : set{Link}(points, points);
)" + std::string(kChainMatrix) +
                            R"(
export func solve() -> (x : vector[points](float), iterations : int)
  A = (map stiffness to links reduce +) + (map diagonal to points reduce +);
  b = points.b;
  x = 0.0 * b;
  var r = b;
  var p = r;
  var rr = r' * r;
  while (rr > 1e-20) and (iterations < 50)
    Ap = A * p;
    alpha = rr / (p' * Ap);
    x = x + alpha * p;
    r = r - alpha * Ap;
    rr_new = r' * r;
    p = r + (rr_new / rr) * p;
    rr = rr_new;
    iterations = iterations + 1;
  end
end
)";

TEST(Jit, ASolverLoopFusesIntoThreeLoopsAndComputesTheInterpretersBits) {
  if (!api::jit_available()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  std::vector<Value> results[2];
  std::string dump, stats;
  for (int k = 0; k < 2; ++k) {
    auto compiled = CompiledProgram::from_source("solver.sim", kSolver);
    ASSERT_TRUE(compiled->ok());
    runtime::Set points("points");
    runtime::Set links("links", {&points, &points});
    const int n = 40;
    points.add_many(n);
    points.add_field("b", runtime::FieldType{runtime::ComponentKind::Float, {}, false});
    points.add_field("d", runtime::FieldType{runtime::ComponentKind::Float, {}, false});
    links.add_field("k", runtime::FieldType{runtime::ComponentKind::Float, {}, false});
    for (int i = 0; i < n; ++i) {
      points.field(0).at<double>(i)[0] = std::sin(0.3 * i);
      points.field(1).at<double>(i)[0] = 0.1 + 0.01 * i;
      if (i + 1 < n) links.add({i, i + 1});
    }
    for (int e = 0; e < links.size(); ++e)
      links.field(0).at<double>(e)[0] = 1.0 + 0.5 * std::cos(e);
    std::ostringstream dumped;
    EngineOptions o;
    o.executor.kind = k ? ExecutorKind::Jit : ExecutorKind::Interpreter;
    o.executor.threshold = 0;
    o.dump = &dumped;
    o.executor.dump_loop_ir = true;
    Engine engine(compiled, o);
    engine.bind_set(*compiled->find_extern("points"), points);
    engine.bind_set(*compiled->find_extern("links"), links);
    results[k] = engine.call(*compiled->find_func("solve"), {});
    std::ostringstream os;
    engine.print_jit_stats(os);
    if (k) {
      dump = dumped.str();
      stats = os.str();
    }
  }
  // The loop: the product with p'Ap, one pass for x, r and r'r, one for p.
  const size_t begin = dump.find("  while ");
  ASSERT_NE(begin, std::string::npos) << dump;
  const std::string loop = dump.substr(begin, dump.find("  after", begin) - begin);
  auto count = [&](const std::string& what) {
    size_t c = 0;
    for (size_t at = loop.find(what); at != std::string::npos; at = loop.find(what, at + 1)) ++c;
    return c;
  };
  EXPECT_EQ(count(" = spmv("), 1u) << loop;
  EXPECT_EQ(count("pass over"), 2u) << loop;
  // Six loops before fusion (the product, p'Ap, x, r, r'r, p), three after; the set-up before
  // the loop (x, r, p and r'r) is one pass.
  EXPECT_NE(stats.find(" compiled"), std::string::npos) << stats;
  const size_t setup_at = dump.find("  before");
  ASSERT_LT(setup_at, begin) << dump;
  const std::string setup = dump.substr(setup_at, begin - setup_at);
  EXPECT_NE(setup.find("pass over"), std::string::npos) << setup;
  EXPECT_EQ(setup.find("pass over", setup.find("pass over") + 1), std::string::npos) << setup;
  ASSERT_EQ(results[0][1].as_int(), results[1][1].as_int());
  EXPECT_GT(results[0][1].as_int(), 5);  // CG took real iterations
  expect_same(results[0][0], results[1][0], "x");
}

// --check-finite compiled: a check after every operation, as the interpreter does; a map's
// error is reported by the interpreter running it again, an apply's by the kernel.
const char* kFinite = R"(
element P
  a : float;
  b : float;
end
extern ps : set{P};

func logs(p : P) -> r : vector[ps](float)
  r(p) = 2.0 * log(p.a);
end

func roots(inout p : P)
  p.b = sqrt(p.a) + 1.0;
end

export func map_it() -> (r : vector[ps](float))
  r = map logs to ps reduce +;
end

export func apply_it()
  apply roots to ps;
end
)";

TEST(Jit, CheckFiniteIsCompiledAndStopsWhereTheInterpreterStops) {
  if (!api::jit_available()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  std::string messages[2][2], stats;
  for (int k = 0; k < 2; ++k) {
    auto compiled = CompiledProgram::from_source("finite.sim", kFinite);
    ASSERT_TRUE(compiled->ok());
    runtime::Set ps("ps");
    ps.add_many(5);
    ps.add_field("a", runtime::FieldType{runtime::ComponentKind::Float, {}, false});
    ps.add_field("b", runtime::FieldType{runtime::ComponentKind::Float, {}, false});
    for (int i = 0; i < 5; ++i) ps.field(0).at<double>(i)[0] = i == 3 ? -1.0 : 1.0 + i;
    EngineOptions o;
    o.executor.kind = k ? ExecutorKind::Jit : ExecutorKind::Interpreter;
    o.executor.threshold = 0;
    o.check_finite = true;
    Engine engine(compiled, o);
    engine.bind_set(*compiled->find_extern("ps"), ps);
    for (int f = 0; f < 2; ++f) {
      try {
        engine.call(*compiled->find_func(f ? "apply_it" : "map_it"), {});
      } catch (const interp::RuntimeError& e) {
        messages[k][f] = e.render();
      }
    }
    std::ostringstream os;
    engine.print_jit_stats(os);
    if (k) stats = os.str();
  }
  EXPECT_NE(stats.find("logs (line 17)"), std::string::npos) << stats;
  EXPECT_NE(stats.find("roots (line 21)"), std::string::npos) << stats;
  EXPECT_EQ(stats.find("interpreted"), std::string::npos) << stats;
  // The map: the interpreter's own words (it ran the site again).
  EXPECT_NE(messages[0][0].find("finite.sim:9:16: runtime error: the operation produced NaN"),
            std::string::npos)
      << messages[0][0];
  EXPECT_EQ(messages[0][0], messages[1][0]);
  // The apply: the same place and element, in the kernel's words.
  EXPECT_NE(messages[0][1].find("finite.sim:13:9: runtime error: the operation produced NaN"),
            std::string::npos)
      << messages[0][1];
  EXPECT_NE(messages[1][1].find(
                "finite.sim:13:9: runtime error: the operation produced a NaN or an infinity"),
            std::string::npos)
      << messages[1][1];
  EXPECT_NE(messages[1][1].find("in roots (finite.sim:13), mapping over element 3 of set 'ps'"),
            std::string::npos)
      << messages[1][1];
}

// Error statements: a map compiles one as a check that always fails, so the interpreter runs
// the site again and reports it; an apply that writes fields stays interpreted.
const char* const kErrorStatements = R"(element P
  a : float;
  b : float;
end
extern ps : set{P};

func checked(p : P) -> r : vector[ps](float)
  if p.a < 0.0
    error "a = ", p.a, " < 0";
  end
  r(p) = 2.0 * p.a;
end

func guarded(inout p : P)
  p.b = 3.0 * p.a;
  if p.a < 0.0
    error "a = ", p.a, " < 0 in an apply";
  end
end

export func map_it() -> (r : vector[ps](float))
  r = map checked to ps reduce +;
end

export func apply_it()
  apply guarded to ps;
end
)";

struct ErrorRun {
  std::string messages[2];
  std::vector<double> r, b;
  std::string stats;
};

ErrorRun run_errors(ExecutorKind kind, bool bad) {
  auto compiled = CompiledProgram::from_source("errors.sim", kErrorStatements);
  EXPECT_TRUE(compiled->ok());
  runtime::Set ps("ps");
  ps.add_many(5);
  ps.add_field("a", runtime::FieldType{runtime::ComponentKind::Float, {}, false});
  ps.add_field("b", runtime::FieldType{runtime::ComponentKind::Float, {}, false});
  for (int i = 0; i < 5; ++i) ps.field(0).at<double>(i)[0] = bad && i == 3 ? -1.5 : 0.25 * i;
  EngineOptions o;
  o.executor.kind = kind;
  o.executor.threshold = 0;
  Engine engine(compiled, o);
  engine.bind_set(*compiled->find_extern("ps"), ps);
  ErrorRun run;
  for (int f = 0; f < 2; ++f) {
    try {
      std::vector<Value> res = engine.call(*compiled->find_func(f ? "apply_it" : "map_it"), {});
      if (!f) run.r.assign(res[0].tensor().floats(), res[0].tensor().floats() + 5);
    } catch (const interp::RuntimeError& e) {
      run.messages[f] = e.render();
    }
  }
  for (int i = 0; i < 5; ++i) run.b.push_back(ps.field(1).at<double>(i)[0]);
  std::ostringstream os;
  engine.print_jit_stats(os);
  run.stats = os.str();
  return run;
}

TEST(Jit, ErrorStatementsAreReportedInTheInterpretersWords) {
  if (!api::jit_available()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  for (bool bad : {false, true}) {
    const ErrorRun in = run_errors(ExecutorKind::Interpreter, bad);
    const ErrorRun jit = run_errors(ExecutorKind::Jit, bad);
    for (int f = 0; f < 2; ++f) EXPECT_EQ(in.messages[f], jit.messages[f]) << f;
    EXPECT_EQ(in.r, jit.r);
    EXPECT_EQ(in.b, jit.b);
    // The map is compiled; the apply is not, and says why.
    std::istringstream lines(jit.stats);
    bool map_seen = false;
    for (std::string line; std::getline(lines, line);)
      if (line.find("checked (line 22)") != std::string::npos) {
        map_seen = true;
        EXPECT_EQ(line.find("interpreted"), std::string::npos) << jit.stats;
      }
    EXPECT_TRUE(map_seen) << jit.stats;
    EXPECT_NE(jit.stats.find("interpreted: error statements in an apply with inout fields are "
                             "not compiled (line 17)"),
              std::string::npos)
        << jit.stats;
    if (!bad) {
      EXPECT_EQ(jit.r, (std::vector<double>{0.0, 0.5, 1.0, 1.5, 2.0}));
      EXPECT_EQ(jit.b, (std::vector<double>{0.0, 0.75, 1.5, 2.25, 3.0}));
      EXPECT_EQ(jit.messages[0], "");
      EXPECT_EQ(jit.messages[1], "");
      continue;
    }
    EXPECT_EQ(jit.messages[0],
              "errors.sim:9:5: runtime error: a = -1.5 < 0\n"
              "  in checked (errors.sim:9), mapping over element 3 of set 'ps'\n"
              "  in map_it (errors.sim:22)\n");
    EXPECT_EQ(jit.messages[1],
              "errors.sim:17:5: runtime error: a = -1.5 < 0 in an apply\n"
              "  in guarded (errors.sim:17), mapping over element 3 of set 'ps'\n"
              "  in apply_it (errors.sim:26)\n");
    // The apply stopped at element 3, which had already written its b.
    EXPECT_EQ(jit.b, (std::vector<double>{0.0, 0.75, 1.5, -4.5, 0.0}));
  }
}

// ---------------------------------------------------------------------------
// Zero folding (jit/zero_fold.h)

const char* const kZeros = R"(element P
  x : float;
  y : vector[3](float);
end
extern ps : set{P};

func unit(d : int) -> e : vector[3](float)
  e(d) = 1.0;
end

func outer(p : P) -> r : vector[ps](vector[3](float))
  M = unit(1) * p.y';
  r(p) = M * p.y;
end

func reciprocal(p : P) -> q : vector[ps](float)
  z = p.x * unit(1)(0);
  q(p) = 1.0 / z;
end

export func main() -> (r : vector[ps](vector[3](float)), q : vector[ps](float))
  r = map outer to ps reduce +;
  q = map reciprocal to ps reduce +;
end
)";

struct ZeroRun {
  std::vector<Value> results;
  std::string dump, stats;
};

// y of element 2 holds an infinity when `inf` is set: 0 * inf is NaN, not 0.
ZeroRun run_zeros(ExecutorKind kind, bool inf) {
  auto compiled = CompiledProgram::from_source("zeros.sim", kZeros);
  EXPECT_TRUE(compiled->ok());
  runtime::Set ps("ps");
  ps.add_many(4);
  ps.add_field("x", runtime::FieldType{runtime::ComponentKind::Float, {}, false});
  ps.add_field("y", runtime::FieldType{runtime::ComponentKind::Float, {3}, false});
  for (int i = 0; i < 4; ++i) {
    ps.field(0).at<double>(i)[0] = i % 2 ? -2.0 - i : 3.0 + i;  // odd elements negative
    for (int k = 0; k < 3; ++k) ps.field(1).at<double>(i)[k] = 0.5 * (i + 1) - 0.75 * k;
  }
  if (inf) ps.field(1).at<double>(2)[2] = HUGE_VAL;
  std::ostringstream dump;
  EngineOptions o;
  o.executor.kind = kind;
  o.executor.threshold = 0;
  o.dump = &dump;
  o.executor.dump_loop_ir = true;
  Engine engine(compiled, o);
  engine.bind_set(*compiled->find_extern("ps"), ps);
  ZeroRun r;
  r.results = engine.call(*compiled->find_func("main"), {});
  std::ostringstream stats;
  engine.print_jit_stats(stats);
  r.dump = dump.str();
  r.stats = stats.str();
  return r;
}

TEST(Jit, ProductsByKnownZerosFoldWhereTheyCannotChangeAValue) {
  if (!api::jit_available()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  for (bool inf : {false, true}) {
    const ZeroRun in = run_zeros(ExecutorKind::Interpreter, inf);
    const ZeroRun jit = run_zeros(ExecutorKind::Jit, inf);
    const double* a = in.results[0].tensor().floats();
    const double* b = jit.results[0].tensor().floats();
    for (size_t i = 0; i < 12; ++i) {
      // Row 1 of the outer product is y', so r(p) = (0, y'y, 0); rows 0 and 2 are zeros
      // whose sign the interpreter takes from y (its 0 * y(k)), the JIT from nothing.
      if (std::isnan(a[i])) {
        EXPECT_TRUE(std::isnan(b[i])) << i;
        continue;
      }
      EXPECT_EQ(a[i], b[i]) << "r[" << i << "] inf " << inf;
    }
    // Element 2's y holds an infinity: 0 * inf is NaN in its rows 0 and 2, and the JIT's check
    // of the folded factors handed the call back to the interpreter, which computed it.
    EXPECT_EQ(std::isnan(a[6]), inf);
    EXPECT_EQ(a[1], 0.5 * 0.5 + -0.25 * -0.25 + -1.0 * -1.0);
    // 1 / (x * 0) depends on the zero's sign (-inf for negative x): not folded, exact.
    const double* qa = in.results[1].tensor().floats();
    const double* qb = jit.results[1].tensor().floats();
    for (int i = 0; i < 4; ++i) {
      EXPECT_EQ(qa[i], i % 2 ? -HUGE_VAL : HUGE_VAL) << i;
      EXPECT_EQ(qb[i], qa[i]) << i;
    }
    // Both sites compiled; the outer product's zero rows left no multiplication behind.
    EXPECT_NE(jit.stats.find("outer (line 22)"), std::string::npos) << jit.stats;
    EXPECT_EQ(jit.stats.find("interpreted"), std::string::npos) << jit.stats;
    const size_t outer = jit.dump.find("trace outer"), next = jit.dump.find("trace reciprocal");
    ASSERT_NE(outer, std::string::npos) << jit.dump;
    const std::string body = jit.dump.substr(outer, next - outer);
    size_t products = 0;
    for (size_t at = body.find(" * "); at != std::string::npos; at = body.find(" * ", at + 1))
      ++products;
    EXPECT_EQ(products, 3u) << body;  // y'y: three products
    EXPECT_NE(body.find("check"), std::string::npos) << body;
  }
}

// Map kernels compute four elements at once, one per SIMD lane, then run each element's writes,
// branches and checks in order. Eleven springs: two full groups and one of three; the
// branches differ between lanes of one group, and the results are the interpreter's bits.
const char* const kLanes = R"(element P
  x : vector[3](float);
  fixed : bool;
end
element S
  k : float;
end
extern ps : set{P};
extern ss : set{S}(ps, ps);

func pull(s : S, p : (P * 2)) -> (f : vector[ps](vector[3](float)), K : matrix[ps,ps](matrix[3,3](float)))
  d = p(1).x - p(0).x;
  l = norm(d);
  t = (s.k * (l - 1.0) / l) * d;
  if not p(0).fixed
    f(p(0)) = t;
    K(p(0), p(0)) = (s.k / l) * (d * d');
  end
  if not p(1).fixed
    f(p(1)) = -t;
    K(p(1), p(1)) = (s.k / (l * l)) * (d * d');
  end
  if not (p(0).fixed or p(1).fixed)
    K(p(0), p(1)) = -exp(-l) * (d * d');
  end
end

func ratio(s : S, p : (P * 2)) -> r : vector[ss](float)
  r(s) = log(s.k) * p(1).x(0);
end

export func both() -> (f : vector[ps](vector[3](float)), K : matrix[ps,ps](matrix[3,3](float)))
  f, K = map pull to ss reduce +;
end

export func ratios() -> r : vector[ss](float)
  r = map ratio to ss reduce +;
end
)";

struct LaneRun {
  std::vector<Value> results;
  std::string stats, error;
};

LaneRun run_lanes(ExecutorKind kind, const char* function, int zero_at = -1) {
  auto compiled = CompiledProgram::from_source("lanes.sim", kLanes);
  EXPECT_TRUE(compiled->ok());
  runtime::Set ps("ps"), ss("ss", {&ps, &ps});
  const int n = 12;
  ps.add_many(n);
  ps.add_field("x", runtime::FieldType{runtime::ComponentKind::Float, {3}, false});
  ps.add_field("fixed", runtime::FieldType{runtime::ComponentKind::Bool, {}, false});
  for (int i = 0; i < n; ++i) {
    for (int k = 0; k < 3; ++k) ps.field(0).at<double>(i)[k] = 0.3 + 0.71 * i - 0.13 * k * i;
    ps.field(1).at<bool>(i)[0] = i % 5 == 2;  // lanes of one group take different branches
  }
  std::vector<int32_t> ends;
  for (int i = 0; i + 1 < n; ++i) ends.insert(ends.end(), {i, (5 * i + 3) % n});
  ss.add_edges(ends);
  ss.add_field("k", runtime::FieldType{runtime::ComponentKind::Float, {}, false});
  for (int i = 0; i + 1 < n; ++i)
    ss.field(0).at<double>(i)[0] = i == zero_at ? 0.0 : 1.0 + 0.37 * i;
  EngineOptions o;
  o.executor.kind = kind;
  o.executor.threshold = 0;
  o.check_finite = zero_at >= 0;
  Engine engine(compiled, o);
  engine.bind_set(*compiled->find_extern("ps"), ps);
  engine.bind_set(*compiled->find_extern("ss"), ss);
  LaneRun run;
  try {
    for (int call = 0; call < 2; ++call)
      run.results = engine.call(*compiled->find_func(function), {});
  } catch (const interp::RuntimeError& e) {
    run.error = e.render();
  }
  std::ostringstream os;
  engine.print_jit_stats(os);
  run.stats = os.str();
  return run;
}

TEST(Jit, MapKernelsComputeFourElementsAtOnceWithTheInterpretersBits) {
  if (!api::jit_available()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  const LaneRun in = run_lanes(ExecutorKind::Interpreter, "both");
  const LaneRun jit = run_lanes(ExecutorKind::Jit, "both");
  ASSERT_EQ(in.results.size(), 2u);
  ASSERT_EQ(jit.results.size(), 2u);
  expect_same(in.results[0], jit.results[0], "f");
  expect_same(in.results[1], jit.results[1], "K");
  EXPECT_NE(in.results[0].tensor().floats()[0], 0.0);
  EXPECT_NE(jit.stats.find("pull (line 33)"), std::string::npos) << jit.stats;
  EXPECT_NE(jit.stats.find("4 elements at once"), std::string::npos) << jit.stats;
  EXPECT_EQ(jit.stats.find("interpreted"), std::string::npos) << jit.stats;
}

// A check that fails in one lane only (spring 6: lane 2 of the second group) stops the call
// at that element: the interpreter, running the site again, reports it in its own words.
TEST(Jit, ACheckFailingInOneLaneStopsAtItsElement) {
  if (!api::jit_available()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  const LaneRun in = run_lanes(ExecutorKind::Interpreter, "ratios", 6);
  const LaneRun jit = run_lanes(ExecutorKind::Jit, "ratios", 6);
  EXPECT_NE(in.error.find("lanes.sim:29:10: runtime error"), std::string::npos) << in.error;
  EXPECT_NE(in.error.find("element 6 of set 'ss'"), std::string::npos) << in.error;
  EXPECT_EQ(in.error, jit.error);
  EXPECT_NE(jit.stats.find("4 elements at once"), std::string::npos) << jit.stats;
}

// ---------------------------------------------------------------------------
// Solver loops with ifs (jit/system_trace.cpp): a preconditioned CG whose body tests p'Ap,
// counts slow iterations, may stop with an error statement at an iteration the host chooses,
// and restarts its search direction once (a vector update in a branch).

const char* const kPcg = R"(element Point
  b : vector[3](float);
  d : float;
end
element Link
  k : float;
end
extern points : set{Point};
extern links : set{Link}(points, points);
extern stop_at : int;

const eye3 = [1.0, 0.0, 0.0; 0.0, 1.0, 0.0; 0.0, 0.0, 1.0];
const offd = [0.0, 1.0, 0.0; 1.0, 0.0, 0.0; 0.0, 0.0, 0.5];

func stiffness(l : Link, p : (Point * 2)) -> A : matrix[points,points](matrix[3,3](float))
  A(p(0), p(0)) = l.k * eye3;
  A(p(1), p(1)) = l.k * eye3;
  A(p(0), p(1)) = (-0.5 * l.k) * eye3;
  A(p(1), p(0)) = (-0.5 * l.k) * eye3;
end

func diagonal(q : Point) -> D : matrix[points,points](matrix[3,3](float))
  D(q, q) = q.d * eye3 + 0.1 * offd;
end

func jacobi(A : matrix[points,points](matrix[3,3](float)), q : Point)
    -> Pc : matrix[points,points](matrix[3,3](float))
  Pc(q, q) = inv(A(q, q));
end

export func solve() -> (x : vector[points](vector[3](float)), iterations : int, rz : float,
                        slow : int, fast : float)
  A = (map stiffness to links reduce +) + (map diagonal to points reduce +);
  Pc = map jacobi(A) to points reduce +;
  b = points.b;
  var r = b;
  var z = Pc * r;
  var p = z;
  rz = r' * z;
  var going = rz > 1.0e-24;
  while going
    Ap = A * p;
    pAp = p' * Ap;
    if pAp <= 0.0
      error "CG breakdown: p'Ap = ", pAp, " <= 0 at CG iteration ", iterations;
    end
    alpha = rz / pAp;
    x = x + alpha * p;
    r = r - alpha * Ap;
    z = Pc * r;
    rz_new = r' * z;
    if rz_new > 0.05 * rz
      slow = slow + 1;
    elif iterations == 1
      fast = fast - 1.0;
    else
      fast = max(fast, rz_new / rz);
    end
    if iterations == stop_at
      error "stopped at CG iteration ", iterations, " with r'z = ", rz_new;
    end
    if iterations == 4
      p = z;
    else
      p = z + (rz_new / rz) * p;
    end
    rz = rz_new;
    iterations = iterations + 1;
    going = (rz > 1.0e-24) and (iterations < 60);
  end
end
)";

struct PcgRun {
  std::vector<std::vector<Value>> results;  // per call that returned
  std::string error, stats, dump;
};

// Calls `solve` once per entry of `stops` (the iteration its error statement fires at, -1
// for none) on one engine; the first error ends the run.
PcgRun run_pcg(ExecutorKind kind, bool check, const std::vector<int>& stops) {
  auto compiled = CompiledProgram::from_source("pcg.sim", kPcg);
  EXPECT_TRUE(compiled->ok());
  runtime::Set points("points");
  runtime::Set links("links", {&points, &points});
  const int n = 30;
  points.add_many(n);
  points.add_field("b", runtime::FieldType{runtime::ComponentKind::Float, {3}, false});
  points.add_field("d", runtime::FieldType{runtime::ComponentKind::Float, {}, false});
  links.add_field("k", runtime::FieldType{runtime::ComponentKind::Float, {}, false});
  for (int i = 0; i < n; ++i) {
    for (int c = 0; c < 3; ++c) points.field(0).at<double>(i)[c] = std::sin(0.3 * i + c);
    points.field(1).at<double>(i)[0] = 0.2 + 0.01 * i;
    if (i + 1 < n) links.add({i, i + 1});
  }
  for (int e = 0; e < links.size(); ++e) links.field(0).at<double>(e)[0] = 1.0 + 0.5 * std::cos(e);
  EngineOptions o;
  o.executor.kind = kind;
  o.executor.threshold = 0;
  o.executor.check = check;
  std::ostringstream dump;
  o.dump = &dump;
  o.executor.dump_loop_ir = true;
  Engine engine(compiled, o);
  engine.bind_set(*compiled->find_extern("points"), points);
  engine.bind_set(*compiled->find_extern("links"), links);
  PcgRun run;
  for (int stop : stops) {
    engine.set_global(*compiled->find_extern("stop_at"), Value::of_int(stop));
    try {
      run.results.push_back(engine.call(*compiled->find_func("solve"), {}));
    } catch (const interp::RuntimeError& e) {
      run.error = e.render();
      break;
    }
  }
  std::ostringstream os;
  engine.print_jit_stats(os);
  run.stats = os.str();
  run.dump = dump.str();
  return run;
}

// The stats line of the trace that runs the while loop at `line`: the loop alone, or a run
// of statements whose lines hold it.
std::string loop_stats(const std::string& stats, int line) {
  std::istringstream in(stats);
  std::string l;
  while (std::getline(in, l)) {
    int first = 0, last = 0;
    if (l.find("  while (line " + std::to_string(line) + ")") == 0 ||
        (std::sscanf(l.c_str(), "  statements (lines %d-%d)", &first, &last) == 2 &&
         first <= line && line <= last))
      return l;
  }
  return "";
}

void expect_same_pcg_results(const std::vector<Value>& a, const std::vector<Value>& b) {
  ASSERT_EQ(a.size(), 5u);
  ASSERT_EQ(b.size(), 5u);
  expect_same(a[0], b[0], "x");
  EXPECT_EQ(a[1].as_int(), b[1].as_int());
  const double rz[2] = {a[2].as_float(), b[2].as_float()};
  expect_same_bits(&rz[0], &rz[1], 1, "rz");
  EXPECT_EQ(a[3].as_int(), b[3].as_int());
  const double fast[2] = {a[4].as_float(), b[4].as_float()};
  expect_same_bits(&fast[0], &fast[1], 1, "fast");
}

TEST(Jit, ALoopWithIfsOnScalarsIsCompiledAndComputesTheInterpretersBits) {
  if (!api::jit_available()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  const PcgRun in = run_pcg(ExecutorKind::Interpreter, false, {-1, -1});
  const PcgRun jit = run_pcg(ExecutorKind::Jit, false, {-1, -1});
  ASSERT_EQ(in.error, "");
  ASSERT_EQ(jit.error, "");
  const std::string loop = loop_stats(jit.stats, line_of(kPcg, "while going"));
  EXPECT_NE(loop.find(" compiled"), std::string::npos) << jit.stats;
  EXPECT_NE(loop.find(" 2 "), std::string::npos) << loop;  // both calls ran the kernel
  // The set-up from `b = points.b` is in the loop's run: `var going = rz > ...` (scalars
  // alone) joins it.
  EXPECT_EQ(loop.find("  statements (lines " + std::to_string(line_of(kPcg, "b = points.b")) + "-"),
            0u)
      << jit.stats;
  for (int call = 0; call < 2; ++call) expect_same_pcg_results(in.results[call], jit.results[call]);
  // The restart's two updates of p are passes under guards; the breakdown test is an if in a
  // scalar op.
  const std::string loop_ir = jit.dump.substr(jit.dump.find("system trace"));
  const size_t guarded = loop_ir.find(" when %");
  ASSERT_NE(guarded, std::string::npos) << loop_ir;
  const size_t line = loop_ir.rfind('\n', guarded) + 1;
  EXPECT_EQ(loop_ir.compare(line, 13, "    pass over"), 0) << loop_ir.substr(line, guarded - line);
  EXPECT_NE(loop_ir.find("check false else error 0"), std::string::npos) << loop_ir;
  // The branches ran: CG took real iterations, some slow and some not.
  const std::vector<Value>& r = in.results[0];
  EXPECT_GT(r[1].as_int(), 5);
  EXPECT_GT(r[3].as_int(), 0);
  EXPECT_LT(r[3].as_int(), r[1].as_int());
}

TEST(Jit, AnErrorStatementInACompiledLoopIsReportedAsTheInterpreterReportsIt) {
  if (!api::jit_available()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  // The first call stops at iteration 3; the engine then solves without stopping.
  for (bool check : {false, true}) {
    const PcgRun in = run_pcg(ExecutorKind::Interpreter, false, {3});
    const PcgRun jit = run_pcg(ExecutorKind::Jit, check, {3});
    const PcgRun jit_after = run_pcg(ExecutorKind::Jit, check, {-1, 3, -1});
    const PcgRun in_after = run_pcg(ExecutorKind::Interpreter, false, {-1, 3, -1});
    // The message prints the loop's state at iteration 3: the interpreter ran the loop from
    // the state before the kernel's call, which the controller put back.
    const std::string where = "pcg.sim:" + std::to_string(line_of(kPcg, "error \"stopped")) + ":";
    EXPECT_EQ(in.error.rfind(where, 0), 0u) << in.error;
    EXPECT_NE(in.error.find("runtime error: stopped at CG iteration 3 with r'z = "),
              std::string::npos)
        << in.error;
    EXPECT_EQ(jit.error, in.error);
    EXPECT_EQ(jit_after.error, in.error);
    EXPECT_EQ(in_after.error, in.error);
    ASSERT_EQ(jit_after.results.size(), 1u);
    expect_same_pcg_results(in_after.results[0], jit_after.results[0]);
    const std::string loop = loop_stats(jit.stats, line_of(kPcg, "while going"));
    EXPECT_NE(loop.find(" compiled"), std::string::npos) << jit.stats;
    EXPECT_NE(jit.stats.find("1 call reached an error statement and ran again interpreted"),
              std::string::npos)
        << jit.stats;
  }
}

TEST(Jit, CheckModeComparesALoopWithIfs) {
  if (!api::jit_available()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  const PcgRun in = run_pcg(ExecutorKind::Interpreter, false, {-1, -1});
  const PcgRun jit = run_pcg(ExecutorKind::Jit, true, {-1, -1});
  ASSERT_EQ(jit.error, "");
  const std::string loop = loop_stats(jit.stats, line_of(kPcg, "while going"));
  EXPECT_NE(loop.find(" compiled"), std::string::npos) << jit.stats;
  for (int call = 0; call < 2; ++call) expect_same_pcg_results(in.results[call], jit.results[call]);
}

// A loop without products whose error statement fires on two calls: both hand the loop back,
// and the stats say so once.
const char* const kHalving = R"(element P
  b : float;
end
extern ps : set{P};

export func main()
  b = ps.b;
  var x = 0.0 * b;
  var k = 0;
  while k < 10
    x = x + b;
    if x' * x > 40.0
      x = 0.5 * x;
      error "x'x = ", x' * x, " after halving at k = ", k;
    end
    k = k + 1;
  end
end
)";

TEST(Jit, EveryCallThatReachesAnErrorStatementIsHandedBack) {
  if (!api::jit_available()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  auto compiled = CompiledProgram::from_source("halving.sim", kHalving);
  ASSERT_TRUE(compiled->ok());
  runtime::Set ps("ps");
  ps.add_many(2);
  ps.add_field("b", runtime::FieldType{runtime::ComponentKind::Float, {}, false});
  ps.field(0).at<double>(0)[0] = 1.0;
  ps.field(0).at<double>(1)[0] = 2.0;
  EngineOptions o;
  o.executor.kind = ExecutorKind::Jit;
  o.executor.threshold = 0;
  Engine engine(compiled, o);
  engine.bind_set(*compiled->find_extern("ps"), ps);
  // x'x is 5, 20, then 45: halved to [1.5, 3], 11.25, at k = 2.
  const std::string where = "halving.sim:" + std::to_string(line_of(kHalving, "error \"x")) + ":";
  for (int call = 0; call < 2; ++call) {
    std::string message;
    try {
      engine.call(*compiled->find_func("main"), {});
    } catch (const interp::RuntimeError& e) {
      message = e.render();
    }
    EXPECT_EQ(message.rfind(where, 0), 0u) << message;
    EXPECT_NE(message.find("runtime error: x'x = 11.25 after halving at k = 2"), std::string::npos)
        << message;
  }
  std::ostringstream os;
  engine.print_jit_stats(os);
  const std::string stats = os.str();
  const std::string note = "2 calls reached an error statement and ran again interpreted";
  EXPECT_NE(stats.find(note), std::string::npos) << stats;
  const size_t first = stats.find("reached an error statement");
  EXPECT_EQ(stats.find("reached an error statement", first + 1), std::string::npos) << stats;
  EXPECT_NE(loop_stats(stats, line_of(kHalving, "while k")).find(" compiled"), std::string::npos)
      << stats;
}

// Runs of system-level statements: a field read and a vector update; a CG function's set-up
// (with a product inside an expression), loop and residual compiled as one trace; a run with
// a field write and read, cut before a statement the JIT does not compile (a matrix made by
// the run); the interpreter's bits either way.
const std::string kRuns = R"(element Point
  b : float;
  d : float;
  c : float;
end
element Link
  k : float;
end
extern points : set{Point};
extern links : set{Link}(points, points);
)" + std::string(kChainMatrix) +
                          R"(
func cg(A : matrix[points,points](float), b : vector[points](float),
        x0 : vector[points](float)) -> (x : vector[points](float), iterations : int,
                                        residual : float)
  x = x0;
  var r = b - A * x;
  var p = r;
  var rr = r' * r;
  while (rr > 1e-20) and (iterations < 50)
    Ap = A * p;
    alpha = rr / (p' * Ap);
    x = x + alpha * p;
    r = r - alpha * Ap;
    rr_new = r' * r;
    p = r + (rr_new / rr) * p;
    rr = rr_new;
    iterations = iterations + 1;
  end
  residual = sqrt(rr / (b' * b));
end

export func solve() -> (x : vector[points](float), iterations : int, residual : float,
                        s : vector[points](float), w : vector[points](float))
  A = (map stiffness to links reduce +) + (map diagonal to points reduce +);
  b = points.b;
  x0 = 0.25 * b;
  x, iterations, residual = cg(A, b, x0);
  s = 2.0 * x + b;
  t = s - x;
  points.c = t;
  s = s + points.c;
  var u = s - b;
  w = u + u;
  B = 2.0 * A;
  w = w - u;
end
)";

struct RunsRun {
  std::vector<Value> results;
  std::vector<double> c;  // points.c
  std::string stats, dump;
};

// float32: the engine's float32 mode, with the points' fields stored as binary32.
RunsRun run_runs(ExecutorKind kind, bool check, bool float32 = false) {
  auto compiled = CompiledProgram::from_source("runs.sim", kRuns);
  EXPECT_TRUE(compiled->ok());
  runtime::Set points("points");
  runtime::Set links("links", {&points, &points});
  const int n = 40;
  points.add_many(n);
  for (const char* f : {"b", "d", "c"})
    points.add_field(f, runtime::FieldType{runtime::ComponentKind::Float, {}, float32});
  auto set = [&](int field, int i, double v) {
    if (float32)
      points.field(field).at<float>(i)[0] = static_cast<float>(v);
    else
      points.field(field).at<double>(i)[0] = v;
  };
  for (int i = 0; i < n; ++i) {
    set(0, i, std::sin(0.3 * i));
    set(1, i, 0.1 + 0.01 * i);
    if (i + 1 < n) links.add({i, i + 1});
  }
  links.add_field("k", runtime::FieldType{runtime::ComponentKind::Float, {}, false});
  for (int e = 0; e < links.size(); ++e) links.field(0).at<double>(e)[0] = 1.0 + 0.5 * std::cos(e);
  EngineOptions o;
  o.executor.kind = kind;
  o.float32 = float32;
  o.executor.threshold = 0;
  o.executor.check = check;
  std::ostringstream dump;
  o.dump = &dump;
  o.executor.dump_loop_ir = true;
  Engine engine(compiled, o);
  engine.bind_set(*compiled->find_extern("points"), points);
  engine.bind_set(*compiled->find_extern("links"), links);
  RunsRun run;
  for (int call = 0; call < 2; ++call) run.results = engine.call(*compiled->find_func("solve"), {});
  if (float32)
    run.c.assign(points.field(2).data<float>(), points.field(2).data<float>() + n);
  else
    run.c.assign(points.field(2).data<double>(), points.field(2).data<double>() + n);
  std::ostringstream os;
  engine.print_jit_stats(os);
  run.stats = os.str();
  run.dump = dump.str();
  return run;
}

// The stats line of the trace of the statements from the line holding `first` to the line
// holding `last`.
std::string run_stats(const std::string& stats, const std::string& text, const char* first,
                      const char* last) {
  const std::string site = "  statements (lines " + std::to_string(line_of(text, first)) + "-" +
                           std::to_string(line_of(text, last)) + ")";
  const size_t at = stats.find(site);
  return at == std::string::npos ? "" : stats.substr(at, stats.find('\n', at) - at);
}

void expect_same_runs(const RunsRun& in, const RunsRun& jit) {
  ASSERT_EQ(in.results.size(), 5u);
  ASSERT_EQ(jit.results.size(), 5u);
  expect_same(in.results[0], jit.results[0], "x");
  EXPECT_EQ(in.results[1].as_int(), jit.results[1].as_int());
  const double residual[2] = {in.results[2].as_float(), jit.results[2].as_float()};
  expect_same_bits(&residual[0], &residual[1], 1, "residual");
  expect_same(in.results[3], jit.results[3], "s");
  expect_same(in.results[4], jit.results[4], "w");
  expect_same_bits(in.c.data(), jit.c.data(), in.c.size(), "points.c");
}

TEST(Jit, ARunOfStatementsCompilesAsOneTraceWithItsLoop) {
  if (!api::jit_available()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  const RunsRun in = run_runs(ExecutorKind::Interpreter, false);
  const RunsRun jit = run_runs(ExecutorKind::Jit, false);
  expect_same_runs(in, jit);
  EXPECT_GT(in.results[1].as_int(), 5);  // CG took real iterations
  EXPECT_GT(in.results[2].as_float(), 0.0);
  // cg's six statements are one trace, called twice; its loop is not compiled on its own.
  const std::string cg = run_stats(jit.stats, kRuns, "x = x0", "residual = sqrt");
  EXPECT_NE(cg.find(" compiled"), std::string::npos) << jit.stats;
  EXPECT_NE(cg.find(" 2 "), std::string::npos) << cg;
  // Its loop-IR size, the last number before the status.
  std::istringstream fields(cg.substr(cg.find(')') + 1));
  double compile_ms = 0, run_ms = 0, cpu_ms = 0;
  long calls = 0, nodes = 0;
  fields >> compile_ms >> calls >> run_ms >> cpu_ms >> nodes;
  EXPECT_GT(nodes, 20) << cg;
  EXPECT_EQ(jit.stats.find("  while (line"), std::string::npos) << jit.stats;
  // The set-up's product (b - A * x) goes into a scratch vector; the residual's b'b is after.
  const size_t trace =
      jit.dump.find("system trace statements:" + std::to_string(line_of(kRuns, "x = x0")));
  ASSERT_NE(trace, std::string::npos) << jit.dump;
  const std::string ir = jit.dump.substr(trace);
  const size_t before = ir.find("  before"), loop = ir.find("  while "), after = ir.find("  after");
  ASSERT_TRUE(before < loop && loop < after) << ir;
  EXPECT_NE(ir.find("scratch"), std::string::npos) << ir;
  EXPECT_NE(ir.substr(before, loop - before).find(" = spmv("), std::string::npos) << ir;
  EXPECT_NE(ir.substr(after).find("pass over"), std::string::npos) << ir;
  // `b = points.b; x0 = 0.25 * b` compile; from `s = ...` the statements before `B = 2.0 * A`
  // (which makes a matrix) compile, the field write among them.
  EXPECT_NE(run_stats(jit.stats, kRuns, "b = points.b", "x0 = 0.25").find(" compiled"),
            std::string::npos)
      << jit.stats;
  EXPECT_NE(run_stats(jit.stats, kRuns, "s = 2.0", "w = u + u").find(" compiled"),
            std::string::npos)
      << jit.stats;
  EXPECT_NE(jit.dump.find("points.c f64 written"), std::string::npos) << jit.dump;
  for (double c : in.c) EXPECT_NE(c, 0.0);  // the field was written
}

// A system statement that is no part of a run (`w = w - u` after the matrix statement that
// ends the run before it) compiles alone; one that does not compile (`B = 2.0 * A` makes a
// matrix) is not listed: the interpreter runs it, as it runs most matrix statements.
TEST(Jit, ASystemStatementAloneCompilesAndOneThatCannotIsNotListed) {
  if (!api::jit_available()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  const RunsRun in = run_runs(ExecutorKind::Interpreter, false);
  for (bool check : {false, true}) {
    const RunsRun jit = run_runs(ExecutorKind::Jit, check);
    expect_same_runs(in, jit);
    const std::string site =
        "  statement (line " + std::to_string(line_of(kRuns, "w = w - u")) + ")";
    const size_t at = jit.stats.find(site);
    ASSERT_NE(at, std::string::npos) << jit.stats;
    const std::string line = jit.stats.substr(at, jit.stats.find('\n', at) - at);
    EXPECT_NE(line.find(" compiled"), std::string::npos) << line;
    EXPECT_NE(line.find(" 2 "), std::string::npos) << line;  // both calls
    EXPECT_EQ(
        jit.stats.find("  statement (line " + std::to_string(line_of(kRuns, "B = 2.0 * A")) + ")"),
        std::string::npos)
        << jit.stats;
  }
}

TEST(Jit, CheckModeComparesARunOfStatements) {
  if (!api::jit_available()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  const RunsRun in = run_runs(ExecutorKind::Interpreter, false);
  const RunsRun jit = run_runs(ExecutorKind::Jit, true);
  expect_same_runs(in, jit);
  const std::string cg = run_stats(jit.stats, kRuns, "x = x0", "residual = sqrt");
  EXPECT_NE(cg.find(" compiled"), std::string::npos) << jit.stats;
  EXPECT_EQ(jit.stats.find("  while (line"), std::string::npos) << jit.stats;
  EXPECT_NE(run_stats(jit.stats, kRuns, "s = 2.0", "w = u + u").find(" compiled"),
            std::string::npos)
      << jit.stats;
}

// Under float32 (every operator, call and literal rounded to binary32) with binary32 fields,
// the same runs compile: each product's and each operator's value rounded, the fields
// widened at each read and rounded at each write; the bits are the interpreter's, also
// under --check-jit, and differ from the binary64 run's.
TEST(Jit, RunsCompileInFloat32ModeWithBinary32Fields) {
  if (!api::jit_available()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  const RunsRun in = run_runs(ExecutorKind::Interpreter, false, true);
  for (bool check : {false, true}) {
    const RunsRun jit = run_runs(ExecutorKind::Jit, check, true);
    expect_same_runs(in, jit);
    EXPECT_NE(run_stats(jit.stats, kRuns, "x = x0", "residual = sqrt").find(" compiled"),
              std::string::npos)
        << jit.stats;
    EXPECT_NE(run_stats(jit.stats, kRuns, "s = 2.0", "w = u + u").find(" compiled"),
              std::string::npos)
        << jit.stats;
    if (!check) {
      EXPECT_NE(jit.dump.find("points.c f32 written"), std::string::npos) << jit.dump;
      EXPECT_NE(jit.dump.find("round32("), std::string::npos) << jit.dump;
    }
  }
  const RunsRun wide = run_runs(ExecutorKind::Interpreter, false, false);
  EXPECT_NE(wide.results[2].as_float(), in.results[2].as_float());  // the rounding is real
  for (double c : in.c) EXPECT_EQ(c, static_cast<double>(static_cast<float>(c)));
}

// A run whose loop reaches an error statement: the interpreter runs the statements again
// from the first and stops at the error; neither the rest of the run nor the loop alone is
// compiled for it.
const char* const kRunError = R"(element P
  b : float;
end
extern ps : set{P};

func grow(b : vector[ps](float)) -> x : vector[ps](float)
  x = 0.0 * b;
  var y = b + b;
  var n = b' * b;
  while n < 100.0
    x = x + y;
    n = x' * x;
    if n > 40.0
      error "x'x = ", n, " above 40";
    end
  end
end

export func main() -> x : vector[ps](float)
  x = grow(ps.b);
end
)";

TEST(Jit, ARunWhoseLoopReachesAnErrorStatementIsInterpretedOnce) {
  if (!api::jit_available()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  std::string message[2], stats;
  for (int k = 0; k < 2; ++k) {
    auto compiled = CompiledProgram::from_source("grow.sim", kRunError);
    ASSERT_TRUE(compiled->ok());
    runtime::Set ps("ps");
    ps.add_many(2);
    ps.add_field("b", runtime::FieldType{runtime::ComponentKind::Float, {}, false});
    ps.field(0).at<double>(0)[0] = 1.0;
    ps.field(0).at<double>(1)[0] = 2.0;
    EngineOptions o;
    o.executor.kind = k ? ExecutorKind::Jit : ExecutorKind::Interpreter;
    o.executor.threshold = 0;
    Engine engine(compiled, o);
    engine.bind_set(*compiled->find_extern("ps"), ps);
    try {
      engine.call(*compiled->find_func("main"), {});
    } catch (const interp::RuntimeError& e) {
      message[k] = e.render();
    }
    std::ostringstream os;
    engine.print_jit_stats(os);
    if (k) stats = os.str();
  }
  // y = [2, 4]: x'x is 20, then 80.
  EXPECT_NE(message[0].find("runtime error: x'x = 80"), std::string::npos) << message[0];
  EXPECT_NE(message[0].find(" above 40"), std::string::npos) << message[0];
  EXPECT_EQ(message[1], message[0]);
  EXPECT_NE(stats.find("1 call reached an error statement and ran again interpreted"),
            std::string::npos)
      << stats;
  EXPECT_EQ(stats.find("  while (line"), std::string::npos) << stats;
  EXPECT_EQ(stats.find("statements (lines " + std::to_string(line_of(kRunError, "var y"))),
            std::string::npos)
      << stats;
}

// Ctrl-C in a compiled loop that never ends (a solver that does not converge): the kernel
// reads the interrupt flag once per iteration and stops at an iteration boundary; the call
// ends with the interpreter's Interrupted error, the fields and the global scalar the loop
// writes hold the values of one whole number of iterations, and the engine runs the next call
// (the interrupt was taken).
const char* const kSpin = R"(element P
  b : float;
  c : float;
  d : float;
end
extern ps : set{P};
extern count : float;

export func spin(limit : float)
  var x = 0.0 * ps.b;
  var n = 0.0;
  while n < limit
    x = x + ps.b;
    ps.c = x;
    n = n + 1.0;
    ps.d = n * ps.b;
    count = count + 1.0;
  end
end
)";

// The calls of the trace that holds line `line` (a loop alone or a run; 0 when absent).
long trace_calls(const std::string& stats, int line) {
  const std::string l = loop_stats(stats, line);
  if (l.empty()) return 0;
  std::istringstream fields(l.substr(l.find(')') + 1));
  double compile_ms = 0;
  long calls = 0;
  fields >> compile_ms >> calls;
  return calls;
}

TEST(Jit, AnInterruptStopsACompiledLoopAtAnIterationBoundary) {
  if (!api::jit_available()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  auto compiled = CompiledProgram::from_source("spin.sim", kSpin);
  ASSERT_TRUE(compiled->ok());
  runtime::Set ps("ps");
  const int n = 1000;
  ps.add_many(n);
  for (const char* f : {"b", "c", "d"})
    ps.add_field(f, runtime::FieldType{runtime::ComponentKind::Float, {}, false});
  for (int i = 0; i < n; ++i) ps.field(0).at<double>(i)[0] = 1.0 + i % 7;  // small integers
  interp::Trap trap;  // what the REPL's SIGINT handler asks to interrupt
  EngineOptions o;
  o.executor.kind = ExecutorKind::Jit;
  o.executor.threshold = 0;
  o.trap = &trap;
  Engine engine(compiled, o);
  engine.bind_set(*compiled->find_extern("ps"), ps);
  const ast::Variable& count = *compiled->find_extern("count");
  engine.set_global(count, Value::of_float(0.0));
  const ast::FuncDecl& spin = *compiled->find_func("spin");
  const int loop_line = line_of(kSpin, "while n");
  auto stats = [&] {
    std::ostringstream os;
    engine.print_jit_stats(os);
    return os.str();
  };
  // c and d after `iterations` whole iterations, in exact (small integer) arithmetic.
  auto expect_boundary = [&](double iterations) {
    for (int i = 0; i < n; ++i) {
      const double b = ps.field(0).at<double>(i)[0];
      ASSERT_EQ(ps.field(1).at<double>(i)[0], iterations * b) << "c at element " << i;
      ASSERT_EQ(ps.field(2).at<double>(i)[0], iterations * b) << "d at element " << i;
    }
  };
  // The first call compiles the loop (a bounded one): 3 iterations.
  engine.call(spin, {Value::of_float(3.0)});
  expect_boundary(3.0);
  ASSERT_EQ(engine.global(count).as_float(), 3.0);
  ASSERT_EQ(trace_calls(stats(), loop_line), 1) << stats();
  // The second never ends: its kernel runs until the flag is set, as SIGINT sets it.
  auto run = std::async(std::launch::async, [&]() -> std::string {
    try {
      engine.call(spin, {Value::of_float(1e300)});
    } catch (const interp::Interrupted& e) {
      return "interrupted: " + e.render();
    } catch (const interp::RuntimeError& e) {
      return "error: " + e.render();
    }
    return "returned";
  });
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  trap.request_interrupt();
  if (run.wait_for(std::chrono::seconds(30)) != std::future_status::ready) {
    // The kernel never looked at the flag: end the test process rather than hang.
    std::fprintf(stderr, "FAIL: the compiled loop did not stop within 30 s of the interrupt\n");
    std::fflush(stderr);
    std::_Exit(1);
  }
  const std::string outcome = run.get();
  EXPECT_EQ(outcome.rfind("interrupted: ", 0), 0u) << outcome;
  EXPECT_NE(outcome.find("spin.sim:"), std::string::npos) << outcome;
  EXPECT_FALSE(trap.interrupt_pending());  // taken, as the interpreter takes it
  // The kernel ran and stopped itself (the interpreter did not catch the interrupt before
  // it), after a whole number of iterations (at least one: 300 ms).
  EXPECT_EQ(trace_calls(stats(), loop_line), 2) << stats();
  const double iterations = ps.field(1).at<double>(0)[0] / ps.field(0).at<double>(0)[0];
  EXPECT_GE(iterations, 1.0);
  EXPECT_EQ(iterations, std::floor(iterations));
  expect_boundary(iterations);
  EXPECT_EQ(engine.global(count).as_float(), 3.0 + iterations);  // a scalar handed back
  // The engine goes on: the next call runs compiled, to its end.
  engine.call(spin, {Value::of_float(5.0)});
  expect_boundary(5.0);
  EXPECT_EQ(engine.global(count).as_float(), 8.0 + iterations);
  EXPECT_EQ(trace_calls(stats(), loop_line), 3) << stats();
  EXPECT_NE(loop_stats(stats(), loop_line).find(" compiled"), std::string::npos) << stats();
}

}  // namespace
}  // namespace simit::jit
