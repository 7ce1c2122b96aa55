// Unit tests of the parser (LANGUAGE.md §3, §6.1, §6.2.6): precedence, literals, names,
// statements and declarations, with their error locations (recovery, the printers and the
// corpus round trip: parser_recovery_test.cpp).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <memory>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "parser_support.h"

namespace simit::frontend {
namespace {

using namespace ast;
using namespace parser_support;

// ---------------------------------------------------------------------------
// Precedence (§6.1)

TEST(ParserPrecedence, ArithmeticLevels) {
  EXPECT_EQ(printed("a + b * c"), "a + (b * c)");
  EXPECT_EQ(printed("a * b + c"), "(a * b) + c");
  EXPECT_EQ(printed("a - b - c"), "(a - b) - c");
  EXPECT_EQ(printed("a / b * c"), "(a / b) * c");
  EXPECT_EQ(printed("a .* b ./ c \\ d"), "((a .* b) ./ c) \\ d");
  EXPECT_EQ(printed("a ^ b ^ c"), "a ^ (b ^ c)");
  EXPECT_EQ(printed("a * b ^ c"), "a * (b ^ c)");
}

TEST(ParserPrecedence, UnaryAndTranspose) {
  EXPECT_EQ(printed("-a * b"), "(-a) * b");
  EXPECT_EQ(printed("a * -b"), "a * (-b)");
  EXPECT_EQ(printed("-x'"), "-x'");
  EXPECT_EQ(printed("A * B'"), "A * B'");
  EXPECT_EQ(printed("(A * B)'"), "(A * B)'");
  EXPECT_EQ(printed("2.0 * x(i)"), "2.0 * x(i)");
  EXPECT_EQ(printed("-x ^ 2"), "-(x ^ 2)");
  EXPECT_EQ(printed("x''"), "x''");
  EXPECT_EQ(printed("--x"), "- -x");
  EXPECT_EQ(printed("not not b"), "not not b");
  EXPECT_EQ(printed("(0).k"), "(0).k");
  EXPECT_EQ(printed("not -x"), "not -x");
  EXPECT_EQ(printed("-(not b)"), "-(not b)");

  auto p = parse_expr_text("-x'");
  const auto* neg = p.expr->as<Unary>();
  ASSERT_NE(neg, nullptr);
  EXPECT_EQ(neg->op, Unary::Op::Neg);
  EXPECT_TRUE(neg->operand->is<Transpose>());
}

TEST(ParserPrecedence, BooleanLevels) {
  EXPECT_EQ(printed("not a == b"), "(not a) == b");
  EXPECT_EQ(printed("not a and b"), "(not a) and b");
  EXPECT_EQ(printed("not a + b"), "not (a + b)");
  EXPECT_EQ(printed("not not a"), "not not a");
  EXPECT_EQ(printed("a or b and c"), "a or (b and c)");
  EXPECT_EQ(printed("a and b xor c"), "a and (b xor c)");
  EXPECT_EQ(printed("a xor b and c"), "(a xor b) and c");
  EXPECT_EQ(printed("a or b or c"), "(a or b) or c");
  EXPECT_EQ(printed("a + b == c and d or e"), "(((a + b) == c) and d) or e");
}

TEST(ParserPrecedence, ComparisonChains) {
  auto p = parse_expr_text("a < b <= c");
  const auto* cmp = p.expr->as<Compare>();
  ASSERT_NE(cmp, nullptr);
  ASSERT_EQ(cmp->operands.size(), 3u);
  EXPECT_EQ(cmp->ops, (std::vector<Compare::Op>{Compare::Op::Lt, Compare::Op::Le}));
  EXPECT_EQ(printed("a == b != c > d >= e"), "a == b != c > d >= e");
  EXPECT_EQ(printed("a + 1 < b * 2"), "(a + 1) < (b * 2)");
}

// ---------------------------------------------------------------------------
// Literals and folding (§6.2, §6.2.6)

TEST(ParserLiterals, SignsFoldIntoLiterals) {
  auto p = parse_expr_text("--+-1.0");
  ASSERT_TRUE(p.expr->is<FloatLit>());
  EXPECT_EQ(p.expr->as<FloatLit>()->value, -1.0);

  p = parse_expr_text("-3");
  ASSERT_TRUE(p.expr->is<IntLit>());
  EXPECT_EQ(p.expr->as<IntLit>()->value, -3);
  LineCol lc = p.expr->span.start();
  EXPECT_EQ(lc.column, 7);  // the span covers the sign
  EXPECT_EQ(p.expr->span.end - p.expr->span.begin, 2u);

  p = parse_expr_text("-<1.0, -2.0>");
  ASSERT_TRUE(p.expr->is<ComplexLit>());
  EXPECT_EQ(p.expr->as<ComplexLit>()->value, std::complex<double>(-1.0, 2.0));

  p = parse_expr_text("-[1, -2]");
  ASSERT_TRUE(p.expr->is<DenseLit>());
  EXPECT_EQ(p.expr->as<DenseLit>()->ints, (std::vector<long long>{-1, 2}));

  EXPECT_TRUE(parse_expr_text("-x").expr->is<Unary>());
  EXPECT_TRUE(parse_expr_text("+x").expr->is<Unary>());
  EXPECT_TRUE(parse_expr_text("1 + 2").expr->is<Binary>());
  EXPECT_TRUE(parse_expr_text("-\"s\"").expr->is<Unary>());
}

TEST(ParserLiterals, TransposeFolding) {
  auto p = parse_expr_text("[1.0, 2.0]'");
  const auto* d = p.expr->as<DenseLit>();
  ASSERT_NE(d, nullptr);
  EXPECT_TRUE(d->column);

  p = parse_expr_text("[1.0, 2.0]''");
  ASSERT_TRUE(p.expr->is<DenseLit>());
  EXPECT_FALSE(p.expr->as<DenseLit>()->column);

  p = parse_expr_text("-[1.0, 2.0]'");
  ASSERT_TRUE(p.expr->is<DenseLit>());
  EXPECT_TRUE(p.expr->as<DenseLit>()->column);
  EXPECT_EQ(p.expr->as<DenseLit>()->floats, (std::vector<double>{-1.0, -2.0}));

  EXPECT_TRUE(parse_expr_text("3'").expr->is<IntLit>());
  EXPECT_TRUE(parse_expr_text("[1, 2; 3, 4]'").expr->is<Transpose>());
  EXPECT_TRUE(parse_expr_text("x'").expr->is<Transpose>());
}

TEST(ParserLiterals, ScalarLiterals) {
  EXPECT_EQ(parse_expr_text("12").expr->as<IntLit>()->value, 12);
  EXPECT_EQ(parse_expr_text("2e3").expr->as<FloatLit>()->value, 2000.0);
  EXPECT_TRUE(parse_expr_text("true").expr->as<BoolLit>()->value);
  EXPECT_FALSE(parse_expr_text("false").expr->as<BoolLit>()->value);
  EXPECT_EQ(parse_expr_text("\"a\\n\"").expr->as<StringLit>()->value, "a\n");
  EXPECT_EQ(parse_expr_text("<0.5, -1.0>").expr->as<ComplexLit>()->value,
            std::complex<double>(0.5, -1.0));
}

const DenseLit& dense(const ParsedExpr& p) {
  const auto* d = p.expr ? p.expr->as<DenseLit>() : nullptr;
  if (!d) throw std::runtime_error("not a dense literal");
  return *d;
}

TEST(ParserLiterals, DenseShapes) {
  auto p = parse_expr_text("[1.0, 2.0, 3.0]");
  EXPECT_EQ(dense(p).shape, std::vector<int>{3});
  EXPECT_EQ(dense(p).component, ScalarKind::Float);
  EXPECT_FALSE(dense(p).column);

  p = parse_expr_text("[1, 2, 3; 4, 5, 6]");
  EXPECT_EQ(dense(p).shape, (std::vector<int>{2, 3}));
  EXPECT_EQ(dense(p).ints, (std::vector<long long>{1, 2, 3, 4, 5, 6}));

  p = parse_expr_text("[[1, 2], [3, 4]]");
  EXPECT_EQ(dense(p).shape, (std::vector<int>{2, 2}));
  EXPECT_EQ(dense(p).ints, (std::vector<long long>{1, 2, 3, 4}));

  p = parse_expr_text("[[1.0, 2.0; 3.0, 4.0], [5.0, 6.0; 7.0, 8.0]]");
  EXPECT_EQ(dense(p).shape, (std::vector<int>{2, 2, 2}));
  EXPECT_EQ(dense(p).floats[5], 6.0);

  EXPECT_EQ(dense(parse_expr_text("[[1, 2] [3, 4]]")).shape, (std::vector<int>{2, 2}));
  EXPECT_EQ(dense(parse_expr_text("[[1.0, 2.0]]")).shape, (std::vector<int>{1, 2}));
  EXPECT_EQ(dense(parse_expr_text("[4.0; 5.0]")).shape, (std::vector<int>{2, 1}));
  EXPECT_EQ(dense(parse_expr_text("[7]")).shape, std::vector<int>{1});
}

TEST(ParserLiterals, DenseSignsAndCommas) {
  for (const char* text : {"[1.0 -2.0]", "[1.0, -2.0]", "[1.0 - 2.0]"}) {
    auto p = parse_expr_text(text);
    EXPECT_EQ(dense(p).floats, (std::vector<double>{1.0, -2.0})) << text;
    EXPECT_EQ(dense(p).shape, std::vector<int>{2}) << text;
  }
  auto p = parse_expr_text("[<1.0, 0.0>, <0.0, -1.0>]");
  EXPECT_EQ(dense(p).component, ScalarKind::Complex);
  EXPECT_EQ(dense(p).complexes[1], std::complex<double>(0.0, -1.0));
}

TEST(ParserLiterals, DenseShapeErrorsAreSemantic) {
  for (const char* text : {"[1, 2; 3]", "[[1, 2], [3]]", "[[1, 2], [3.0, 4.0]]", "[1, 2; 3.0, 4.0]",
                           "[[1, 2], [[3, 4]]]"}) {
    auto p = parse_expr_text(text);
    EXPECT_FALSE(dense(p).shape_error.empty()) << text;
  }
  EXPECT_EQ(dense(parse_expr_text("[1, 2; 3]")).shape_error, "mismatched dimension sizes");
  EXPECT_EQ(dense(parse_expr_text("[1, 2; 3.0, 4.0]")).shape_error, "mismatched element types");
}

TEST(ParserLiterals, MalformedDenseLiteralsAreSyntaxErrors) {
  EXPECT_EQ(first_error("func f()\n  r = [1, 2.0];\nend"),
            "2:11 expected an integer literal but got float literal 2.0");
  EXPECT_EQ(first_error_at("func f()\n  r = [];\nend"), "2:8");
  EXPECT_EQ(first_error_at("func f()\n  r = [x];\nend"), "2:8");
  EXPECT_EQ(first_error_at("func f()\n  r = [1, 2,];\nend"), "2:13");
  EXPECT_EQ(first_error_at("func f()\n  r = [[1], 2];\nend"), "2:13");
  EXPECT_EQ(first_error_at("func f()\n  r = <1, 2>;\nend"), "2:8");
}

// ---------------------------------------------------------------------------
// Names (§3.6.1, §3.6.2)

TEST(ParserNames, CallsNeedEarlierDeclarations) {
  auto p = parse_ok(
      "func g(x : float) -> y : float\n  y = x;\nend\n"
      "func f()\n  a = g(1.0);\n  b = h(1.0);\n  c = norm(v);\nend\n"
      "func h(x : float) -> y : float\n  y = x;\nend\n");
  const Block& body = p->func(1).body;
  EXPECT_TRUE(body[0]->as<Assign>()->value->is<Call>());
  const auto* later = body[1]->as<Assign>()->value->as<TensorRead>();
  ASSERT_NE(later, nullptr);
  EXPECT_TRUE(later->base->is<VarRef>());
  EXPECT_TRUE(body[2]->as<Assign>()->value->is<Call>());
}

TEST(ParserNames, ValuesHideFunctions) {
  auto p = parse_ok(
      "element Cell\n  weight : float;\nend\n"
      "func total(v : vector[3](float)) -> norm : float\n  norm = v(0) + v(1);\nend\n"
      "func cell(w : float) -> cell : Cell\n  cell.weight = w;\nend\n");
  const auto* a = p->func(0).body[0]->as<Assign>();
  EXPECT_TRUE(a->targets[0]->is<VarRef>());
  const auto* f = p->func(1).body[0]->as<Assign>()->targets[0]->as<FieldRead>();
  ASSERT_NE(f, nullptr);
  EXPECT_TRUE(f->base->is<VarRef>());
}

TEST(ParserNames, HidingIsScoped) {
  auto p = parse_ok(
      "func f(x : float) -> y : float\n"
      "  if true\n    var sin = [1.0, 2.0];\n    a = sin(0);\n  end\n"
      "  y = sin(x);\n"
      "  for cos in 0:3\n    b = cos(1);\n  end\n"
      "end\n");
  const auto* branch = p->body()[0]->as<If>();
  EXPECT_TRUE(branch->branches[0][1]->as<Assign>()->value->is<TensorRead>());
  EXPECT_TRUE(p->body()[1]->as<Assign>()->value->is<Call>());
  const auto* loop = p->body()[2]->as<ForRange>();
  EXPECT_TRUE(loop->body[0]->as<Assign>()->value->is<TensorRead>());
}

TEST(ParserNames, RecursiveCallParsesAsCall) {
  auto p = parse_ok("func f(x : int) -> y : int\n  y = f(x);\nend\n");
  EXPECT_TRUE(p->body()[0]->as<Assign>()->value->is<Call>());
}

TEST(ParserNames, AssigningToAFunctionNameIsASyntaxError) {
  EXPECT_EQ(first_error("func f()\n  norm = 1.0;\nend"),
            "2:8 expected '(' after the function name 'norm' but got '='");
  // An implicit declaration hides nothing; an explicit one does.
  parse_ok("func f()\n  var norm = 1.0;\n  norm = 2.0;\nend");
}

TEST(ParserNames, TupleReads) {
  auto p = parse_ok(
      "element Node\n  x : float;\nend\n"
      "func f(e : (Node * 2), p : (a : Node, b : Node), n : Node) -> r : float\n"
      "  r = e(0).x + p.a.x + n.x;\n"
      "end\n");
  const auto* sum = p->body()[0]->as<Assign>()->value->as<Binary>();
  ASSERT_NE(sum, nullptr);
  const auto* inner = sum->lhs->as<Binary>();
  ASSERT_NE(inner, nullptr);
  const auto* f0 = inner->lhs->as<FieldRead>();
  ASSERT_NE(f0, nullptr);
  const auto* t0 = f0->base->as<TupleRead>();
  ASSERT_NE(t0, nullptr);
  EXPECT_TRUE(t0->index->is<IntLit>());
  const auto* t1 = inner->rhs->as<FieldRead>()->base->as<TupleRead>();
  ASSERT_NE(t1, nullptr);
  EXPECT_EQ(t1->member, "a");
  EXPECT_EQ(t1->index, nullptr);
  EXPECT_TRUE(sum->rhs->as<FieldRead>()->base->is<VarRef>());
}

TEST(ParserNames, TupleReadRestrictions) {
  const char* decls = "func f(e : (Node * 2))\n";
  EXPECT_EQ(first_error_at(std::string(decls) + "  x = e(0, 1);\nend"), "2:10");
  EXPECT_EQ(first_error_at(std::string(decls) + "  x = e(:);\nend"), "2:9");
}

TEST(ParserNames, GenericCallHeuristic) {
  auto p = parse_expr_text("foo<N, 3>(x)");
  const auto* call = p.expr->as<Call>();
  ASSERT_NE(call, nullptr);
  ASSERT_EQ(call->generic_args.size(), 2u);
  EXPECT_EQ(call->generic_args[0].name, "N");
  EXPECT_TRUE(call->generic_args[1].is_int);
  EXPECT_EQ(call->generic_args[1].value, 3);

  EXPECT_TRUE(parse_expr_text("foo<N>()").expr->is<Call>());
  EXPECT_TRUE(parse_expr_text("a < b").expr->is<Compare>());
  EXPECT_TRUE(parse_expr_text("a < b > (c)").expr->is<Compare>());

  p = parse_expr_text("g<3>(v)", "func g<N>(v : vector[N](float)) -> s : float\n  s = v(0);\nend");
  ASSERT_TRUE(p.expr->is<Call>());
  EXPECT_EQ(p.expr->as<Call>()->generic_args.size(), 1u);
}

TEST(ParserNames, ComplexLiteralOnlyStartsAFactor) {
  auto p = parse_expr_text("a < <1.0, 2.0>");
  const auto* cmp = p.expr->as<Compare>();
  ASSERT_NE(cmp, nullptr);
  EXPECT_TRUE(cmp->operands[1]->is<ComplexLit>());
}

// ---------------------------------------------------------------------------
// Statements and access expressions (§3.3, §3.6.3, §3.6.6-3.6.9)

TEST(ParserStatements, ForDomains) {
  auto p = parse_ok(
      "func f(k : int)\n"
      "  for e in edges\n  end\n"
      "  for i in 0:n\n  end\n"
      "  for j in k:3\n  end\n"
      "  for m in (k):(k + 2)\n  end\n"
      "end\n");
  const Block& b = p->body();
  ASSERT_EQ(b.size(), 4u);
  ASSERT_TRUE(b[0]->is<ForSet>());
  EXPECT_EQ(b[0]->as<ForSet>()->domain, "edges");
  EXPECT_TRUE(b[1]->is<ForRange>());
  EXPECT_TRUE(b[2]->as<ForRange>()->lo->is<VarRef>());
  EXPECT_TRUE(b[3]->as<ForRange>()->hi->is<Binary>());
  EXPECT_EQ(first_error("func f()\n  for i 1:2\n  end\nend"),
            "2:9 expected 'in' but got integer literal 1");
}

TEST(ParserStatements, DoWhileAndIvarNeedNoSemicolon) {
  auto p = parse_ok(
      "func f()\n"
      "  var x = 0;\n"
      "  do\n    x = x + 1;\n  end while x < 3\n"
      "  ivar i\n  ivar j;\n"
      "  do\n  end while false;\n"
      "end\n");
  const Block& b = p->body();
  ASSERT_EQ(b.size(), 5u);
  EXPECT_TRUE(b[1]->is<DoWhile>());
  EXPECT_TRUE(b[1]->as<DoWhile>()->condition->is<Compare>());
  EXPECT_EQ(b[2]->as<IvarDecl>()->name, "i");
  EXPECT_EQ(b[3]->as<IvarDecl>()->name, "j");
  EXPECT_TRUE(b[4]->is<DoWhile>());
}

TEST(ParserStatements, IfElifElse) {
  auto p = parse_ok(
      "func f(d : float) -> s : int\n"
      "  if d < 0.0\n    s = -1;\n  elif (d > 0.0)\n    s = 1;\n  else\n    s = 0;\n  end\n"
      "end\n");
  const auto* s = p->body()[0]->as<If>();
  ASSERT_NE(s, nullptr);
  EXPECT_EQ(s->conditions.size(), 2u);
  EXPECT_TRUE(s->has_else);
  EXPECT_EQ(s->else_branch.size(), 1u);
}

TEST(ParserStatements, AssignmentsAndExpressionStatements) {
  auto p = parse_ok(
      "func f()\n  a, b = g(x);\n  update(v);\n  ;\n  c = map m to S reduce +;\n"
      "  map m to S;\n  print \"a\", 1;\n  println x;\nend\n");
  const Block& b = p->body();
  ASSERT_EQ(b.size(), 6u);
  EXPECT_EQ(b[0]->as<Assign>()->targets.size(), 2u);
  EXPECT_TRUE(b[1]->is<ExprStmt>());
  const auto* map = b[2]->as<Assign>()->value->as<Map>();
  ASSERT_NE(map, nullptr);
  EXPECT_TRUE(map->reduce);
  EXPECT_TRUE(b[3]->as<ExprStmt>()->expr->is<Map>());
  EXPECT_EQ(b[4]->as<Print>()->args.size(), 2u);
  EXPECT_TRUE(b[5]->as<Print>()->newline());
  EXPECT_EQ(first_error_at("func f()\n  a, b = b, a;\nend"), "2:11");
  EXPECT_EQ(first_error_at("func f()\n  print \"a\" \"\\n\";\nend"), "2:13");
}

TEST(ParserStatements, ErrorStatementTakesPrintsArgumentsAndIsAKeyword) {
  auto p =
      parse_ok("func f(x : float)\n  if x < 0.0\n    error \"x = \", x, \" < 0\";\n  end\nend\n");
  const auto* e = p->body()[0]->as<If>()->branches[0][0]->as<Print>();
  ASSERT_NE(e, nullptr);
  EXPECT_TRUE(e->is_error());
  EXPECT_TRUE(e->newline());
  EXPECT_EQ(e->args.size(), 3u);
  EXPECT_EQ(e->span.start().line, 3);
  EXPECT_EQ(e->span.start().column, 5);
  EXPECT_EQ(
      print_source(*p->program).find("    error \"x = \", x, \" < 0\";\n") != std::string::npos,
      true);
  // Like print, at least one argument; and `error` is no longer a name.
  EXPECT_EQ(first_error_at("func f()\n  error;\nend"), "2:8");
  EXPECT_EQ(first_error_at("func f()\n  var error = 1;\nend"), "2:7");
}

TEST(ParserStatements, MapAndApply) {
  auto p = parse_ok(
      "func f()\n"
      "  K = map stencil<cells, 3>(1.0, x) to cells through faces reduce +;\n"
      "  apply relax(0.5) to nodes;\n  apply relax to nodes;\nend\n");
  const auto* map = p->body()[0]->as<Assign>()->value->as<Map>();
  ASSERT_NE(map, nullptr);
  EXPECT_EQ(map->assembly.func, "stencil");
  EXPECT_EQ(map->assembly.generic_args.size(), 2u);
  EXPECT_EQ(map->assembly.args.size(), 2u);
  EXPECT_EQ(map->assembly.target, "cells");
  EXPECT_EQ(map->through, "faces");
  const auto* apply = p->body()[1]->as<Apply>();
  ASSERT_NE(apply, nullptr);
  EXPECT_EQ(apply->assembly.args.size(), 1u);
  EXPECT_EQ(first_error("func f()\n  apply g to S reduce +;\nend"),
            "2:16 expected ';' but got 'reduce'");
  EXPECT_EQ(first_error_at("func f()\n  x = 1 + map g to S;\nend"), "2:11");
}

TEST(ParserStatements, PostfixChains) {
  auto p = parse_expr_text("e.f(i)(j)");
  const auto* outer = p.expr->as<TensorRead>();
  ASSERT_NE(outer, nullptr);
  const auto* inner = outer->base->as<TensorRead>();
  ASSERT_NE(inner, nullptr);
  EXPECT_TRUE(inner->base->is<FieldRead>());

  p = parse_expr_text("g[0;1].w");
  const auto* field = p.expr->as<FieldRead>();
  ASSERT_NE(field, nullptr);
  const auto* set = field->base->as<SetRead>();
  ASSERT_NE(set, nullptr);
  EXPECT_TRUE(set->has_semicolon);
  EXPECT_EQ(set->first.size(), 1u);
  EXPECT_EQ(set->second.size(), 1u);
  EXPECT_EQ(set->second[0]->as<IntLit>()->value, 1);

  p = parse_expr_text("A(:, j)");
  const auto* slice = p.expr->as<TensorRead>();
  ASSERT_NE(slice, nullptr);
  EXPECT_EQ(slice->indices[0], nullptr);
  EXPECT_NE(slice->indices[1], nullptr);

  EXPECT_EQ(first_error("func f()\n  r = X(i).f;\nend"), "2:11 expected ';' but got '.'");
  EXPECT_EQ(first_error_at("func f()\n  r = a.b.c;\nend"), "2:10");
  EXPECT_EQ(first_error_at("func f()\n  r = sin(:);\nend"), "2:11");
  EXPECT_EQ(first_error_at("func f()\n  r = g[:];\nend"), "2:9");
}

TEST(ParserStatements, TestsOnlyAtTopLevel) {
  auto p = parse_ok(
      "%! f(1, [1.0, 2.0]') == -2;\nfunc f(a : int, v : vector[2](float)) -> r : int\n  r = "
      "a;\nend\n");
  const auto* test = p->program->decls[0]->as<TestDecl>();
  ASSERT_NE(test, nullptr);
  EXPECT_EQ(test->func, "f");
  EXPECT_EQ(test->args.size(), 2u);
  EXPECT_EQ(test->expected->as<IntLit>()->value, -2);
  EXPECT_EQ(first_error("func f()\n  %! f() == 1;\nend"),
            "2:3 a test ('%!') is only allowed at the top level, not inside a function");
}

// ---------------------------------------------------------------------------
// Program elements and types (§3.2, §3.5)

TEST(ParserDecls, ProgramElements) {
  auto p = parse_ok(
      "element Particle\n  pos : vector[3](float);\n  mass : float;\nend\n"
      "extern nodes : set{Particle};\n"
      "extern bars : set{Bar}(nodes * 2);\n"
      "extern ties : set{Tie}(parts, nodes);\n"
      "extern faces : grid[2]{Face}(cells);\n"
      "const tol : float = 1e-8;\n"
      "extern func ext<N>(inout x : vector[N](float)) -> (a : int, b : opaque);\n"
      "export func main()\nend\n"
      "func r<M, 0:K>(A : matrix[M, K](float), t : (a : E, b : F)) -> s : "
      "vector[M](float)'\nend\n");
  const auto& decls = p->program->decls;
  ASSERT_EQ(decls.size(), 9u);
  const auto* element = decls[0]->as<ElementDecl>();
  ASSERT_NE(element, nullptr);
  EXPECT_EQ(element->fields.size(), 2u);
  EXPECT_EQ(element->field_index("mass"), 1);
  EXPECT_EQ(element->field_index("nope"), -1);

  const auto* bars = decls[2]->as<ExternDecl>()->type_expr->as<SetTypeExpr>();
  ASSERT_NE(bars, nullptr);
  EXPECT_TRUE(bars->shorthand);
  EXPECT_EQ(bars->shorthand_count, 2);
  ASSERT_EQ(bars->endpoints.size(), 2u);
  EXPECT_EQ(bars->endpoints[1].name, "nodes");
  EXPECT_EQ(decls[3]->as<ExternDecl>()->type_expr->as<SetTypeExpr>()->endpoints.size(), 2u);
  const auto* grid = decls[4]->as<ExternDecl>()->type_expr->as<GridTypeExpr>();
  ASSERT_NE(grid, nullptr);
  EXPECT_EQ(grid->dims, 2);
  EXPECT_EQ(grid->point_set.name, "cells");

  const auto* ext = decls[6]->as<FuncDecl>();
  EXPECT_TRUE(ext->is_extern);
  EXPECT_TRUE(ext->params[0].inout);
  EXPECT_EQ(ext->results.size(), 2u);
  EXPECT_TRUE(ext->results[1].type_expr->is<OpaqueTypeExpr>());
  EXPECT_TRUE(decls[7]->as<FuncDecl>()->exported);
  const auto* r = decls[8]->as<FuncDecl>();
  ASSERT_EQ(r->generics.size(), 2u);
  EXPECT_FALSE(r->generics[0].ranged);
  EXPECT_TRUE(r->generics[1].ranged);
  EXPECT_TRUE(r->params[1].type_expr->as<TupleTypeExpr>()->named);
  EXPECT_TRUE(r->results[0].type_expr->as<TensorTypeExpr>()->transposed);
  EXPECT_EQ(p->program->find_func("main"), decls[7].get());
  EXPECT_EQ(p->program->find_func("nope"), nullptr);
}

TEST(ParserDecls, TensorTypes) {
  auto p = parse_ok(
      "func f(a : tensor[4,4](tensor[2,2](float)), b : vector(float), c : "
      "matrix[V,V](matrix[3,3](float)),"
      " d : (E * 3))\nend\n");
  const auto& params = p->func().params;
  const auto* a = params[0].type_expr->as<TensorTypeExpr>();
  ASSERT_NE(a, nullptr);
  EXPECT_EQ(a->dims.size(), 2u);
  EXPECT_TRUE(a->block->is<TensorTypeExpr>());
  EXPECT_TRUE(params[1].type_expr->as<TensorTypeExpr>()->dims.empty());
  EXPECT_EQ(params[2].type_expr->as<TensorTypeExpr>()->dims[1].name, "V");
  const auto* d = params[3].type_expr->as<TupleTypeExpr>();
  ASSERT_NE(d, nullptr);
  EXPECT_FALSE(d->named);
  EXPECT_EQ(d->count, 3);
}

TEST(ParserDecls, SyntaxErrorsWithLocations) {
  EXPECT_EQ(first_error("var x = 1;"),
            "1:1 expected a program element (element, extern, const, func, export or a test) "
            "but got 'var'");
  EXPECT_EQ(first_error("func f()\n  var x;\nend"), "2:8 expected ':' or '=' but got ';'");
  EXPECT_EQ(first_error("export func main\n  print 1;\nend"), "2:3 expected '(' but got 'print'");
  EXPECT_EQ(first_error_at("func f() -> inout r : float\nend"), "1:13");
  EXPECT_EQ(first_error_at("extern inout x : float;"), "1:8");
  EXPECT_EQ(first_error_at("const c : float;"), "1:16");
  EXPECT_EQ(first_error_at("func f<1:N>()\nend"), "1:8");
  EXPECT_EQ(first_error_at("element E\n  p : (E * 2);\nend"), "2:7");
  EXPECT_EQ(first_error_at("func f()\n  var x : Particle;\nend"), "2:11");
  EXPECT_EQ(first_error_at("func f()\n  var x : matrix[2,2](float)' = 0.0;\nend"), "2:29");
  EXPECT_EQ(first_error_at("func f(x : vector[2,2](float))\nend"), "1:20");
  EXPECT_EQ(first_error_at("func f(x : matrix[2](float))\nend"), "1:20");
  EXPECT_EQ(first_error_at("func f(x : vector(tensor(float)))\nend"), "1:19");
  EXPECT_EQ(first_error_at("func f(x : tensor(tensor))\nend"), "1:25");
  EXPECT_EQ(first_error_at("func f(x : set{1})\nend"), "1:16");
  EXPECT_EQ(first_error_at("func f(x : set{E}(int))\nend"), "1:19");
  EXPECT_EQ(first_error_at("func f(x : (E * E))\nend"), "1:17");
  EXPECT_EQ(first_error_at("func f(x : 3)\nend"), "1:12");
  EXPECT_EQ(first_error_at("func f()\n  while\n  end\nend"), "3:3");
  EXPECT_EQ(first_error_at("func f()\n  x = 1 + * 2;\nend"), "2:11");
  EXPECT_EQ(first_error_at("func f()\n  x = 1 and or 2;\nend"), "2:13");
  EXPECT_EQ(first_error_at("func f()\n  = 1;\nend"), "2:3");
  EXPECT_EQ(first_error_at("func f()\n  return 1;\nend"), "2:3");
  EXPECT_EQ(first_error_at("func f()\n  x = .5;\nend"), "2:7");
}

TEST(ParserDecls, MissingSemicolonIsReportedAtTheNextToken) {
  EXPECT_EQ(first_error("func f()\n  x = 1\n  y = 2;\nend"),
            "3:3 expected ';' but got identifier 'y'");
  EXPECT_EQ(first_error("extern x : float\nfunc f()\nend"), "2:1 expected ';' but got 'func'");
}

}  // namespace
}  // namespace simit::frontend
