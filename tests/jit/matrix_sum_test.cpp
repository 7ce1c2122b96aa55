// Fused matrix sums (jit/matrix_sum.h): `A = M - s * K` computed in the storage K's map
// assembled, with the interpreter's bits, only where K dies with the statement.
#include <gtest/gtest.h>

#include <cstring>
#include <sstream>

#include "api/engine.h"
#include "runtime/system_ops.h"

namespace simit::jit {
namespace {

using api::CompiledProgram;
using api::Engine;
using api::EngineOptions;
using api::ExecutorKind;
using interp::Value;

// Springs on a chain with 2 x 2 blocks; a spring writes only while both its ends are on (so
// the stiffness is specialised to fewer blocks than its pattern), and a negative zero lands in
// each written block. `step` may fuse its sum; `step_keeps` reads K after the sum.
const char* kProgram = R"(
element V
  m : float;
  k : float;
  on : bool;
end
element E
end
extern verts : set{V};
extern edges : set{E}(verts, verts);
const h = 0.1;
const I = [1.0, 0.0; 0.0, 1.0];
const J = [0.0, 1.0; 1.0, 0.0];

func spring(e : E, v : (V * 2)) -> K : matrix[verts,verts](matrix[2,2](float))
  a = v(0).k * v(1).k;
  z = (0.0 - a) * 0.0;
  if v(0).on and v(1).on
    K(v(0), v(0)) = a * I + z * J;
    K(v(0), v(1)) = (0.0 - a) * I + 0.5 * J;
    K(v(1), v(0)) = (0.0 - a) * I + 0.25 * J;
    K(v(1), v(1)) = a * I + z * J;
  end
end

func mass(p : V) -> M : matrix[verts,verts](matrix[2,2](float))
  M(p, p) = p.m * I;
end

func unit(p : V) -> x : vector[verts](vector[2](float))
  x(p) = p.k * [1.0, 2.0]';
end

export func step() -> (A : matrix[verts,verts](matrix[2,2](float)),
                       y : vector[verts](vector[2](float)))
  K = map spring to edges reduce +;
  M = map mass to verts reduce +;
  A = M - (h * h) * K;
  x = map unit to verts reduce +;
  y = A * x;
end

export func parts() -> (K : matrix[verts,verts](matrix[2,2](float)),
                        M : matrix[verts,verts](matrix[2,2](float)))
  K = map spring to edges reduce +;
  M = map mass to verts reduce +;
end

export func step_keeps() -> (A : matrix[verts,verts](matrix[2,2](float)),
                             y : vector[verts](vector[2](float)))
  K = map spring to edges reduce +;
  M = map mass to verts reduce +;
  A = M - (h * h) * K;
  x = map unit to verts reduce +;
  y = A * x + K * x;
end
)";

int line_of(const std::string& text, int nth) {
  size_t at = 0;
  for (int i = 0; i <= nth; ++i) at = std::string(kProgram).find(text, i ? at + 1 : 0);
  int line = 1;
  for (size_t i = 0; i < at; ++i) line += kProgram[i] == '\n';
  return line;
}

struct Chain {
  std::shared_ptr<const CompiledProgram> compiled =
      CompiledProgram::from_source("chain.sim", kProgram);
  runtime::Set verts{"verts"};
  runtime::Set edges{"edges", {&verts, &verts}};
  std::unique_ptr<Engine> engine;

  // `vertices` on a chain of `vertices - isolated` of them (the rest in no spring).
  Chain(ExecutorKind kind, bool check, bool float32, int vertices = 6, int isolated = 0) {
    EXPECT_TRUE(compiled->ok());
    verts.add_many(vertices);
    verts.add_field("m", runtime::FieldType{runtime::ComponentKind::Float, {}, false});
    verts.add_field("k", runtime::FieldType{runtime::ComponentKind::Float, {}, false});
    verts.add_field("on", runtime::FieldType{runtime::ComponentKind::Bool, {}, false});
    for (int i = 0; i < vertices; ++i) {
      verts.field(0).at<double>(i)[0] = 1.0 + 0.125 * i;
      verts.field(1).at<double>(i)[0] = 0.3 + 0.7 * i;
      verts.field(2).at<bool>(i)[0] = i != 2;
    }
    std::vector<int32_t> ends;
    for (int i = 0; i + 1 < vertices - isolated; ++i) ends.insert(ends.end(), {i, i + 1});
    edges.add_edges(ends);
    EngineOptions o;
    o.executor.kind = kind;
    o.float32 = float32;
    o.executor.threshold = 0;
    o.executor.check = check;
    engine = std::make_unique<Engine>(compiled, o);
    engine->bind_set(*compiled->find_extern("verts"), verts);
    engine->bind_set(*compiled->find_extern("edges"), edges);
  }
  std::vector<Value> call(const char* f) { return engine->call(*compiled->find_func(f), {}); }
  std::string stats() const {
    std::ostringstream os;
    engine->print_jit_stats(os);
    return os.str();
  }
};

// The same matrix, component by component (the patterns may differ by zero blocks), to the bit.
void expect_same(const Value& a, const Value& b, const std::string& what) {
  ASSERT_EQ(a.kind(), b.kind()) << what;
  if (a.kind() == Value::Kind::Matrix) {
    const runtime::SystemMatrix &x = *a.matrix(), &y = *b.matrix();
    ASSERT_EQ(x.scalar_rows(), y.scalar_rows()) << what;
    for (int64_t i = 0; i < x.scalar_rows(); ++i)
      for (int64_t j = 0; j < x.scalar_cols(); ++j) {
        const double u = x.component(i, j), v = y.component(i, j);
        EXPECT_EQ(std::memcmp(&u, &v, sizeof u), 0) << what << "(" << i << ", " << j << ")";
      }
    return;
  }
  ASSERT_EQ(a.tensor().size(), b.tensor().size()) << what;
  EXPECT_EQ(std::memcmp(a.tensor().floats(), b.tensor().floats(), a.tensor().size() * 8), 0)
      << what;
}

// The stats line of the statement at `line`, or "".
std::string stats_line(const std::string& stats, int line) {
  const size_t at = stats.find("  statement (line " + std::to_string(line) + ")");
  return at == std::string::npos ? "" : stats.substr(at, stats.find('\n', at) - at);
}

// Fused on every call: the first assembles K on its full pattern, the later ones on the
// blocks the springs write plus the diagonal (vertex 2 is off, so its diagonal block is
// written by no spring, and the mass lands there all the same); the bits are the
// interpreter's, also under --check-jit, which computes the sum both ways.
TEST(MatrixSum, ASumWhoseScaledOperandDiesIsComputedInItsStorage) {
  if (!api::jit_available()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  for (bool check : {false, true}) {
    Chain in(ExecutorKind::Interpreter, false, false), jit(ExecutorKind::Jit, check, false);
    for (int frame = 0; frame < 3; ++frame) {
      const std::vector<Value> a = in.call("step"), b = jit.call("step");
      expect_same(a[0], b[0], "A");
      expect_same(a[1], b[1], "y");
      // A's diagonal block of vertex 2 is the mass alone.
      EXPECT_EQ(b[0].matrix()->component(4, 4), 1.25);
      EXPECT_EQ(b[0].matrix()->component(4, 5), 0.0);
      // The 11 blocks the three springs on write, and vertex 2's diagonal (--check-jit keeps
      // full patterns).
      if (frame == 2 && !check) {
        EXPECT_EQ(b[0].matrix()->pattern().nnz(), 12);
        EXPECT_EQ(a[0].matrix()->pattern().nnz(), 16);
      }
    }
    const std::string line = stats_line(jit.stats(), line_of("A = M - (h * h) * K", 0));
    EXPECT_NE(line.find(" fused"), std::string::npos) << jit.stats();
    EXPECT_NE(line.find(" 3 "), std::string::npos) << line;
    EXPECT_NE(jit.stats().find("A = M - s * K in the storage of K (the map on line " +
                               std::to_string(line_of("K = map spring", 0)) + ")"),
              std::string::npos)
        << jit.stats();
  }
}

// K read after the sum: the interpreter's sum, no fused line.
TEST(MatrixSum, AScaledOperandReadAfterTheSumIsLeftAlone) {
  if (!api::jit_available()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  Chain in(ExecutorKind::Interpreter, false, false), jit(ExecutorKind::Jit, false, false);
  for (int frame = 0; frame < 2; ++frame) {
    const std::vector<Value> a = in.call("step_keeps"), b = jit.call("step_keeps");
    expect_same(a[0], b[0], "A");
    expect_same(a[1], b[1], "y");
  }
  EXPECT_EQ(stats_line(jit.stats(), line_of("A = M - (h * h) * K", 1)), "") << jit.stats();
}

// A vertex in no spring: its mass block lies outside K's pattern, so the sum needs the union
// and runs interpreted, saying why; under float32 (s * K rounded on its own) it is not tried.
TEST(MatrixSum, AMassOutsideTheStiffnessPatternRunsTheInterpretersSum) {
  if (!api::jit_available()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  Chain in(ExecutorKind::Interpreter, false, false, 7, 1);
  Chain jit(ExecutorKind::Jit, false, false, 7, 1);
  for (int frame = 0; frame < 2; ++frame) {
    const std::vector<Value> a = in.call("step"), b = jit.call("step");
    expect_same(a[0], b[0], "A");
    expect_same(a[1], b[1], "y");
  }
  EXPECT_NE(stats_line(jit.stats(), line_of("A = M - (h * h) * K", 0))
                .find("interpreted: M has blocks outside the pattern of K"),
            std::string::npos)
      << jit.stats();
}

// Under --float32 the sum is fused too, in the interpreter's float32 order: s * K rounded to
// binary32, then M - it rounded (docs/arithmetic.md). The expected matrix is computed here
// from K and M (map results, themselves rounded once assembled) by that formula.
TEST(MatrixSum, Float32FusesWithTheInterpretersRounding) {
  if (!api::jit_available()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  Chain in(ExecutorKind::Interpreter, false, true), jit(ExecutorKind::Jit, false, true),
      checked(ExecutorKind::Jit, true, true), parts(ExecutorKind::Interpreter, false, true);
  const std::vector<Value> km = parts.call("parts");
  const runtime::SystemMatrix &k = *km[0].matrix(), &m = *km[1].matrix();
  EXPECT_TRUE(runtime::is_binary32(k));
  EXPECT_TRUE(runtime::is_binary32(m));
  const auto f32 = [](double x) { return static_cast<double>(static_cast<float>(x)); };
  const double s = f32(f32(0.1) * f32(0.1));
  for (int frame = 0; frame < 2; ++frame) {
    const std::vector<Value> a = in.call("step"), b = jit.call("step"), c = checked.call("step");
    expect_same(a[0], b[0], "A (float32)");
    expect_same(a[1], b[1], "y (float32)");
    expect_same(a[0], c[0], "A (float32, --check-jit)");
    const runtime::SystemMatrix& got = *b[0].matrix();
    for (int64_t i = 0; i < got.scalar_rows(); ++i)
      for (int64_t j = 0; j < got.scalar_cols(); ++j) {
        const double want = f32(m.component(i, j) - f32(s * k.component(i, j)));
        const double have = got.component(i, j);
        EXPECT_EQ(std::memcmp(&want, &have, sizeof want), 0)
            << "A(" << i << ", " << j << "): " << have << ", want " << want;
      }
  }
  EXPECT_NE(stats_line(jit.stats(), line_of("A = M - (h * h) * K", 0)).find("fused"),
            std::string::npos)
      << jit.stats();
}

}  // namespace
}  // namespace simit::jit
