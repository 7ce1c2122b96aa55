// The type checker (LANGUAGE.md §4-10): accepted programs, the category and line of the
// first diagnostic of rejected ones, and the annotations the interpreter relies on.
#include "frontend/checker.h"

#include <gtest/gtest.h>

#include "frontend/frontend.h"

namespace simit::frontend {
namespace {

// A graph most snippets use; snippet lines are counted after it.
const char* const kGraph = R"(element Node
  x : float;
  v : vector[3](float);
  m : matrix[3,3](float);
  flag : bool;
end
element Edge
  k : float;
end
extern nodes : set{Node};
extern others : set{Node};
extern edges : set{Edge}(nodes, nodes);
extern hetero : set{Edge}(nodes, others);
extern count : int;
)";
const int kGraphLines = 14;

struct Case {
  const char* name;
  const char* source;  // appended to kGraph
  const char* expect;  // "ok", or "<category>@<line within source>"
};

std::unique_ptr<Compilation> compile(const std::string& source) {
  return compile_source("test.sim", std::string(kGraph) + source);
}

// "ok", or the first diagnostic as "<category>@<line>" (lines counted within `source`).
std::string outcome(const std::string& source) {
  auto c = compile(source);
  if (c->ok()) return "ok";
  const Diagnostic& d = c->diagnostics.items().front();
  int line = d.span.valid() ? d.span.start().line - kGraphLines : 0;
  return std::string(category_name(d)) + "@" + std::to_string(line);
}

void expect_cases(const std::vector<Case>& cases) {
  for (const auto& c : cases) {
    std::string got = outcome(c.source);
    EXPECT_EQ(got, c.expect) << c.name << "\n"
                             << c.source << "\n"
                             << compile(c.source)->diagnostics.render_all();
  }
}

const ast::FuncDecl* func(const Compilation& c, const std::string& name) {
  for (const auto& d : c.program->decls)
    if (auto* f = d->as<ast::FuncDecl>(); f && f->name == name) return f;
  return nullptr;
}

template <class T>
const T* stmt(const ast::FuncDecl& f, size_t i) {
  return i < f.body.size() ? f.body[i]->as<T>() : nullptr;
}

// ---------------------------------------------------------------------------
// Declarations (§4, §5, §11.3)

TEST(CheckerTest, Declarations) {
  expect_cases({
      {"element redefinition", "element Node\nend\n", "redefinition@1"},
      {"field redefinition", "element P\n  a : float;\n  a : int;\nend\n", "redefinition@3"},
      {"string field", "element P\n  s : string;\nend\n", "type@2"},
      {"extern redefinition", "extern nodes : set{Edge};\n", "redefinition@1"},
      {"function redefinition", "func f()\nend\nfunc f(a : int)\nend\n", "redefinition@3"},
      {"intrinsic redefinition", "func sin(a : float) -> b : float\n  b = a;\nend\n",
       "redefinition@1"},
      {"parameter redefinition", "func f(a : int, a : float)\nend\n", "redefinition@1"},
      {"result vs parameter", "func f(a : int) -> a : int\nend\n", "redefinition@1"},
      {"generic redefinition", "func f<N, N>(a : vector[N](float))\nend\n", "redefinition@1"},
      {"parameter vs generic", "func f<N>(N : int)\nend\n", "redefinition@1"},
      {"local redefinition", "func f()\n  var a = 1;\n  var a = 2;\nend\n", "redefinition@3"},
      {"local shadows parameter", "func f(a : int)\n  var a = 2.0;\nend\n", "ok"},
      {"undeclared element in set", "extern s : set{Nope};\n", "undeclared@1"},
      {"undeclared set dimension", "extern v : vector[nope](float);\n", "undeclared@1"},
      {"element as dimension", "extern v : vector[Node](float);\n", "undeclared@1"},
      {"int as dimension", "extern v : vector[count](float);\n", "type@1"},
      {"int as endpoint", "extern s : set{Edge}(count);\n", "type@1"},
      {"zero arity", "extern s : set{Edge}(nodes * 0);\n", "type@1"},
      {"grid over edge set", "extern g : grid[1]{Edge}(edges);\n", "type@1"},
      {"mixed dimensions", "extern v : tensor[nodes, 3](float);\n", "dimension@1"},
      {"block order", "extern v : tensor[nodes](tensor[3,3](float));\n", "dimension@1"},
      {"transposed matrix type", "extern v : tensor[3,3](float)';\n", "type@1"},
      {"undeclared tuple element", "func f(t : (Nope * 2))\nend\n", "undeclared@1"},
      {"empty tuple", "func f(t : (Node * 0))\nend\n", "type@1"},
      {"tuple element redefinition", "func f(t : (a : Node, a : Node))\nend\n", "redefinition@1"},
      {"element extern", "extern e : Node;\n", "type@1"},
      {"const not literal", "const c : int = 1 + 2;\n", "literal-required@1"},
      {"const folded literal", "const c = -[1.0, 2.0]';\n", "ok"},
      {"const transposed matrix", "const c = [1.0, 2.0; 3.0, 4.0]';\n", "literal-required@1"},
      {"const scalar for vector", "const c : vector[3](float) = 1.0;\n", "type@1"},
      {"const leading one", "const m : tensor[1,3](float) = [1.0, 2.0, 3.0];\n", "ok"},
      {"const orientation", "const c : vector[2](complex) = [<1.0,0.0>, <0.0,1.0>];\n", "ok"},
      {"var initializer mismatch", "func f()\n  var t : int = 1.0;\nend\n", "type@2"},
      {"var broadcast", "func f()\n  var t : matrix[3,3](float) = 0.0;\nend\n", "ok"},
      {"var orientation", "func f()\n  var t : vector[2](float) = [1.0, 2.0];\nend\n", "type@2"},
      {"local const lenient", "func f()\n  const t : vector[2](float) = [1.0, 2.0];\nend\n", "ok"},
      {"var of element", "func f(n : Node)\n  var e = n;\nend\n", "type@2"},
      {"exported generic", "export func f<N>(v : vector[N](float))\nend\n", "semantic@1"},
      {"element result accepted", "func f(w : float) -> c : Node\n  c.x = w;\nend\n", "ok"},
      {"ragged literal", "func f()\n  a = [1.0, 2.0; 3.0];\nend\n", "dimension@2"},
  });
}

// ---------------------------------------------------------------------------
// Statements and calls (§7, §4.5.3, §11.4)

TEST(CheckerTest, StatementsAndCalls) {
  expect_cases({
      {"undeclared function", "func f()\n  a = g(1);\nend\n", "undeclared@2"},
      {"recursion", "func f(a : int) -> b : int\n  b = f(a);\nend\n", "undeclared@2"},
      {"argument count",
       "func g(a : int) -> b : int\n  b = a;\nend\nfunc f()\n  c = g(1, 2);\nend\n", "arity@5"},
      {"argument type", "func g(a : int) -> b : int\n  b = a;\nend\nfunc f()\n  c = g(1.0);\nend\n",
       "type@5"},
      {"argument orientation",
       "func g(a : vector[2](float))\nend\nfunc f()\n  g([1.0, 2.0]);\nend\n", "type@4"},
      {"void argument", "func g()\nend\nfunc h(a : int)\nend\nfunc f()\n  h(g());\nend\n",
       "type@6"},
      {"inout const", "const c = 1;\nfunc g(inout a : int)\nend\nfunc f()\n  g(c);\nend\n",
       "not-writable@5"},
      {"inout extern component",
       "extern dtc : vector[2](float);\nfunc g(inout a : float)\nend\nfunc f()\n  "
       "g(dtc(0));\nend\n",
       "ok"},
      {"unresolved generic", "func g<N>(v : vector[N](float))\nend\nfunc f()\n  g(1.0);\nend\n",
       "generic-unresolved@4"},
      {"generic mismatch",
       "func g<N>(a : matrix[N,N](float))\nend\nfunc f()\n  g([1.0; 2.0]);\nend\n", "type@4"},
      {"explicit generic undeclared",
       "func g<N>(a : vector[N](float))\nend\nfunc f()\n  g<nope>(nodes.x);\nend\n",
       "undeclared@4"},
      {"too many generics",
       "func g<N>(a : vector[N](float))\nend\nfunc f()\n  g<nodes, 3>(nodes.x);\nend\n", "arity@4"},
      {"assign to const", "const c = 1;\nfunc f()\n  c = 2;\nend\n", "not-writable@3"},
      {"assign to parameter", "func f(a : int)\n  a = 2;\nend\n", "not-writable@2"},
      {"reassign implicit", "func f()\n  a = 1;\n  a = 2;\nend\n", "not-writable@3"},
      {"implicit scoped", "func f()\n  if true\n    a = 1;\n  end\n  a = 2.0;\nend\n", "ok"},
      {"assign element", "func f(n : Node)\n  var x = 1.0;\n  x = n;\nend\n", "type@3"},
      {"two results one target", "func g() -> (a : int, b : int)\nend\nfunc f()\n  x = g();\nend\n",
       "arity@4"},
      {"multi assign", "func g() -> (a : int, b : float)\nend\nfunc f()\n  x, y = g();\nend\n",
       "ok"},
      {"element result used", "func g(w : float) -> c : Node\nend\nfunc f()\n  g(1.0);\nend\n",
       "type@4"},
      {"apply non-void", "func g(n : Node) -> a : int\nend\nfunc f()\n  apply g to nodes;\nend\n",
       "semantic@4"},
      {"while condition", "func f()\n  while 1\n  end\nend\n", "type@2"},
      {"elif condition", "func f()\n  if true\n  elif 1.0\n  end\nend\n", "type@3"},
      {"for over int", "func f()\n  for i in count\n  end\nend\n", "type@2"},
      {"range bound", "func f()\n  for i in 0:2.0\n  end\nend\n", "type@2"},
      {"loop variable read-only", "func f()\n  for i in 0:3\n    i = 2;\n  end\nend\n",
       "not-writable@3"},
      {"set loop variable field", "func f()\n  for p in nodes\n    p.x = 1.0;\n  end\nend\n",
       "not-writable@3"},
      {"set field through set", "func f()\n  for p in nodes\n    nodes.x(p) = 1.0;\n  end\nend\n",
       "ok"},
      {"print set", "func f()\n  print nodes;\nend\n", "type@2"},
      {"slice assignment",
       "func f()\n  var A : matrix[2,2](float);\n  A(:, 0) = [1.0, 2.0]';\nend\n",
       "not-writable@3"},
      {"slice types",
       "func f(A : matrix[2,3](float)) -> (r : vector[3](float)', c : vector[2](float))\n"
       "  r = A(0, :);\n  c = A(:, 1);\nend\n",
       "ok"},
      {"const component", "const c = [1, 2];\nfunc f()\n  c(0) = 3;\nend\n", "not-writable@3"},
      {"literal target", "func f()\n  1 = 1;\nend\n", "not-writable@2"},
      {"do scope", "func f()\n  do\n    a = true;\n  end while a\nend\n", "undeclared@4"},
      {"opaque implicit",
       "func f(A : matrix[nodes,nodes](float))\n  s = lu(A);\n  lufree(s);\nend\n", "ok"},
      {"inout element write", "func f(inout n : Node)\n  n.x = 1.0;\nend\n", "ok"},
      {"param element write", "func f(n : Node)\n  n.x = 1.0;\nend\n", "not-writable@2"},
  });
}

// ---------------------------------------------------------------------------
// Expressions and reads (§6, §11.5, §11.6)

TEST(CheckerTest, ExpressionsAndReads) {
  expect_cases({
      {"undeclared variable", "func f()\n  a = b;\nend\n", "undeclared@2"},
      {"undefined field", "func f(n : Node)\n  a = n.nope;\nend\n", "undeclared@2"},
      {"matrix set field", "func f()\n  a = nodes.m;\nend\n", "type@2"},
      {"field of scalar", "func f(a : float)\n  b = a.x;\nend\n", "type@2"},
      {"field of void call", "func g()\nend\nfunc f()\n  b = g().x;\nend\n", "type@4"},
      {"tensor read of set", "func f()\n  a = nodes(1);\nend\n", "type@2"},
      {"index count", "func f(A : matrix[2,2](float))\n  a = A(1);\nend\n", "arity@2"},
      {"float index", "func f(v : vector[2](float))\n  a = v(1.0);\nend\n", "type@2"},
      {"int for set dimension", "func f(v : vector[nodes](float))\n  a = v(0);\nend\n", "type@2"},
      {"wrong element type", "func f(e : Edge, v : vector[nodes](float))\n  a = v(e);\nend\n",
       "type@2"},
      {"element of another set",
       "func f(v : vector[nodes](float))\n  for p in others\n    a = v(p);\n  end\nend\n",
       "dimension@3"},
      {"inferred source conflict",
       "func f(n : Node, v : vector[nodes](float), w : vector[others](float))\n"
       "  a = v(n);\n  b = w(n);\nend\n",
       "dimension@3"},
      {"source inferred before use",
       "func g(n : Node, v : vector[nodes](float)) -> a : float\n  a = v(n);\nend\n"
       "func f(n : Node, w : vector[others](float)) -> a : float\n"
       "  a = g(n, nodes.x);\n  b = w(n);\nend\n",
       "type@5"},
      {"tuple float index", "func f(t : (Node * 2))\n  a = t(1.0).x;\nend\n", "type@2"},
      {"tuple named element", "func f(t : (a : Node, b : Node))\n  y = t.b.x;\nend\n", "ok"},
      {"tuple undefined element", "func f(t : (a : Node, b : Node))\n  y = t.c.x;\nend\n",
       "undeclared@2"},
      {"set read of non-set", "func f(a : float)\n  b = a[0];\nend\n", "type@2"},
      {"grid read of edge set", "func f()\n  b = edges[0;1].k;\nend\n", "type@2"},
      {"int float mix", "func f()\n  a = 1.0 * 2;\nend\n", "type@2"},
      {"row times row", "func f()\n  r = [1.0, 2.0];\n  q = r * r;\nend\n", "type@3"},
      {"matrix vector dims",
       "func f(A : matrix[2,3](float), v : vector[2](float))\n  a = A * v;\nend\n", "dimension@2"},
      {"generic sets differ",
       "func f<N, M>(A : matrix[N,N](float), B : matrix[M,M](float))\n  C = A + B;\nend\n",
       "dimension@2"},
      {"compare vectors", "func f(a : vector[2](float))\n  b = a < a;\nend\n", "type@2"},
      {"and on ints", "func f()\n  b = 1 and 2;\nend\n", "type@2"},
      {"not int", "func f()\n  b = not 1;\nend\n", "type@2"},
      {"negate bool", "func f()\n  b = -true;\nend\n", "type@2"},
      {"generic loop var as number",
       "func f<N>(v : vector[N](float))\n  for m in N\n    a = m + 1;\n  end\nend\n", "type@3"},
      {"generic loop var index",
       "func f<N>(v : vector[N](float)) -> s : float\n  for m in N\n    s = s + v(m);\n  "
       "end\nend\n",
       "ok"},
      {"int into plain generic", "func f<N>(v : vector[N](float)) -> s : float\n  s = v(0);\nend\n",
       "type@2"},
      {"ranged generic",
       "func f<0:N>(v : vector[N](int)) -> w : vector[N](int)\n"
       "  for i in 0:N\n    w(N - 1 - i) = v(i);\n  end\nend\n",
       "ok"},
      {"plain generic value", "func f<N>(v : vector[N](float))\n  a = N;\nend\n", "type@2"},
  });
}

// ---------------------------------------------------------------------------
// Index notation (§7.2, §11.7)

TEST(CheckerTest, IndexNotation) {
  const char* pre =
      "func f(A : matrix[3,3](float), B : matrix[3,3](float), u : vector[3](float))\n"
      "  ivar i;\n  ivar j;\n  var C : matrix[3,3](float);\n";
  auto with = [&](const char* body) { return std::string(pre) + body + "end\n"; };
  std::vector<std::pair<std::string, std::string>> cases = {
      {"  C(i, j) = A(i, j) + B(j, i);\n", "ok"},
      {"  s = u(i) * u(i);\n", "ok"},
      {"  i = 1;\n", "not-writable@5"},
      {"  x = i;\n", "semantic@5"},
      {"  x = i + i;\n", "semantic@5"},
      {"  if A(i, 0) > 0.0\n  end\n", "semantic@5"},
      {"  C(i, j) = A(C(i, j), 0);\n", "semantic@5"},
      {"  C(i, :) = A(i, :);\n", "semantic@5"},
      {"  ivar i;\n", "redefinition@5"},
      {"  C(i, j) = A(i, j) / 2.0;\n", "semantic@5"},
      {"  C(i, j) = sqrt(A(i, j));\n", "semantic@5"},
      {"  C(i, j) = A(i, j) * u(j);\n", "ok"},
  };
  for (const auto& [body, expect] : cases) EXPECT_EQ(outcome(with(body.c_str())), expect) << body;
}

TEST(CheckerTest, IndexNotationAnnotations) {
  auto c = compile(
      "func f(A : matrix[3,3](float), x : vector[3](float)) -> y : vector[3](float)\n"
      "  ivar i;\n  ivar j;\n  y(i) = A(i, j) * x(j);\nend\n");
  ASSERT_TRUE(c->ok()) << c->diagnostics.render_all();
  const auto* a = stmt<ast::Assign>(*func(*c, "f"), 2);
  ASSERT_NE(a, nullptr);
  EXPECT_TRUE(a->index_notation);
  ASSERT_EQ(a->free_vars.size(), 1u);
  EXPECT_EQ(a->free_vars[0]->name, "i");
  ASSERT_EQ(a->reduction_vars.size(), 1u);
  EXPECT_EQ(a->reduction_vars[0]->name, "j");
  EXPECT_TRUE(a->targets[0]->as<ast::TensorRead>()->index_notation);
}

// ---------------------------------------------------------------------------
// Assembly (§8.5-8.7)

TEST(CheckerTest, Maps) {
  expect_cases({
      {"undeclared function", "func f()\n  a = map g to nodes;\nend\n", "undeclared@2"},
      {"target not a set",
       "func g(n : Node) -> r : vector[nodes](float)\nend\nfunc f()\n  a = map g to count;\nend\n",
       "type@4"},
      {"generic target",
       "func g(n : Node) -> r : vector[nodes](float)\nend\nfunc f<N>(v : vector[N](float))\n"
       "  a = map g to N;\nend\n",
       "type@4"},
      {"element partial argument",
       "func g(a : Node, n : Node) -> r : vector[nodes](float)\nend\nfunc f(p : Node)\n"
       "  a = map g(p) to nodes;\nend\n",
       "type@4"},
      {"argument count",
       "func g(a : float, n : Node) -> r : vector[nodes](float)\nend\nfunc f()\n"
       "  a = map g to nodes;\nend\n",
       "arity@4"},
      {"partial argument type",
       "func g(a : float, n : Node) -> r : vector[nodes](float)\nend\nfunc f()\n"
       "  a = map g(1) to nodes;\nend\n",
       "type@4"},
      {"tuple length",
       "func g(e : Edge, t : (Node * 3)) -> r : vector[nodes](float)\nend\nfunc f()\n"
       "  a = map g to edges;\nend\n",
       "type@4"},
      {"source mismatch",
       "func g(n : Node) -> r : vector[nodes](float)\n  r(n) = n.x;\nend\nfunc f()\n"
       "  a = map g to others;\nend\n",
       "type@5"},
      {"result without set dimensions",
       "func g(n : Node) -> r : float\nend\nfunc f()\n  a = map g to nodes;\nend\n", "type@4"},
      {"whole result assignment",
       "func g(n : Node) -> r : vector[nodes](float)\n  r = nodes.x;\nend\nfunc f()\n"
       "  a = map g to nodes;\nend\n",
       "semantic@2"},
      {"whole result never mapped",
       "func g(n : Node) -> r : vector[nodes](float)\n  r = nodes.x;\nend\n", "ok"},
      {"result read",
       "func g(n : Node) -> r : vector[nodes](float)\n  r(n) = r(n) + 1.0;\nend\n"
       "func f()\n  a = map g to nodes;\nend\n",
       "semantic@2"},
      {"heterogeneous named",
       "func g(e : Edge, t : (a : Node, b : Node)) -> r : vector[others](float)\n"
       "  r(t.b) = e.k;\nend\nfunc f()\n  a = map g to hetero reduce +;\nend\n",
       "ok"},
      {"generic source binding",
       "func g<V>(e : Edge, t : (Node * 2)) -> K : matrix[V,V](float)\n"
       "  K(t(0), t(1)) = e.k;\nend\nfunc f()\n  K = map g to edges reduce +;\n"
       "  y = K * nodes.x;\nend\n",
       "ok"},
      {"through non-grid",
       "func g(n : Node, h : set{Edge}(nodes, nodes)) -> r : vector[nodes](float)\nend\n"
       "func f()\n  a = map g to nodes through edges;\nend\n",
       "type@4"},
      {"apply inout",
       "func g(inout n : Node)\n  n.x = 0.0;\nend\nfunc f()\n  apply g to nodes;\nend\n", "ok"},
  });
}

TEST(CheckerTest, Grids) {
  const char* grid = "extern cells : set{Node};\nextern faces : grid[1]{Edge}(cells);\n";
  auto with = [&](const char* body) { return std::string(grid) + body; };
  EXPECT_EQ(
      outcome(with("func s(c : Node, g : grid[1]{Edge}(cells)) -> L : matrix[cells,cells](float)\n"
                   "  L(c, c) = g[0;1].k + g[0;-1].k;\n  L(c, cells[1]) = -g[0;1].k;\nend\n"
                   "func f()\n  L = map s to cells through faces reduce +;\nend\n")),
      "ok");
  EXPECT_EQ(
      outcome(with("func s(c : Node, g : grid[1]{Edge}(cells)) -> L : matrix[cells,cells](float)\n"
                   "  L(c, c) = g[0, 1; 2].k;\nend\n")),
      "arity@4");
  EXPECT_EQ(
      outcome(with("func s(c : Node, g : grid[1]{Edge}(cells)) -> L : matrix[cells,cells](float)\n"
                   "  L(c, c) = g[0].k;\nend\n")),
      "arity@4");
  EXPECT_EQ(
      outcome(with("func s(c : Node, g : grid[1]{Edge}(cells)) -> L : matrix[cells,cells](float)\n"
                   "  L(c, c) = g[0;1.0].k;\nend\n")),
      "type@4");
}

// ---------------------------------------------------------------------------
// `%!` tests (TESTFORMAT.md §3.1)

TEST(CheckerTest, InlineTests) {
  expect_cases({
      {"later function", "%! g(2) == 4;\nfunc g(a : int) -> b : int\n  b = a * 2;\nend\n", "ok"},
      {"unknown function", "%! nope(2) == 4;\n", "ok"},
      {"argument expression", "%! g(1 + 1) == 4;\nfunc g(a : int) -> b : int\nend\n",
       "literal-required@1"},
      {"expected name", "%! g(1) == count;\nfunc g(a : int) -> b : int\nend\n",
       "literal-required@1"},
      {"signed column",
       "%! g(-[1.0, 2.0]') == 4.0;\nfunc g(a : vector[2](float)) -> b : float\nend\n", "ok"},
  });
  auto c = compile("%! g(2) == 4;\nfunc g(a : int) -> b : int\n  b = a * 2;\nend\n");
  ASSERT_TRUE(c->ok());
  const ast::TestDecl* t = nullptr;
  for (const auto& d : c->program->decls)
    if (auto* td = d->as<ast::TestDecl>()) t = td;
  ASSERT_NE(t, nullptr);
  EXPECT_EQ(t->callee, func(*c, "g"));
  ASSERT_TRUE(t->args[0]->type);
  EXPECT_EQ(to_string(*t->args[0]->type), "int");
}

// ---------------------------------------------------------------------------
// Annotations the interpreter relies on

TEST(CheckerTest, SlotsAndResolution) {
  auto c = compile(
      "const k = 2.0;\n"
      "func g<N>(v : vector[N](float)) -> w : vector[N](float)\n"
      "  var t = k;\n  w = t * v;\n  for i in 0:3\n    u = i;\n  end\nend\n"
      "func f() -> r : vector[nodes](float)\n  r = g(nodes.x);\nend\n");
  ASSERT_TRUE(c->ok()) << c->diagnostics.render_all();
  ASSERT_EQ(c->program->globals.size(), 6u);  // five externs and the constant
  EXPECT_EQ(c->program->globals[5]->name, "k");
  EXPECT_EQ(c->program->globals[5]->slot, 5);
  const ast::FuncDecl& g = *func(*c, "g");
  EXPECT_EQ(g.frame_size, 6);  // N, v, w, t, i, u
  EXPECT_EQ(g.generics[0].var->slot, 0);
  EXPECT_EQ(g.results[0].var->slot, 2);
  const auto* vd = stmt<ast::VarDecl>(g, 0);
  ASSERT_NE(vd, nullptr);
  EXPECT_EQ(vd->var->slot, 3);
  EXPECT_EQ(vd->init->as<ast::VarRef>()->var, c->program->globals[5]);
  const ast::FuncDecl& f = *func(*c, "f");
  const auto* call = stmt<ast::Assign>(f, 0)->value->as<ast::Call>();
  ASSERT_NE(call, nullptr);
  EXPECT_EQ(call->func, &g);
  ASSERT_EQ(call->bindings.size(), 1u);
  EXPECT_EQ(call->bindings[0], IndexSet::set(c->program->globals[0]));
  EXPECT_EQ(to_string(*call->type), "vector[nodes](float)");
}

TEST(CheckerTest, ElementSourcesAndMaps) {
  auto c = compile(
      "func g(e : Edge, t : (Node * 2)) -> r : vector[nodes](float)\n"
      "  r(t(0)) = e.k;\nend\n"
      "func h(n : Node) -> r : vector[nodes](float)\n  r(n) = n.x;\nend\n"
      "func f()\n  a = map g to edges reduce +;\n  b = map h to nodes;\nend\n");
  ASSERT_TRUE(c->ok()) << c->diagnostics.render_all();
  const ast::Variable* nodes = c->program->globals[0];
  const ast::Variable* n = func(*c, "h")->params[0].var;
  EXPECT_TRUE(n->type->has_source);
  EXPECT_EQ(n->type->source, IndexSet::set(nodes));
  const ast::Variable* t = func(*c, "g")->params[1].var;
  EXPECT_TRUE(t->type->members[0]->has_source);
  const ast::FuncDecl& f = *func(*c, "f");
  const auto* m = stmt<ast::Assign>(f, 0)->value->as<ast::Map>();
  ASSERT_NE(m, nullptr);
  EXPECT_EQ(m->assembly.callee, func(*c, "g"));
  EXPECT_EQ(m->assembly.target_set, c->program->globals[2]);
  EXPECT_TRUE(m->assembly.pass_endpoints);
  EXPECT_TRUE(m->reduce);
  const auto* m2 = stmt<ast::Assign>(f, 1)->value->as<ast::Map>();
  EXPECT_FALSE(m2->assembly.pass_endpoints);
}

TEST(CheckerTest, FieldAndTupleReads) {
  auto c = compile(
      "func g(inout e : Edge, t : (a : Node, b : Node))\n"
      "  e.k = t.b.x + nodes.x(t.a);\nend\n");
  ASSERT_TRUE(c->ok()) << c->diagnostics.render_all();
  const auto* a = stmt<ast::Assign>(*func(*c, "g"), 0);
  const auto* target = a->targets[0]->as<ast::FieldRead>();
  ASSERT_NE(target, nullptr);
  EXPECT_EQ(target->field_index, 0);
  EXPECT_TRUE(target->writable);
  const auto* sum = a->value->as<ast::Binary>();
  const auto* tb = sum->lhs->as<ast::FieldRead>()->base->as<ast::TupleRead>();
  ASSERT_NE(tb, nullptr);
  EXPECT_EQ(tb->member_index, 1);
  const auto* view = sum->rhs->as<ast::TensorRead>()->base->as<ast::FieldRead>();
  ASSERT_NE(view, nullptr);
  EXPECT_TRUE(view->of_set);
  EXPECT_EQ(to_string(*view->type), "vector[nodes](float)");
}

// One mistake gives one diagnostic: uses of a name whose declaration failed are silent.
TEST(CheckerTest, NoCascades) {
  auto c = compile("func f()\n  a = nope + 1;\n  b = a * 2;\n  print b;\nend\n");
  EXPECT_EQ(c->diagnostics.size(), 1u) << c->diagnostics.render_all();
  c = compile("func f(v : vector[nope](float))\n  a = v(0);\n  b = v + v;\nend\n");
  EXPECT_EQ(c->diagnostics.size(), 1u) << c->diagnostics.render_all();
}

// A dense tensor's component count is bounded at type check: the product of its integer
// dimensions over all blocking levels would otherwise wrap around.
TEST(CheckerTest, TensorTypesTooLargeAreRejected) {
  auto c = compile_source("t.sim",
                          "func f()\n"
                          "  var a : tensor[65536,65536,65536,65536](float);\n"
                          "  var b : matrix[65536,65536](matrix[2,2](float));\n"
                          "  var c : vector[2147483647](float);\n"
                          "  var d : matrix[46341,46341](float);\n"
                          "end\n");
  const auto& items = c->diagnostics.items();
  ASSERT_EQ(items.size(), 3u) << c->diagnostics.render_all();
  const std::string message =
      "tensor type has more than 2147483647 components (2^31 - 1, the limit for a dense tensor)";
  const std::pair<int, int> places[] = {{2, 11}, {3, 11}, {5, 11}};
  for (size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(items[i].message, message);
    EXPECT_EQ(items[i].span.start().line, places[i].first);
    EXPECT_EQ(items[i].span.start().column, places[i].second);
    EXPECT_STREQ(category_name(items[i]), "dimension");
  }
}

// Control characters of the source are escaped where a diagnostic echoes it (a terminal
// would obey them), and the caret still lines up under the escaped text.
TEST(CheckerTest, DiagnosticsEscapeControlCharacters) {
  auto lexical = compile_source("t.sim", "func f()\n  var x = 1\x07;\nend\n");
  EXPECT_EQ(lexical->diagnostics.render_all(),
            "t.sim:2:12: error: unexpected symbol '\\x07'\n"
            "    var x = 1\\x07;\n"
            "             ^~~~\n");
  auto typed = compile_source("t.sim", "func f()\n  var s = \"a\x1b[31m\" + 1;\nend\n");
  EXPECT_EQ(typed->diagnostics.render_all(),
            "t.sim:2:11: error: expected left operand of element-wise operation to be a numeric "
            "tensor but got a value of type 'string'\n"
            "    var s = \"a\\x1b[31m\" + 1;\n"
            "            ^~~~~~~~~~~~~~~\n");
}

}  // namespace
}  // namespace simit::frontend
