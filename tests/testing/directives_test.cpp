// Parsing and validation of `%@` directives (TESTFORMAT.md §7).
#include "testing/directives.h"

#include <gtest/gtest.h>

namespace simit::tools {
namespace {

SectionDirectives parse_ok(const std::string& source) {
  SectionDirectives d = parse_directives(source);
  for (const auto& e : d.errors) ADD_FAILURE() << "line " << e.line << ": " << e.message;
  return d;
}

std::string only_error(const std::string& source) {
  SectionDirectives d = parse_directives(source);
  EXPECT_EQ(d.errors.size(), 1u) << source;
  return d.errors.empty() ? "" : d.errors[0].message;
}

template <class T>
const T& step(const SectionDirectives& d, size_t i) {
  EXPECT_LT(i, d.graph.size());
  return std::get<T>(d.graph.at(i).action);
}

TEST(Directives, NoneInPlainSection) {
  SectionDirectives d = parse_ok("%%% name\nfunc f()\nend\n% @ not a directive\nx = 1; %@ run f\n");
  EXPECT_FALSE(d.error);
  EXPECT_FALSE(d.has_graph());
}

TEST(Directives, ErrorExpectations) {
  SectionDirectives d = parse_ok(
      "%%% bad\n%@ error semantic\n  %@ error-line 4\n%@ error-contains \"two row vectors\"\n"
      "%@ error-contains \"a, b\"\n");
  ASSERT_TRUE(d.error);
  EXPECT_EQ(d.error->category, "semantic");
  EXPECT_EQ(d.error->line, 4);
  EXPECT_EQ(d.error->contains, (std::vector<std::string>{"two row vectors", "a, b"}));
  EXPECT_FALSE(d.error->runtime());
}

TEST(Directives, EveryErrorCategory) {
  for (const char* c :
       {"lexical", "syntax", "semantic", "undeclared", "redefinition", "type", "dimension",
        "not-writable", "literal-required", "generic-unresolved", "arity", "runtime"}) {
    SectionDirectives d = parse_ok(std::string("%@ error ") + c + "\n");
    ASSERT_TRUE(d.error);
    EXPECT_EQ(d.error->category, c);
  }
}

TEST(Directives, RuntimeErrorWithLine) {
  SectionDirectives d = parse_ok("%@ error runtime\n%@ error-line 3\n");
  ASSERT_TRUE(d.error);
  EXPECT_TRUE(d.error->runtime());
  EXPECT_EQ(d.error->line, 3);
}

TEST(Directives, ErrorLineAloneMakesMustFail) {
  SectionDirectives d = parse_ok("%@ error-line 2\n");
  ASSERT_TRUE(d.error);
  EXPECT_EQ(d.error->category, "");
}

TEST(Directives, BadErrorDirectives) {
  EXPECT_NE(only_error("%@ error semantik\n").find("unknown error category"), std::string::npos);
  EXPECT_NE(only_error("%@ error type\n%@ error syntax\n").find("second"), std::string::npos);
  EXPECT_NE(only_error("%@ error-line 0\n").find("line number"), std::string::npos);
  EXPECT_NE(only_error("%@ error-line x\n").find("line number"), std::string::npos);
  EXPECT_NE(only_error("%@ error-contains two\n").find("error-contains"), std::string::npos);
}

TEST(Directives, UnknownDirectiveNamesItsLine) {
  SectionDirectives d = parse_directives("%%% s\nx\n%@ expext nodes.u = 1.0\n");
  ASSERT_EQ(d.errors.size(), 1u);
  EXPECT_EQ(d.errors[0].line, 3);
  EXPECT_NE(d.errors[0].message.find("unknown directive '%@ expext'"), std::string::npos);
  EXPECT_NE(only_error("%@\n").find("keyword"), std::string::npos);
}

TEST(Directives, LinesCountCrLf) {
  SectionDirectives d = parse_directives("%%% s\r\n\r\n%@ bogus\r\n");
  ASSERT_EQ(d.errors.size(), 1u);
  EXPECT_EQ(d.errors[0].line, 3);
}

TEST(Directives, VertexAndEdgeSets) {
  SectionDirectives d = parse_ok(
      "%@ set nodes = 4\n%@ set links(nodes, nodes) = (0,1), (1,2), (2,3)\n"
      "%@ set empty(nodes, nodes) =\n%@ set none = 0\n");
  ASSERT_EQ(d.graph.size(), 4u);
  const auto& nodes = step<SetDirective>(d, 0);
  EXPECT_EQ(nodes.name, "nodes");
  EXPECT_EQ(nodes.size, 4);
  EXPECT_FALSE(nodes.is_edge_set());
  const auto& links = step<SetDirective>(d, 1);
  EXPECT_TRUE(links.is_edge_set());
  EXPECT_EQ(links.endpoint_sets, (std::vector<std::string>{"nodes", "nodes"}));
  EXPECT_EQ(links.edges, (std::vector<std::vector<int>>{{0, 1}, {1, 2}, {2, 3}}));
  EXPECT_EQ(d.graph[1].line, 2);
  EXPECT_TRUE(step<SetDirective>(d, 2).edges.empty());
  EXPECT_EQ(step<SetDirective>(d, 3).size, 0);
}

TEST(Directives, BadSets) {
  EXPECT_NE(only_error("%@ set nodes = -1\n").find("element count"), std::string::npos);
  EXPECT_NE(only_error("%@ set nodes 4\n").find("expected '='"), std::string::npos);
  EXPECT_NE(only_error("%@ set e(a, b) = (0,1), (1)\n").find("1 endpoints"), std::string::npos);
  EXPECT_NE(only_error("%@ set e(a, b) = 0,1\n").find("tuple"), std::string::npos);
  EXPECT_NE(only_error("%@ set e() = \n").find("set names"), std::string::npos);
  EXPECT_NE(only_error("%@ set 2x = 1\n").find("set name"), std::string::npos);
}

TEST(Directives, Grid) {
  SectionDirectives d = parse_ok("%@ set P = 0\n%@ grid G(P) = 3, 4\n");
  const auto& g = step<GridDirective>(d, 1);
  EXPECT_EQ(g.name, "G");
  EXPECT_EQ(g.point_set, "P");
  EXPECT_EQ(g.extents, (std::vector<int>{3, 4}));
  EXPECT_NE(only_error("%@ grid G(P, Q) = 3\n").find("one point set"), std::string::npos);
  EXPECT_NE(only_error("%@ grid G(P) = 0\n").find("extent"), std::string::npos);
  EXPECT_NE(only_error("%@ grid G(P) =\n").find("at least one"), std::string::npos);
}

TEST(Directives, FieldValuesWithCommasInsideBrackets) {
  SectionDirectives d = parse_ok(
      "%@ field nodes.x = [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]\n"
      "%@ field nodes.m = [1.0, 2.0; 3.0, 4.0], [1.0, 0.0; 0.0, 1.0]\n"
      "%@ field nodes.b = true, false\n%@ field nodes.c = <1.0, 2.0>, <0.0, -1.0>\n");
  const auto& x = step<FieldDirective>(d, 0);
  EXPECT_EQ(x.set, "nodes");
  EXPECT_EQ(x.field, "x");
  ASSERT_EQ(x.values.size(), 2u);
  EXPECT_EQ(x.values[1].floats, (std::vector<double>{0.0, 1.0, 0.0}));
  EXPECT_EQ(step<FieldDirective>(d, 1).values[0].shape, (std::vector<int>{2, 2}));
  EXPECT_EQ(step<FieldDirective>(d, 2).values.size(), 2u);
  EXPECT_EQ(step<FieldDirective>(d, 3).values.size(), 2u);
  EXPECT_NE(only_error("%@ field nodes.x = 1.0, , 2.0\n").find("empty value"), std::string::npos);
  EXPECT_NE(only_error("%@ field nodes = 1.0\n").find("S.f"), std::string::npos);
  EXPECT_NE(only_error("%@ field nodes.x = 1.0 + 2.0\n").find("bad literal"), std::string::npos);
}

TEST(Directives, TensorAndArg) {
  SectionDirectives d = parse_ok("%@ tensor g = [0.0, -9.8, 0.0]'\n%@ arg dt = 0.01\n");
  const auto& t = step<ValueDirective>(d, 0);
  EXPECT_EQ(t.target, ValueDirective::Target::ExternTensor);
  EXPECT_EQ(t.name, "g");
  EXPECT_TRUE(t.value.column);
  const auto& a = step<ValueDirective>(d, 1);
  EXPECT_EQ(a.target, ValueDirective::Target::Argument);
  EXPECT_EQ(a.value.floats, std::vector<double>{0.01});
  EXPECT_NE(only_error("%@ arg dt = 1.0, 2.0\n").find("bad literal"), std::string::npos);
}

TEST(Directives, Runs) {
  SectionDirectives d = parse_ok("%@ run init\n%@ run step 10\n");
  EXPECT_TRUE(d.has_runs());
  EXPECT_EQ(step<RunDirective>(d, 0).times, 1);
  EXPECT_EQ(step<RunDirective>(d, 1).func, "step");
  EXPECT_EQ(step<RunDirective>(d, 1).times, 10);
  EXPECT_NE(only_error("%@ run step 0\n").find("run count"), std::string::npos);
  EXPECT_NE(only_error("%@ run\n").find("function name"), std::string::npos);
}

TEST(Directives, Expectations) {
  SectionDirectives d = parse_ok(
      "%@ expect nodes.r = -2.0, 1.0, -2.0, 3.0\n%@ expect nodes.r[2] = -2.0\n"
      "%@ expect total = 6\n%@ expect-near nodes.x = [1.0, 2.0], [3.0, 4.0] tol=1e-12\n"
      "%@ expect-near nodes.u[0] = 1.0, tol=0.5\n%@ expect-output \"3\\n\"\n");
  const auto& all = step<ExpectDirective>(d, 0);
  EXPECT_TRUE(all.is_field());
  EXPECT_EQ(all.values.size(), 4u);
  EXPECT_FALSE(all.element);
  EXPECT_FALSE(all.tolerance);
  const auto& one = step<ExpectDirective>(d, 1);
  EXPECT_EQ(one.element, 2);
  EXPECT_EQ(one.field, "r");
  const auto& named = step<ExpectDirective>(d, 2);
  EXPECT_FALSE(named.is_field());
  EXPECT_EQ(named.name, "total");
  const auto& near = step<ExpectDirective>(d, 3);
  EXPECT_EQ(near.tolerance, 1e-12);
  EXPECT_EQ(near.values.size(), 2u);
  EXPECT_EQ(step<ExpectDirective>(d, 4).tolerance, 0.5);
  EXPECT_EQ(step<ExpectOutputDirective>(d, 5).text, "3\n");
}

TEST(Directives, BadExpectations) {
  EXPECT_NE(only_error("%@ expect-near nodes.x = 1.0\n").find("tol="), std::string::npos);
  EXPECT_NE(only_error("%@ expect nodes.x = 1.0 tol=1e-3\n").find("expect-near"),
            std::string::npos);
  EXPECT_NE(only_error("%@ expect-near nodes.x = 1.0 tol=abc\n").find("tolerance"),
            std::string::npos);
  EXPECT_NE(only_error("%@ expect nodes.x[1] = 1.0, 2.0\n").find("exactly one"), std::string::npos);
  EXPECT_NE(only_error("%@ expect nodes.x[a] = 1.0\n").find("element index"), std::string::npos);
  EXPECT_NE(only_error("%@ expect-output hello\n").find("quoted string"), std::string::npos);
}

TEST(Directives, GraphStepsKeepOrderAndLines) {
  SectionDirectives d = parse_ok(
      "%%% laplacian\n%@ set nodes = 2\n%@ field nodes.u = 1.0, 2.0\n%@ run apply_l\n"
      "%@ expect nodes.r = 0.0, 0.0\n");
  ASSERT_EQ(d.graph.size(), 4u);
  EXPECT_EQ(d.graph[0].line, 2);
  EXPECT_EQ(d.graph[3].line, 5);
  EXPECT_TRUE(std::holds_alternative<RunDirective>(d.graph[2].action));
}

}  // namespace
}  // namespace simit::tools
