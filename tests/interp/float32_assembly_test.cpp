// --float32 and sums (docs/arithmetic.md): a map's assembled block, a dense product and a row
// of a system matrix times a vector add in binary32 steps (each product and addition rounded,
// as a binary32 machine computes them), a reduction over a set keeps binary64 and is rounded
// once, and every matrix operator's value is rounded like any other operator's. The expected
// values are worked out here from the data.
#include <cmath>
#include <cstring>

#include "runtime/set.h"
#include "runtime/system_ops.h"
#include "test_util.h"

namespace simit::interp {
namespace {

// Three edges between two vertices: edge e adds w(e) into g(a) and K(a, b), and u(e) into
// g(b). With w = 1, 2^-24, 2^-24 the binary64 sum 1 + 2^-23 is a binary32 value, which
// successive binary32 additions miss (1 + 2^-24 rounds to 1 first); with u = 1, 2^-30, 0
// the binary64 sum is not one, and either order of rounding gives 1.
const char* kProgram = R"(
element V
end
element E
  w : float;
  u : float;
end
extern verts : set{V};
extern edges : set{E}(verts, verts);

func f(e : E, v : (V * 2)) -> (g : vector[verts](float), K : matrix[verts,verts](float))
  g(v(0)) = e.w * 1.0;
  g(v(1)) = e.u * 1.0;
  K(v(0), v(1)) = e.w * 1.0;
  K(v(1), v(0)) = e.u * 1.0;
end

export func assemble() -> (g : vector[verts](float), K : matrix[verts,verts](float),
                           A : matrix[verts,verts](float))
  g, K = map f to edges reduce +;
  A = K - 0.1 * K;
end

% 2^-24 is 5.9604644775390625e-08. In binary32 steps 1 + 2^-24 + 2^-24 - 1 is 0; in binary64
% it is 2^-23. `dense` sums it as a dense inner product and as a matrix row; `over_set` sums
% the edges' w (1, 2^-24, 2^-24) as a reduction over a set.
export func dense() -> (d : float, y : vector[2](float))
  u = [1.0, 5.9604644775390625e-08, 5.9604644775390625e-08, -1.0];
  var ones : vector[4](float) = 1.0;
  d = u * ones;
  M = [1.0, 5.9604644775390625e-08, 5.9604644775390625e-08, -1.0; 0.0, 0.0, 0.0, 2.0];
  y = M * ones;
end

func part(e : E) -> h : vector[edges](float)
  h(e) = e.w;
end

export func over_set() -> s : float
  h = map part to edges reduce +;
  var ones : vector[edges](float) = 1.0;
  s = h' * ones;
end
)";

struct Edges {
  std::unique_ptr<frontend::Compilation> c = testing::compile(kProgram, "float32.sim");
  runtime::Set verts{"verts"};
  runtime::Set edges{"edges", {&verts, &verts}};
  std::unique_ptr<Interpreter> in;

  explicit Edges(bool float32) {
    verts.add_many(2);
    const std::vector<int32_t> ends = {0, 1, 0, 1, 0, 1};
    edges.add_edges(ends);
    edges.add_field("w", runtime::FieldType{runtime::ComponentKind::Float, {}, false});
    edges.add_field("u", runtime::FieldType{runtime::ComponentKind::Float, {}, false});
    const double w[] = {1.0, std::ldexp(1.0, -24), std::ldexp(1.0, -24)};
    const double u[] = {1.0, std::ldexp(1.0, -30), 0.0};
    for (int e = 0; e < 3; ++e) {
      edges.field(0).at<double>(e)[0] = w[e];
      edges.field(1).at<double>(e)[0] = u[e];
    }
    Options o;
    o.float32 = float32;
    in = std::make_unique<Interpreter>(*c->program, o);
    for (const frontend::ast::Variable* v : c->program->globals)
      if (v && v->name == "verts") in->bind_set(*v, verts);
    for (const frontend::ast::Variable* v : c->program->globals)
      if (v && v->name == "edges") in->bind_set(*v, edges);
  }
  std::vector<Value> assemble() { return in->call(testing::func(*c, "assemble"), {}); }
};

bool same(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }
double f32(double x) { return static_cast<float>(x); }

TEST(Float32Assembly, SumsRoundAtEveryAddition) {
  Edges run(true);
  const std::vector<Value> r = run.assemble();
  const double once_w = 1.0 + std::ldexp(1.0, -23);  // the binary64 sum, a binary32 value
  const double stepwise_w = f32(f32(1.0 + std::ldexp(1.0, -24)) + std::ldexp(1.0, -24));
  ASSERT_NE(once_w, stepwise_w);  // the order matters: 1 + 2^-23 against 1
  EXPECT_TRUE(same(r[0].tensor().floats()[0], stepwise_w));
  EXPECT_TRUE(same(r[0].tensor().floats()[1], 1.0));  // 1 + 2^-30 rounded
  const runtime::SystemMatrix& k = *r[1].matrix();
  EXPECT_TRUE(same(k.component(0, 1), stepwise_w));
  EXPECT_TRUE(same(k.component(1, 0), 1.0));
  EXPECT_TRUE(runtime::is_binary32(k));
  // A matrix operator's value is rounded: 0.1 * K, then K - that.
  const runtime::SystemMatrix& a = *r[2].matrix();
  const double s = f32(0.1);
  EXPECT_TRUE(same(a.component(0, 1), f32(stepwise_w - f32(s * stepwise_w))));
  EXPECT_TRUE(same(a.component(1, 0), f32(1.0 - f32(s * 1.0))));
  EXPECT_TRUE(runtime::is_binary32(a));
}

// 1 + 2^-24 + 2^-24 - 1, left to right: 0 in binary32 steps, 2^-23 in binary64.
const double kTiny = std::ldexp(1.0, -24);
const double kStepwise = f32(f32(f32(1.0 + kTiny) + kTiny) - 1.0);

TEST(Float32Assembly, DenseProductsAddInBinary32Steps) {
  ASSERT_EQ(kStepwise, 0.0);
  Edges run(true);
  const std::vector<Value> r = run.in->call(testing::func(*run.c, "dense"), {});
  EXPECT_TRUE(same(r[0].as_float(), 0.0));
  EXPECT_TRUE(same(r[1].tensor().floats()[0], 0.0));
  EXPECT_TRUE(same(r[1].tensor().floats()[1], 2.0));
  // In float64 both keep 2^-23.
  Edges wide(false);
  const std::vector<Value> w = wide.in->call(testing::func(*wide.c, "dense"), {});
  EXPECT_TRUE(same(w[0].as_float(), 2 * kTiny));
  EXPECT_TRUE(same(w[1].tensor().floats()[0], 2 * kTiny));
}

// The edges' w are 1, 2^-24, 2^-24: summed over the set in binary64 and rounded once, 1 +
// 2^-23 (in binary32 steps it would be 1).
TEST(Float32Assembly, AReductionOverASetKeepsBinary64) {
  Edges run(true);
  const std::vector<Value> r = run.in->call(testing::func(*run.c, "over_set"), {});
  EXPECT_TRUE(same(r[0].as_float(), 1.0 + 2 * kTiny));
}

TEST(Float32Assembly, Float64KeepsTheBinary64Sums) {
  Edges run(false);
  const std::vector<Value> r = run.assemble();
  EXPECT_TRUE(same(r[0].tensor().floats()[1], 1.0 + std::ldexp(1.0, -30)));
  EXPECT_TRUE(same(r[1].matrix()->component(1, 0), 1.0 + std::ldexp(1.0, -30)));
  EXPECT_FALSE(runtime::is_binary32(*r[1].matrix()));
}

TEST(Float32Assembly, RoundingAMatrixRoundsEachValue) {
  Edges run(false);
  runtime::SystemMatrix m = *run.assemble()[1].matrix();
  const double wide = m.component(1, 0);
  runtime::round_to_float32(m);
  EXPECT_TRUE(same(m.component(1, 0), f32(wide)));
  EXPECT_TRUE(runtime::is_binary32(m));
  m.values()[0] = std::nan("");
  EXPECT_TRUE(runtime::is_binary32(m));  // a NaN stays a NaN either way
}

}  // namespace
}  // namespace simit::interp
