// Assembly's run-time errors through the interpreter on host-built sets: an error inside a
// mapped function names the element the map was serving (both, in a nested map), and a write
// outside the pattern or the neighbourhood names the element and the line.
#include <Eigen/Dense>
#include <cmath>
#include <cstdio>
#include <set>
#include <utility>

#include "assembly_support.h"

namespace simit::interp {
namespace {

using namespace assembly_support;

// ------------------------------------------------------------------------------------------
// Writes outside the pattern or the neighbourhood: run-time errors naming element and line.

// A run-time error inside a mapped function (here in a helper it calls) names, in the stack, the
// element the map was serving and its endpoints; a nested map names both elements.
TEST(Assembly, RunTimeErrorsNameTheMappedElement) {
  Harness h(R"(element N  d : int; end
element T  k : int; end
extern nodes : set{N};
extern tris : set{T}(nodes, nodes, nodes);
func ratio(a : int, b : int) -> r : int
  r = a / b;
end
func per_tri(t : T, v : (N * 3)) -> f : vector[nodes](float)
  q = ratio(t.k, v(1).d);
  f(v(0)) = 1.0;
end
func per_node(inout n : N)
  f = map per_tri to tris reduce +;
  n.d = n.d + 1;
end
export func run_tris() -> f : vector[nodes](float)
  f = map per_tri to tris reduce +;
end
export func run_nodes()
  apply per_node to nodes;
end
)");
  ASSERT_TRUE(h.ok());
  runtime::Set nodes("nodes"), tris("tris", {&nodes, &nodes, &nodes});
  nodes.add_many(5);
  tris.add({0, 1, 2});
  tris.add({3, 4, 0});  // v(1) = node 4, whose d is 0: the division fails here
  tris.add({1, 2, 3});
  h.bind("nodes", nodes);
  h.bind("tris", tris);
  int32_t* d = nodes.field("d").data<int32_t>();
  for (int i = 0; i < 4; ++i) d[i] = 1;
  try {
    h.run("run_tris");
    FAIL() << "expected a run-time error";
  } catch (const RuntimeError& e) {
    EXPECT_EQ(e.render(),
              "assembly.sim:6:7: runtime error: integer division by zero\n"
              "  in ratio (assembly.sim:6)\n"
              "  in per_tri (assembly.sim:9), mapping over element 1 of set 'tris' (endpoints 3, "
              "4, 0 of 'nodes')\n"
              "  in run_tris (assembly.sim:17)\n");
  }
  try {
    h.run("run_nodes");
    FAIL() << "expected a run-time error";
  } catch (const RuntimeError& e) {
    EXPECT_EQ(e.render(),
              "assembly.sim:6:7: runtime error: integer division by zero\n"
              "  in ratio (assembly.sim:6)\n"
              "  in per_tri (assembly.sim:9), mapping over element 1 of set 'tris' (endpoints 3, "
              "4, 0 of 'nodes')\n"
              "  in per_node (assembly.sim:13), mapping over element 0 of set 'nodes'\n"
              "  in run_nodes (assembly.sim:20)\n");
  }
}

TEST(Assembly, WriteOutsideThePatternNamesElementAndLine) {
  Harness h(R"(element N  x : float; end
element S  k : float; end
extern nodes : set{N};
extern springs : set{S}(nodes, nodes);
func bad(s : S, e : (N * 2)) -> K : matrix[nodes,nodes](float)
  K(e(0), e(1)) = s.k;
  for n in nodes
    K(e(0), n) = 1.0;
  end
end
func badvec(s : S, e : (N * 2)) -> f : vector[nodes](float)
  for n in nodes
    f(n) = s.k;
  end
end
export func mat_case() -> K : matrix[nodes,nodes](float)
  K = map bad to springs reduce +;
end
export func vec_case() -> f : vector[nodes](float)
  f = map badvec to springs reduce +;
end
)");
  ASSERT_TRUE(h.ok());
  runtime::Set nodes("nodes"), springs("springs", {&nodes, &nodes});
  nodes.add_many(4);
  springs.add({0, 1});
  springs.add({2, 3});
  h.bind("nodes", nodes);
  h.bind("springs", springs);
  try {
    h.run("mat_case");
    FAIL() << "expected a run-time error";
  } catch (const RuntimeError& e) {
    EXPECT_EQ(e.line(), 8);
    // (0, 0) and (0, 1) are in the pattern; (0, 2) is not.
    EXPECT_NE(e.message().find("element 2 of set 'nodes'"), std::string::npos) << e.message();
    EXPECT_NE(e.message().find("element 0 of set 'springs'"), std::string::npos) << e.message();
    EXPECT_NE(e.render().find("assembly.sim:8:"), std::string::npos) << e.render();
    ASSERT_FALSE(e.stack().empty());
    EXPECT_EQ(e.stack()[0].func, "bad");
  }
  try {
    h.run("vec_case");
    FAIL() << "expected a run-time error";
  } catch (const RuntimeError& e) {
    EXPECT_EQ(e.line(), 13);
    // Element 0 of nodes is an endpoint of spring 0; element 2 is not.
    EXPECT_NE(e.message().find("element 2 of set 'nodes'"), std::string::npos) << e.message();
    EXPECT_NE(e.message().find("element 0 of set 'springs'"), std::string::npos) << e.message();
  }
  // The interpreter stays usable, and the pattern is intact for a correct program.
  EXPECT_THROW(h.run("mat_case"), RuntimeError);
}

// Any run-time error inside a mapped function names the element being mapped in the stack
// frame of the mapped function, not in the frames of the functions it calls.
TEST(Assembly, RuntimeErrorInMappedFunctionNamesTheElement) {
  Harness h(R"(element N  d : int; end
extern nodes : set{N};
func quotient(n : N) -> q : int
  q = 12 / n.d;
end
func per_node(n : N) -> f : vector[nodes](int)
  f(n) = quotient(n);
end
export func run() -> f : vector[nodes](int)
  f = map per_node to nodes;
end
)");
  ASSERT_TRUE(h.ok());
  runtime::Set nodes("nodes");
  nodes.add_many(4);
  h.bind("nodes", nodes);
  int32_t* d = nodes.field("d").data<int32_t>();
  d[0] = 1;
  d[1] = 2;
  d[2] = 0;  // the division by zero
  d[3] = 3;
  try {
    h.run("run");
    FAIL() << "expected a run-time error";
  } catch (const RuntimeError& e) {
    EXPECT_EQ(e.line(), 4);
    ASSERT_EQ(e.stack().size(), 3u);
    EXPECT_EQ(e.stack()[0].func, "quotient");
    EXPECT_EQ(e.stack()[1].func, "per_node");
    EXPECT_EQ(e.stack()[1].element, "mapping over element 2 of set 'nodes'");
    EXPECT_EQ(e.stack()[2].func, "run");
    EXPECT_NE(
        e.render().find("  in per_node (assembly.sim:7), mapping over element 2 of set 'nodes'\n"),
        std::string::npos)
        << e.render();
  }
}

}  // namespace
}  // namespace simit::interp
