// The order in which index notation sums (docs/arithmetic.md, "Sums"): a reduction variable
// that ranges over a set or a generic parameter sums its elements' sums in the blocked order
// (the same bits as `u' * v`), two of them nest, the first outermost, and dense reduction
// variables keep the row-major order. The expected values come from a reference written here
// from the contract's text, never from the interpreter or runtime/blocked_sum.h.
#include <bit>
#include <complex>
#include <cstdint>
#include <vector>

#include "interp/set_binding.h"
#include "runtime/set.h"
#include "test_util.h"

namespace simit::interp {
namespace {

using testing::compile;
using testing::func;
using Cx = std::complex<double>;

// The contract's blocked order over element sums t_0 .. t_{n-1}: chunks of 256 elements,
// element e added to lane e mod 32 of its chunk (lanes from +0.0), the lanes folded by the
// halving tree, the chunks' partials added left to right from +0.0.
template <class T>
T blocked(const std::vector<T>& t) {
  T total{};
  for (size_t begin = 0; begin < t.size(); begin += 256) {
    T lanes[32] = {};
    for (size_t e = begin; e < t.size() && e < begin + 256; ++e)
      lanes[(e - begin) % 32] = lanes[(e - begin) % 32] + t[e];
    for (size_t w = 16; w >= 1; w /= 2)
      for (size_t i = 0; i < w; ++i) lanes[i] = lanes[i] + lanes[i + w];
    total = total + lanes[0];
  }
  return total;
}

template <class T>
T left_to_right(const std::vector<T>& t) {
  T s{};
  for (const T& x : t) s = s + x;
  return s;
}

// Values of magnitudes from 1e-3 to 1e4 and both signs, so that orders of summation differ.
std::vector<double> spread(size_t n, uint32_t seed) {
  std::vector<double> v(n);
  uint32_t x = seed;
  for (size_t i = 0; i < n; ++i) {
    x = x * 1664525u + 1013904223u;
    const double mantissa = static_cast<double>(x >> 8) / 16777216.0 - 0.5;
    static constexpr double kScale[] = {1e-3, 1e-1, 1.0, 1e2, 1e4};
    v[i] = mantissa * kScale[(x >> 3) % 5];
  }
  return v;
}

uint64_t bits(double d) { return std::bit_cast<uint64_t>(d); }

// Expects the same double, bit for bit.
#define EXPECT_SAME_BITS(actual, expected) \
  EXPECT_EQ(bits(actual), bits(expected)) << (actual) << " vs " << (expected)

Value blocked_vector(const std::vector<double>& components, int block) {
  Tensor t(ComponentKind::Float,
           Shape::blocked({static_cast<int>(components.size()) / block}, Shape{block}));
  for (size_t i = 0; i < components.size(); ++i) t.mutable_floats()[i] = components[i];
  return Value::of_tensor(std::move(t));
}

TEST(IndexNotationOrder, GenericDimensionSumsInTheBlockedOrderLikeTheInnerProduct) {
  auto c = compile(
      "func f<N>(u : vector[N](float), v : vector[N](float)) -> (s : float, t : float)\n"
      "  ivar i;\n  s = u(i) * v(i);\n  t = u' * v;\nend\n");
  Interpreter in(*c->program);
  for (size_t n : {0, 1, 3, 31, 32, 33, 255, 256, 257, 600, 1000}) {
    SCOPED_TRACE(n);
    const std::vector<double> u = spread(n, 11), v = spread(n, 29);
    std::vector<double> t(n);
    for (size_t e = 0; e < n; ++e) t[e] = 0.0 + u[e] * v[e];
    const double expected = blocked(t);
    // The data tell the orders apart (the old row-major sum would fail here).
    if (n >= 256) {
      EXPECT_NE(bits(expected), bits(left_to_right(t)));
    }
    auto r = in.call(func(*c, "f"), {testing::vector(u), testing::vector(v)});
    EXPECT_SAME_BITS(r[0].as_float(), expected);
    EXPECT_SAME_BITS(r[1].as_float(), expected);
  }
}

// A block's components (a dense reduction variable) sum first, from +0.0 in order, whether
// the dense variable appears first or not; a sum of blocks is blocked component by component.
TEST(IndexNotationOrder, BlockComponentsSumPerElementThenTheElementsBlocked) {
  auto c = compile(
      "func f<N>(u : vector[N](vector[3](float)), v : vector[N](vector[3](float)),\n"
      "          a : vector[3](float))\n"
      "    -> (s : float, t : float, r : float, w : vector[3](float), b : vector[3](float))\n"
      "  ivar i;\n  ivar c;\n"
      "  s = u(i)(c) * v(i)(c);\n  t = u' * v;\n  r = a(c) * u(i)(c);\n"
      "  w(c) = u(i)(c);\n  b = u(i);\nend\n");
  Interpreter in(*c->program);
  const size_t n = 700;
  const std::vector<double> u = spread(3 * n, 5), v = spread(3 * n, 17), a = spread(3, 41);
  std::vector<double> ts(n), tr(n);
  std::vector<std::vector<double>> comp(3, std::vector<double>(n));
  for (size_t e = 0; e < n; ++e) {
    double s = 0.0, q = 0.0;
    for (size_t k = 0; k < 3; ++k) {
      s = s + u[3 * e + k] * v[3 * e + k];
      q = q + a[k] * u[3 * e + k];
      comp[k][e] = 0.0 + u[3 * e + k];
    }
    ts[e] = s;
    tr[e] = q;
  }
  std::vector<double> row_major;
  for (size_t k = 0; k < 3 * n; ++k) row_major.push_back(u[k] * v[k]);
  ASSERT_NE(bits(blocked(ts)), bits(left_to_right(row_major)));

  auto res =
      in.call(func(*c, "f"), {blocked_vector(u, 3), blocked_vector(v, 3), testing::vector(a)});
  EXPECT_SAME_BITS(res[0].as_float(), blocked(ts));
  EXPECT_SAME_BITS(res[1].as_float(), blocked(ts));
  EXPECT_SAME_BITS(res[2].as_float(), blocked(tr));
  for (int k = 0; k < 3; ++k) {
    SCOPED_TRACE(k);
    EXPECT_SAME_BITS(res[3].tensor().floats()[k], blocked(comp[k]));
    EXPECT_SAME_BITS(res[4].tensor().floats()[k], blocked(comp[k]));
  }
}

// `s = u(i) * v(j)`: for every i the blocked sum over j, then the blocked sum over i; the
// same bits as the two steps `q(i) = u(i) * v(j)` and `r = q(i)`.
TEST(IndexNotationOrder, TwoSetVariablesNestTheFirstOutermost) {
  auto c = compile(
      "func f<N>(u : vector[N](float), v : vector[N](float)) -> (s : float, r : float)\n"
      "  ivar i;\n  ivar j;\n  s = u(i) * v(j);\n"
      "  var q : vector[N](float);\n  q(i) = u(i) * v(j);\n  r = q(i);\nend\n");
  Interpreter in(*c->program);
  const size_t n = 300;
  const std::vector<double> u = spread(n, 3), v = spread(n, 7);
  std::vector<double> inner(n), inner_left(n), all;
  for (size_t i = 0; i < n; ++i) {
    std::vector<double> t(n);
    for (size_t j = 0; j < n; ++j) {
      t[j] = 0.0 + u[i] * v[j];
      all.push_back(u[i] * v[j]);
    }
    inner[i] = blocked(t);
    inner_left[i] = left_to_right(t);
  }
  const double expected = blocked(inner);
  // Neither the row-major sum nor inner sums taken left to right give these bits.
  ASSERT_NE(bits(expected), bits(left_to_right(all)));
  ASSERT_NE(bits(expected), bits(blocked(inner_left)));
  auto res = in.call(func(*c, "f"), {testing::vector(u), testing::vector(v)});
  EXPECT_SAME_BITS(res[0].as_float(), expected);
  EXPECT_SAME_BITS(res[1].as_float(), expected);
}

// A sum over a fixed dimension keeps the row-major order, however long.
TEST(IndexNotationOrder, DenseDimensionsStayLeftToRight) {
  auto c = compile(
      "func f(u : vector[600](float), v : vector[600](float)) -> s : float\n"
      "  ivar i;\n  s = u(i) * v(i);\nend\n");
  Interpreter in(*c->program);
  const std::vector<double> u = spread(600, 13), v = spread(600, 19);
  std::vector<double> t(600);
  for (size_t e = 0; e < t.size(); ++e) t[e] = u[e] * v[e];
  ASSERT_NE(bits(blocked(t)), bits(left_to_right(t)));
  EXPECT_SAME_BITS(in.call(func(*c, "f"), {testing::vector(u), testing::vector(v)})[0].as_float(),
                   left_to_right(t));
}

// The fields of a bound set: a set dimension, as in a simulation.
TEST(IndexNotationOrder, SetFieldsSumInTheBlockedOrder) {
  auto c = compile(
      "element N  x : float; y : float; end\nextern nodes : set{N};\n"
      "export func f() -> (s : float, t : float)\n"
      "  ivar i;\n  s = nodes.x(i) * nodes.y(i);\n  t = nodes.x' * nodes.y;\nend\n");
  Interpreter in(*c->program);
  const frontend::ast::Variable* ext = nullptr;
  for (const auto* v : c->program->globals)
    if (v && v->name == "nodes") ext = v;
  ASSERT_NE(ext, nullptr);
  const size_t n = 513;  // three chunks, the last one of a single element
  runtime::Set nodes{"nodes"};
  nodes.add_many(static_cast<int>(n));
  for (const frontend::ast::FieldDecl& f : ext->type->element->fields)
    nodes.add_field(f.name, field_type_of(*f.type));
  const std::vector<double> x = spread(n, 23), y = spread(n, 31);
  std::vector<double> t(n);
  for (size_t e = 0; e < n; ++e) {
    nodes.field("x").data<double>()[e] = x[e];
    nodes.field("y").data<double>()[e] = y[e];
    t[e] = 0.0 + x[e] * y[e];
  }
  ASSERT_NE(bits(blocked(t)), bits(left_to_right(t)));
  in.bind_set(*ext, nodes);
  auto r = in.call(func(*c, "f"), {});
  EXPECT_SAME_BITS(r[0].as_float(), blocked(t));
  EXPECT_SAME_BITS(r[1].as_float(), blocked(t));
}

// Complex components follow the same order: real and imaginary parts each blocked.
TEST(IndexNotationOrder, ComplexSumsAreBlocked) {
  auto c = compile(
      "func f<N>(u : vector[N](complex), v : vector[N](complex)) -> s : complex\n"
      "  ivar i;\n  s = u(i) * v(i);\nend\n");
  Interpreter in(*c->program);
  const size_t n = 400;
  const std::vector<double> a = spread(2 * n, 2), b = spread(2 * n, 9);
  Tensor tu(ComponentKind::Complex, Shape{static_cast<int>(n)});
  Tensor tv(ComponentKind::Complex, Shape{static_cast<int>(n)});
  std::vector<Cx> t(n);
  for (size_t e = 0; e < n; ++e) {
    const Cx x(a[2 * e], a[2 * e + 1]), y(b[2 * e], b[2 * e + 1]);
    tu.mutable_complexes()[e] = x;
    tv.mutable_complexes()[e] = y;
    t[e] = Cx() + x * y;
  }
  const Cx expected = blocked(t);
  ASSERT_NE(expected, left_to_right(t));
  const Value r =
      in.call(func(*c, "f"), {Value::of_tensor(std::move(tu)), Value::of_tensor(std::move(tv))})[0];
  ASSERT_EQ(r.kind(), Value::Kind::Complex);
  EXPECT_SAME_BITS(r.as_complex().real(), expected.real());
  EXPECT_SAME_BITS(r.as_complex().imag(), expected.imag());
}

// Under --float32 every product and every addition of the blocked order rounds to binary32.
TEST(IndexNotationOrder, Float32RoundsEveryAdditionOfTheBlockedOrder) {
  auto c = compile(
      "func f<N>(u : vector[N](float), v : vector[N](float)) -> s : float\n"
      "  ivar i;\n  s = u(i) * v(i);\nend\n");
  Options o;
  o.float32 = true;
  Interpreter in(*c->program, o);
  const size_t n = 300;
  std::vector<double> u = spread(n, 37), v = spread(n, 43);
  std::vector<float> t(n);
  for (size_t e = 0; e < n; ++e) {
    u[e] = static_cast<float>(u[e]);
    v[e] = static_cast<float>(v[e]);
    t[e] = 0.0f + static_cast<float>(u[e]) * static_cast<float>(v[e]);
  }
  ASSERT_NE(blocked(t), left_to_right(t));
  EXPECT_SAME_BITS(in.call(func(*c, "f"), {testing::vector(u), testing::vector(v)})[0].as_float(),
                   static_cast<double>(blocked(t)));
}

}  // namespace
}  // namespace simit::interp
