// The interpreter's host-facing behaviour: calls, run-time errors and their stacks, the
// float32 and check-finite options, print formats, the statement hook, externs.
#include <sstream>

#include "interp/hook.h"
#include "test_util.h"

namespace simit::interp {
namespace {

using testing::compile;
using testing::func;

TEST(Interpreter, CallsAFunctionAndReturnsEveryResult) {
  auto c = compile(
      "func f(a : int, b : float) -> (x : int, y : float, z : vector[2](float))\n"
      "  x = a * 2;\n  y = b + 1.0;\n  z(1) = b;\nend\n");
  Interpreter in(*c->program);
  auto r = in.call(func(*c, "f"), {Value::of_int(4), Value::of_float(0.5)});
  ASSERT_EQ(r.size(), 3u);
  EXPECT_EQ(r[0], Value::of_int(8));
  EXPECT_EQ(r[1], Value::of_float(1.5));
  EXPECT_EQ(r[2], testing::vector({0.0, 0.5}));
}

TEST(Interpreter, GenericParametersTakeTheArgumentSizes) {
  auto c = compile(
      "func n<0:N>(v : vector[N](float)) -> (k : int, w : vector[N](float))\n"
      "  k = N;\n  w = 2.0 * v;\nend\n");
  Interpreter in(*c->program);
  auto r = in.call(func(*c, "n"), {testing::vector({1, 2, 3, 4, 5})});
  EXPECT_EQ(r[0], Value::of_int(5));
  EXPECT_EQ(r[1], testing::vector({2, 4, 6, 8, 10}));
  r = in.call(func(*c, "n"), {testing::vector({1})});
  EXPECT_EQ(r[0], Value::of_int(1));
}

// A flat chain is not nesting: sums of 300 and 1000 terms (beyond the 256 levels of nesting)
// compile and run, left to right; a chain of 1100 is refused by the parser's tree limit.
TEST(Interpreter, LongFlatChainsRun) {
  auto chain = [](int terms, const char* op) {
    std::string s = "a";
    for (int i = 1; i < terms; ++i) s += std::string(" ") + op + " a";
    return "func f(a : float) -> r : float\n  r = " + s + ";\nend\n";
  };
  for (int terms : {300, 1000}) {
    auto c = compile(chain(terms, "+"));
    Interpreter in(*c->program);
    EXPECT_EQ(in.call(func(*c, "f"), {Value::of_float(0.5)})[0], Value::of_float(0.5 * terms));
  }
  auto c = compile(chain(1000, "-"));
  Interpreter in(*c->program);
  EXPECT_EQ(in.call(func(*c, "f"), {Value::of_float(0.5)})[0], Value::of_float(0.5 - 999 * 0.5));
  auto too_long = frontend::compile_source("long.sim", chain(1100, "*"));
  ASSERT_FALSE(too_long->ok());
  EXPECT_EQ(too_long->diagnostics.items().front().message,
            "expression is too long: more than 1024 levels of chained operators and nesting");
}

TEST(Interpreter, ArgumentsOfTheWrongCountAreARuntimeError) {
  auto c = compile("func f(a : int) -> r : int\n  r = a;\nend\n");
  Interpreter in(*c->program);
  EXPECT_THROW(in.call(func(*c, "f"), {}), RuntimeError);
}

TEST(RuntimeErrors, CarryLocationMessageAndStack) {
  auto c = compile(
      "func inner(v : vector[2](float), i : int) -> r : float\n"  // 1
      "  r = v(i);\n"                                             // 2
      "end\n"
      "func outer(i : int) -> r : float\n"  // 4
      "  x = 1.0;\n"
      "  r = x + inner([1.0, 2.0]', i);\n"  // 6
      "end\n",
      "errors.sim");
  Interpreter in(*c->program);
  try {
    in.call(func(*c, "outer"), {Value::of_int(2)});
    FAIL() << "expected a run-time error";
  } catch (const RuntimeError& e) {
    EXPECT_EQ(e.line(), 2);
    EXPECT_EQ(e.where().start().column, 9);
    EXPECT_EQ(e.message(), "index 2 is out of range for a dimension of size 2");
    ASSERT_EQ(e.stack().size(), 2u);
    EXPECT_EQ(e.stack()[0].func, "inner");
    EXPECT_EQ(e.stack()[0].at.start().line, 2);
    EXPECT_EQ(e.stack()[1].func, "outer");
    EXPECT_EQ(e.stack()[1].at.start().line, 6);
    EXPECT_EQ(e.render(),
              "errors.sim:2:9: runtime error: index 2 is out of range for a dimension of size 2\n"
              "  in inner (errors.sim:2)\n"
              "  in outer (errors.sim:6)\n");
  }
  // The interpreter stays usable after an error.
  auto r = in.call(func(*c, "outer"), {Value::of_int(1)});
  EXPECT_EQ(r[0], Value::of_float(3.0));
}

TEST(RuntimeErrors, EveryKindIsReportedNotCrashed) {
  auto c = compile(
      "func div(a : int, b : int) -> r : int\n  r = a / b;\nend\n"
      "func md(a : int, b : int) -> r : int\n  r = mod(a, b);\nend\n"
      "func iv(a : matrix[3,3](float)) -> r : matrix[3,3](float)\n  r = inv(a);\nend\n"
      "func minint(a : int) -> r : int\n  r = (a - 1) / -1 + mod(a - 1, -1);\nend\n");
  Interpreter in(*c->program);
  auto message = [&](const char* f, std::vector<Value> args) -> std::string {
    try {
      in.call(func(*c, f), std::move(args));
    } catch (const RuntimeError& e) {
      return e.message();
    }
    return "";
  };
  EXPECT_EQ(message("div", {Value::of_int(1), Value::of_int(0)}), "integer division by zero");
  EXPECT_EQ(message("md", {Value::of_int(1), Value::of_int(0)}), "mod by zero");
  EXPECT_NE(message("iv", {testing::matrix(3, 3, {1, 2, 3, 2, 4, 6, 0, 0, 1})}).find("singular"),
            std::string::npos);
  // INT_MIN / -1 and INT_MIN mod -1 wrap instead of trapping.
  auto r = in.call(func(*c, "minint"), {Value::of_int(-2147483647)});
  EXPECT_EQ(r[0], Value::of_int(-2147483647 - 1));
}

TEST(RuntimeErrors, UnboundSetIsReported) {
  auto c = compile(
      "element P\n  x : float;\nend\nextern ps : set{P};\n"
      "func get(p : P) -> r : vector[ps](float)\n  r(p) = p.x;\nend\n"
      "export func f() -> s : float\n  v = map get to ps reduce +;\n  s = norm(v);\nend\n");
  Interpreter in(*c->program);
  try {
    in.call(func(*c, "f"), {});
    FAIL() << "expected a run-time error";
  } catch (const RuntimeError& e) {
    EXPECT_NE(e.message().find("ps"), std::string::npos) << e.message();
  }
}

const char* kFinite =
    "func q(a : float, b : float) -> r : float\n"
    "  x = a * 2.0;\n"
    "  r = x / b;\n"
    "end\n";

TEST(CheckFinite, OffByDefault) {
  auto c = compile(kFinite);
  Interpreter in(*c->program);
  auto r = in.call(func(*c, "q"), {Value::of_float(1.0), Value::of_float(0.0)});
  EXPECT_TRUE(std::isinf(r[0].as_float()));
}

TEST(CheckFinite, StopsAtTheFirstNanOrInfinity) {
  auto c = compile(kFinite, "finite.sim");
  Options o;
  o.check_finite = true;
  Interpreter in(*c->program, o);
  try {
    in.call(func(*c, "q"), {Value::of_float(0.0), Value::of_float(0.0)});
    FAIL() << "expected a run-time error";
  } catch (const RuntimeError& e) {
    EXPECT_EQ(e.line(), 3);
    EXPECT_EQ(e.message(), "the operation produced NaN");
  }
  try {
    in.call(func(*c, "q"), {Value::of_float(1.0), Value::of_float(0.0)});
    FAIL() << "expected a run-time error";
  } catch (const RuntimeError& e) {
    EXPECT_EQ(e.message(), "the operation produced an infinity");
  }
  try {
    in.call(func(*c, "q"), {Value::of_float(1e308), Value::of_float(1.0)});
    FAIL() << "expected a run-time error";
  } catch (const RuntimeError& e) {
    EXPECT_EQ(e.line(), 2);  // the overflow happens in the multiplication
  }
  auto r = in.call(func(*c, "q"), {Value::of_float(1.0), Value::of_float(4.0)});
  EXPECT_EQ(r[0], Value::of_float(0.5));
}

TEST(CheckFinite, CoversIntrinsicsAndTensors) {
  auto c = compile(
      "func l(x : float) -> r : float\n  r = log(x);\nend\n"
      "func v(x : vector[2](float)) -> r : vector[2](float)\n  r = x ./ x;\nend\n");
  Options o;
  o.check_finite = true;
  Interpreter in(*c->program, o);
  EXPECT_THROW(in.call(func(*c, "l"), {Value::of_float(0.0)}), RuntimeError);
  EXPECT_THROW(in.call(func(*c, "v"), {testing::vector({1.0, 0.0})}), RuntimeError);
  EXPECT_NO_THROW(in.call(func(*c, "v"), {testing::vector({1.0, 2.0})}));
}

TEST(Float32, EveryFloatIsRoundedToBinary32) {
  auto c = compile(
      "func s(a : float, b : float) -> r : float\n  r = a + b;\nend\n"
      "func lit() -> r : float\n  r = 0.1;\nend\n"
      "func m() -> r : matrix[2,2](float)\n  r = [0.1, 0.2; 0.3, 0.4] * 3.0;\nend\n");
  Options o;
  o.float32 = true;
  Interpreter in(*c->program, o);
  float a = 0.1f, b = 0.2f;
  auto r = in.call(func(*c, "s"), {Value::of_float(a), Value::of_float(b)});
  EXPECT_EQ(r[0].as_float(), static_cast<double>(a + b));
  EXPECT_EQ(in.call(func(*c, "lit"), {})[0].as_float(), static_cast<double>(0.1f));
  Value mv = in.call(func(*c, "m"), {})[0];
  EXPECT_EQ(mv.tensor().floats()[2], static_cast<double>(0.3f * 3.0f));
  Interpreter wide(*c->program);
  EXPECT_EQ(wide.call(func(*c, "lit"), {})[0].as_float(), 0.1);
}

std::string printed(const std::string& body) {
  auto c = compile("func p()\n" + body + "end\n");
  std::ostringstream out;
  Options o;
  o.out = &out;
  Interpreter in(*c->program, o);
  in.call(func(*c, "p"), {});
  return out.str();
}

TEST(Print, ScalarFormats) {
  EXPECT_EQ(printed("  print 3, \" \", -2.5, \" \", 1e20, \" \", true, \" \", false;\n"),
            "3 -2.5 1e+20 1 0");
  EXPECT_EQ(printed("  println <1.5, -2.0>, \"|\", \"text\";\n"), "<1.5,-2>|text\n");
  EXPECT_EQ(printed("  println 1.0 / 3.0;\n"), "0.333333\n");
}

TEST(Print, TensorLayouts) {
  EXPECT_EQ(printed("  print [1.0, 2.0, 3.0];\n"), "1 2 3");
  EXPECT_EQ(printed("  print [1.0, 2.0, 3.0]';\n"), "1\n2\n3");
  EXPECT_EQ(printed("  print [1, 2; 3, 4];\n"), "1 2\n3 4");
  EXPECT_EQ(printed("  print [[1, 2; 3, 4], [5, 6; 7, 8]];\n"),
            "(0, 0, 0) 1\n(0, 0, 1) 2\n(0, 1, 0) 3\n(0, 1, 1) 4\n"
            "(1, 0, 0) 5\n(1, 0, 1) 6\n(1, 1, 0) 7\n(1, 1, 1) 8");
  EXPECT_EQ(printed("  var v : vector[2](vector[2](int));\n  v(1) = [3, 4]';\n  print v;\n"),
            "(0)(0) 0\n(0)(1) 0\n(1)(0) 3\n(1)(1) 4");
}

// An error statement formats its message as println would, writes nothing to the output and
// stops before the next statement.
TEST(ErrorStatement, StopsWithThePrintedTextAsItsMessage) {
  auto c = compile(
      "func p(n : int)\n"
      "  println \"before\";\n"
      "  if n > 2\n"
      "    error \"n = \", n, \", v = \", [1.5, -2.0], \", w =\\n\", [1.0, 2.0]';\n"
      "  end\n"
      "  println \"after\";\n"
      "end\n",
      "err.sim");
  std::ostringstream out;
  Options o;
  o.out = &out;
  Interpreter in(*c->program, o);
  in.call(func(*c, "p"), {Value::of_int(1)});
  EXPECT_EQ(out.str(), "before\nafter\n");
  out.str("");
  try {
    in.call(func(*c, "p"), {Value::of_int(3)});
    FAIL() << "expected a run-time error";
  } catch (const RuntimeError& e) {
    EXPECT_EQ(e.line(), 4);
    EXPECT_EQ(e.where().start().column, 5);
    EXPECT_EQ(e.message(), "n = 3, v = 1.5 -2, w =\n1\n2");
    EXPECT_EQ(e.render(),
              "err.sim:4:5: runtime error: n = 3, v = 1.5 -2, w =\n1\n2\n  in p (err.sim:4)\n");
  }
  EXPECT_EQ(out.str(), "before\n");
}

class CountingHook : public StatementHook {
 public:
  void before_statement(const frontend::ast::Stmt& stmt, const frontend::ast::FuncDecl& func,
                        int depth, const Interpreter& interpreter) override {
    ++count;
    max_depth = std::max(max_depth, depth);
    lines.push_back(stmt.span.start().line);
    if (func.name == "g" && !func.params.empty()) {
      const Value* x = interpreter.local(*func.params[0].var);
      if (x) seen_x = x->as_int();
    }
  }
  int count = 0;
  int max_depth = -1;
  int seen_x = 0;
  std::vector<int> lines;
};

TEST(StatementHook, SeesEveryStatementWithItsDepth) {
  if (!kStatementHook) GTEST_SKIP() << "built with SIMIT_STATEMENT_HOOK=OFF";
  auto c = compile(
      "func g(x : int) -> r : int\n"  // 1
      "  r = x + 1;\n"                // 2
      "end\n"                         // 3
      "func f() -> r : int\n"         // 4
      "  for i in 0:3\n"              // 5
      "    r = r + g(i);\n"           // 6
      "  end\n"
      "end\n");
  CountingHook hook;
  Options o;
  o.hook = &hook;
  Interpreter in(*c->program, o);
  auto r = in.call(func(*c, "f"), {});
  EXPECT_EQ(r[0], Value::of_int(6));
  EXPECT_EQ(hook.count, 1 + 3 * 2);  // the loop, then per iteration one statement in each function
  EXPECT_EQ(hook.max_depth, 1);
  EXPECT_EQ(hook.seen_x, 2);
  EXPECT_EQ(hook.lines.front(), 5);
}

TEST(Externs, BoundByTheHost) {
  auto c = compile(
      "extern scale : vector[2](float);\n"
      "func f(x : float) -> r : vector[2](float)\n  r = x * scale;\n  scale(0) = 9.0;\nend\n");
  Interpreter in(*c->program);
  const frontend::ast::Variable* scale = c->program->globals.at(0);
  EXPECT_THROW(in.call(func(*c, "f"), {Value::of_float(2.0)}), RuntimeError);
  in.set_global(*scale, testing::vector({1.0, -1.0}));
  auto r = in.call(func(*c, "f"), {Value::of_float(2.0)});
  EXPECT_EQ(r[0], testing::vector({2.0, -2.0}));
  EXPECT_EQ(in.global(*scale), testing::vector({9.0, -1.0}));  // externs are read-write
}

TEST(Constants, GlobalConstantsAreEvaluatedOnce) {
  auto c = compile(
      "const k : tensor[1,2](int) = [3, 4];\n"
      "func f() -> r : int\n  r = k(0, 1);\nend\n");
  Interpreter in(*c->program);
  EXPECT_EQ(in.call(func(*c, "f"), {})[0], Value::of_int(4));
  const frontend::ast::Variable* k = c->program->globals.at(0);
  EXPECT_EQ(in.global(*k).shape(), (Shape{1, 2}));
}

TEST(Values, ZerosComponentsAndFills) {
  EXPECT_EQ(Value::zero(ComponentKind::Complex), Value::of_complex({0, 0}));
  EXPECT_EQ(Value::zero(ComponentKind::String), Value::of_string(""));
  Value z = Value::zero(ComponentKind::Int, Shape{2, 2});
  ASSERT_TRUE(z.is_tensor());
  Value::of_int(5).fill_into(z.tensor(), 1, 2);
  EXPECT_EQ(Value::component(z.tensor(), 2), Value::of_int(5));
  EXPECT_EQ(Value::component(z.tensor(), 3), Value::of_int(0));
  EXPECT_EQ(Value::of_float(2.0).to_tensor().shape(), Shape());
  EXPECT_TRUE(Value().empty());
}

}  // namespace
}  // namespace simit::interp
