// The tracing JIT against the interpreter: traces of map and apply sites compiled with LLVM
// and run bit for bit like the interpreter, specialised result patterns, the fallbacks with
// their reasons, decompositions, and switching executors mid-run.
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
#include "jit/tunables.h"
#include "jit_test_support.h"

namespace simit::jit {
namespace {

using namespace test_support;  // also ast, Value and the engine API's names

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

}  // namespace
}  // namespace simit::jit
