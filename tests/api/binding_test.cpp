// Programs and bindings through the public API: compile errors, every kind of binding
// mismatch (each reported by name), unbound externs, and a small run on bound sets.
#include <gtest/gtest.h>

#include <sstream>

#include "api_test_util.h"
#include "simit/simit.h"

namespace {

using simit::testing::contains;
using simit::testing::message_of;

const char* kProgram = R"(
element Node
  x  : vector[3](float);
  m  : float;
  id : int;
end
element Bar
  k : float;
end
extern nodes : set{Node};
extern bars  : set{Bar}(nodes, nodes);
extern dt    : vector[2](float);
extern unused : float;

func scale(inout n : Node)
  n.x = dt(0) * n.x;
  n.m = n.m + dt(1);
end

func stretch(inout b : Bar, ends : (Node * 2))
  b.k = ends(1).m - ends(0).m;
end

export func step()
  apply scale to nodes;
  apply stretch to bars;
end

export func twice(a : vector[2](float)) -> (b : vector[2](float), s : float)
  b = 2.0 * a;
  s = a(0) + a(1);
end
)";

simit::Program load() {
  simit::Program p;
  p.load_string(kProgram, "bars.sim");
  return p;
}

// A host graph matching the program: 3 nodes, 2 bars.
struct Graph {
  simit::Set nodes{"nodes"};
  simit::Set bars{"bars", nodes, nodes};
  simit::FieldRef<double, 3> x = nodes.add_field<double, 3>("x");
  simit::FieldRef<double> m = nodes.add_field<double>("m");
  simit::FieldRef<int> id = nodes.add_field<int>("id");
  simit::FieldRef<double> k = bars.add_field<double>("k");
  simit::Tensor<double, 2> dt{2.0, 0.5};
  Graph() {
    for (int i = 0; i < 3; ++i) {
      simit::ElementRef n = nodes.add();
      x(n) = {1.0 * i, 1.0, -1.0};
      m.set(n, 10.0 * i);
    }
    bars.add(simit::ElementRef(0), simit::ElementRef(1));
    bars.add(simit::ElementRef(1), simit::ElementRef(2));
  }
};

TEST(ApiProgram, CompileErrorsCarryRenderedDiagnostics) {
  simit::Program p;
  std::string text = message_of<simit::CompileError>(
      [&] { p.load_string("export func f()\n  x = y;\nend\n", "bad.sim"); });
  EXPECT_TRUE(contains(text, "bad.sim:2:"));
  EXPECT_TRUE(contains(text, "y"));
  EXPECT_TRUE(p.has_errors());
  ASSERT_FALSE(p.diagnostics().empty());
  EXPECT_EQ(p.diagnostics()[0].line, 2);
  EXPECT_EQ(p.diagnostics()[0].category, "undeclared");
  EXPECT_FALSE(p.loaded());
  EXPECT_EQ(p.loadString("export func f()\n  x = y;\nend\n"), 1);
  EXPECT_EQ(p.loadFile("no/such/file.sim"), 2);
  EXPECT_THROW(p.load_file("no/such/file.sim"), simit::CompileError);
  EXPECT_EQ(p.loadString(kProgram), 0);
  EXPECT_FALSE(p.has_errors());
  EXPECT_EQ(p.function_names(), (std::vector<std::string>{"step", "twice"}));
  EXPECT_THROW(p.compile("nope"), simit::Error);
}

TEST(ApiProgram, InitBuildsOptionsWithoutGlobalState) {
  EXPECT_EQ(simit::init("interpreter", 4).float_size, 4);
  EXPECT_THROW((void)simit::init("tpu"), simit::Error);
  EXPECT_THROW((void)simit::init("interpreter", 2), simit::Error);
  EXPECT_EQ(simit::Options{}.float_size, 8);
}

TEST(ApiBind, MatchingGraphRunsInPlace) {
  simit::Program p = load();
  simit::Function step = p.compile("step");
  Graph g;
  step.bind("nodes", g.nodes);
  step.bind("bars", &g.bars);
  step.bind("dt", g.dt);
  EXPECT_TRUE(step.unbound().empty());  // 'unused' is not used by step
  step.init();
  step.run();
  EXPECT_EQ(g.x(simit::ElementRef(2))(0), 4.0);
  EXPECT_EQ(g.x(simit::ElementRef(2))(2), -2.0);
  EXPECT_EQ(double(g.m(simit::ElementRef(1))), 10.5);
  EXPECT_EQ(double(g.k(simit::ElementRef(1))), 10.0);
  g.dt(0) = 1.0;  // host tensors are read at every run
  step.runSafe();
  EXPECT_EQ(g.x(simit::ElementRef(2))(0), 4.0);
  EXPECT_EQ(double(g.m(simit::ElementRef(1))), 11.0);
}

TEST(ApiBind, ParametersAndResults) {
  simit::Program p = load();
  simit::Function twice = p.compile("twice");
  simit::Tensor<double, 2> a{1.5, 2.0}, b;
  simit::Tensor<double> s;
  EXPECT_EQ(twice.unbound(), (std::vector<std::string>{"a"}));
  twice.bind("a", a);
  twice.bind("b", b);
  twice.bind("s", s);
  twice.run();
  EXPECT_EQ(b(0), 3.0);
  EXPECT_EQ(b(1), 4.0);
  EXPECT_EQ(double(s), 3.5);
  EXPECT_EQ(twice.result("s").floats()[0], 3.5);
  EXPECT_EQ(twice.result("s").kind(), simit::ComponentKind::Float);
  EXPECT_EQ(twice.result("s").size(), 1u);
  EXPECT_THROW(twice.matrix("b"), simit::Error);
}

TEST(ApiBind, UnboundExternsAreNamedAtInitAndRun) {
  simit::Program p = load();
  simit::Function step = p.compile("step");
  Graph g;
  step.bind("bars", g.bars);
  EXPECT_EQ(step.unbound(), (std::vector<std::string>{"nodes", "dt"}));
  std::string text = message_of<simit::BindError>([&] { step.init(); });
  EXPECT_TRUE(contains(text, "extern 'nodes' is not bound"));
  EXPECT_TRUE(contains(text, "extern 'dt' is not bound"));
  EXPECT_FALSE(contains(text, "unused"));
  EXPECT_THROW(step.run(), simit::BindError);
}

TEST(ApiBind, UnknownNamesAndKindsOfBinding) {
  simit::Program p = load();
  simit::Function step = p.compile("step");
  Graph g;
  EXPECT_TRUE(contains(message_of<simit::BindError>([&] { step.bind("nods", g.nodes); }),
                       "'nods' is not an extern"));
  EXPECT_TRUE(contains(message_of<simit::BindError>([&] { step.bind("dt", g.nodes); }),
                       "extern 'dt' is vector[2](float), not a set extern"));
  EXPECT_TRUE(contains(message_of<simit::BindError>([&] { step.bind("nodes", g.dt); }),
                       "extern 'nodes' is a set"));
}

TEST(ApiBind, VertexVersusEdgeSetsAndArity) {
  simit::Program p = load();
  simit::Function step = p.compile("step");
  Graph g;
  EXPECT_TRUE(contains(message_of<simit::BindError>([&] { step.bind("bars", g.nodes); }),
                       "extern 'bars': is an edge set with 2 endpoints in the program but "
                       "set 'nodes' is a vertex set"));
  EXPECT_TRUE(contains(message_of<simit::BindError>([&] { step.bind("nodes", g.bars); }),
                       "extern 'nodes': is a vertex set in the program but set 'bars' is an "
                       "edge set with 2 endpoints"));
  simit::Set triples("triples", g.nodes, g.nodes, g.nodes);
  triples.add_field<double>("k");
  EXPECT_TRUE(contains(message_of<simit::BindError>([&] { step.bind("bars", triples); }),
                       "set 'triples' is an edge set with 3 endpoints"));
}

TEST(ApiBind, EveryFieldMismatchIsReportedByNameInOneError) {
  simit::Program p = load();
  simit::Function step = p.compile("step");
  simit::Set nodes("nodes");
  nodes.add_field<double, 2>("x");  // 2 components instead of 3
  nodes.add_field<int>("m");        // int instead of float
  // no field 'id'
  nodes.add_field<double>("extra");  // ignored
  try {
    step.bind("nodes", nodes);
    FAIL() << "bind accepted a mismatching set";
  } catch (const simit::BindError& e) {
    ASSERT_EQ(e.problems().size(), 3u) << e.what();
    EXPECT_EQ(e.problems()[0],
              "extern 'nodes': field 'x' is vector[3](float) in the program but the set's "
              "field 'x' has 2 components");
    EXPECT_EQ(e.problems()[1],
              "extern 'nodes': field 'm' is float in the program but the set's field 'm' has "
              "int components");
    EXPECT_EQ(e.problems()[2], "extern 'nodes': field 'id' (int) is missing from set 'nodes'");
  }
}

TEST(ApiBind, FieldShapeAndPrecisionMismatches) {
  simit::Program p = load();
  simit::Function step = p.compile("step");
  simit::Set nodes("nodes");
  nodes.add_field<double, 3, 1>("x");  // same count, other shape
  nodes.add_field<float>("m");         // binary32 while float size is 8
  nodes.add_field<int>("id");
  std::string text = message_of<simit::BindError>([&] { step.bind("nodes", nodes); });
  EXPECT_TRUE(contains(text,
                       "field 'x' is vector[3](float) in the program but the set's "
                       "field 'x' has dimensions 3x1"));
  EXPECT_TRUE(contains(text,
                       "field 'm' is float in the program but the set's field 'm' "
                       "stores binary32 components, but the program's float size is 8"));
}

TEST(ApiBind, FloatSizeFourWantsSinglePrecisionFields) {
  simit::Program p(simit::init("interpreter", 4));
  p.load_string(kProgram);
  simit::Function step = p.compile("step");
  simit::Set nodes("nodes");
  nodes.add_field<float, 3>("x");
  nodes.add_field<float>("m");
  nodes.add_field<int>("id");
  EXPECT_NO_THROW(step.bind("nodes", nodes));
  simit::Tensor<double, 2> wrong;
  EXPECT_TRUE(contains(message_of<simit::BindError>([&] { step.bind("dt", wrong); }),
                       "extern 'dt' is vector[2](float) in the program but the host tensor "
                       "(double 2) stores binary64 components"));
}

TEST(ApiBind, EndpointSetsMustBeTheBoundSets) {
  simit::Program p = load();
  Graph g;
  simit::Set other("other");
  other.add_field<double, 3>("x");
  other.add_field<double>("m");
  other.add_field<int>("id");
  simit::Set strays("strays", other, g.nodes);
  strays.add_field<double>("k");
  // Nodes bound first: the bind of the edge set itself is refused.
  simit::Function step = p.compile("step");
  step.bind("nodes", g.nodes);
  EXPECT_EQ(message_of<simit::BindError>([&] { step.bind("bars", strays); }),
            "extern 'bars': endpoint 0 must come from the set bound to 'nodes' (set 'nodes'), "
            "but the bound set's endpoint 0 is set 'other'");
  // Edge set bound first: init finds it.
  simit::Function step2 = p.compile("step");
  step2.bind("bars", strays);
  step2.bind("nodes", g.nodes);
  step2.bind("dt", g.dt);
  std::string text = message_of<simit::BindError>([&] { step2.init(); });
  EXPECT_TRUE(contains(text, "endpoint 0 must come from the set bound to 'nodes'"));
  EXPECT_FALSE(contains(text, "endpoint 1"));
}

TEST(ApiBind, TensorExternShapesAndKinds) {
  simit::Program p = load();
  simit::Function step = p.compile("step");
  simit::Tensor<double, 3> three;
  simit::Tensor<int, 2> ints;
  simit::Tensor<double> scalar;
  EXPECT_TRUE(contains(message_of<simit::BindError>([&] { step.bind("dt", three); }),
                       "extern 'dt' is vector[2](float) in the program but the host tensor "
                       "(double 3) has 3 components"));
  EXPECT_TRUE(
      contains(message_of<simit::BindError>([&] { step.bind("dt", ints); }), "has int components"));
  EXPECT_TRUE(
      contains(message_of<simit::BindError>([&] { step.bind("dt", scalar); }), "has 1 component"));
  EXPECT_NO_THROW(step.bind("unused", scalar));
}

TEST(ApiBind, GridSetsAreCheckedAndRun) {
  simit::Program p;
  p.load_string(R"(
element Cell  u : float; r : float; end
element Face  w : float; end
extern cells : set{Cell};
extern faces : grid[1]{Face}(cells);
func stencil(c : Cell, g : grid[1]{Face}(cells)) -> L : matrix[cells,cells](float)
  L(c, c)         = g[0;1].w + g[0;-1].w;
  L(c, cells[1])  = -g[0;1].w;
  L(c, cells[-1]) = -g[0;-1].w;
end
export func apply_laplacian()
  L = map stencil to cells through faces reduce +;
  cells.r = L * cells.u;
end
)");
  simit::Function f = p.compile("apply_laplacian");
  simit::Set cells("cells"), plain("plain");
  simit::Set faces("faces", cells, {4});
  auto u = cells.add_field<double>("u");
  auto r = cells.add_field<double>("r");
  auto w = faces.add_field<double>("w");
  simit::Set square("square", plain, {2, 2});
  square.add_field<double>("w");
  EXPECT_TRUE(contains(message_of<simit::BindError>([&] { f.bind("faces", square); }),
                       "extern 'faces': is a 1-dimensional grid in the program but set "
                       "'square' is a 2-dimensional grid"));
  f.bind("cells", cells);
  f.bind("faces", faces);
  for (int i = 0; i < 4; ++i) {
    u.set(simit::ElementRef(i), 1.0 * i * i);
    w.set(simit::ElementRef(i), 1.0);
  }
  f.run();
  // Periodic second difference of 0, 1, 4, 9.
  EXPECT_EQ(double(r(simit::ElementRef(1))), 2 * 1.0 - 0.0 - 4.0);
  EXPECT_EQ(double(r(simit::ElementRef(0))), 0.0 - 9.0 - 1.0);
}

TEST(ApiRun, SinglePrecisionFieldsRunWithFloatSizeFour) {
  simit::Program p(simit::init("interpreter", 4));
  p.load_string(kProgram);
  simit::Function step = p.compile("step");
  simit::Set nodes("nodes");
  simit::Set bars("bars", nodes, nodes);
  auto x = nodes.add_field<float, 3>("x");
  auto m = nodes.add_field<float>("m");
  nodes.add_field<int>("id");
  auto k = bars.add_field<float>("k");
  simit::ElementRef a = nodes.add(), b = nodes.add();
  x(a) = {1.0f, 2.0f, 3.0f};
  m.set(b, 0.25f);
  bars.add(a, b);
  simit::Tensor<float, 2> dt{0.1f, 1.0f};
  step.bind("nodes", nodes);
  step.bind("bars", bars);
  step.bind("dt", dt);
  step.run();
  EXPECT_EQ(x(a)(2), 0.3f);  // 0.1 * 3 rounded to binary32
  EXPECT_EQ(float(m(b)), 1.25f);
  EXPECT_EQ(float(k(simit::ElementRef(0))), 0.25f);
}

TEST(ApiRun, GrowingASetAfterInitReinitialises) {
  simit::Program p = load();
  simit::Function step = p.compile("step");
  Graph g;
  step.bind("nodes", g.nodes);
  step.bind("bars", g.bars);
  step.bind("dt", g.dt);
  step.init();
  step.run();
  simit::ElementRef n = g.nodes.add();
  g.m.set(n, 100.0);
  g.bars.add(simit::ElementRef(2), n);
  step.run();  // sees the new node and bar without an explicit init()
  EXPECT_EQ(double(g.m(n)), 100.5);
  EXPECT_EQ(double(g.k(simit::ElementRef(2))), 100.5 - 21.0);
}

TEST(ApiRun, RuntimeErrorsNameTheLine) {
  simit::Program p;
  p.load_string(
      "extern v : vector[3](float);\n"
      "export func f(i : int) -> r : float\n"
      "  r = v(i);\n"
      "end\n",
      "oob.sim");
  simit::Function f = p.compile("f");
  simit::Tensor<double, 3> v{1.0, 2.0, 3.0};
  simit::Tensor<int> i{5};
  f.bind("v", v);
  f.bind("i", i);
  try {
    f.run();
    FAIL() << "no run-time error";
  } catch (const simit::RuntimeError& e) {
    EXPECT_EQ(e.line(), 3);
    EXPECT_TRUE(contains(e.what(), "oob.sim:3:"));
  }
  i = 1;
  f.run();
  EXPECT_EQ(f.result("r").floats()[0], 2.0);
}

TEST(ApiRun, PrintGoesToTheOptionsStream) {
  std::ostringstream out;
  simit::Options o;
  o.out = &out;
  simit::Program p(o);
  p.load_string("export func hello()\n  println \"hi\";\nend\n");
  simit::Function f = p.compile("hello");
  f.run();
  EXPECT_EQ(out.str(), "hi\n");
}

}  // namespace
