// --check-jit on sets a scene renumbered: the first difference is reported at the element's
// mesh number (runtime::Set::mesh_number), for map results, fields an apply writes, and the
// vectors and fields a compiled statement writes. The JIT is made to differ with the
// test-only corrupt_for_test, which flips the lowest bit of the first value it computed.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "api/engine.h"
#include "interp/runtime_error.h"

namespace simit::jit {
namespace {

using api::CompiledProgram;
using api::Engine;
using api::EngineOptions;
using api::ExecutorKind;
using runtime::ComponentKind;
using runtime::FieldType;

const char* kProgram = R"(
element V
  x : float;
  y : float;
  u : vector[2](float);
end
element E
  k : float;
end
extern verts : set{V};
extern edges : set{E}(verts, verts);

func spread(e : E, v : (V * 2)) -> r : vector[verts](float)
  r(v(0)) = e.k * v(1).x;
  r(v(1)) = e.k + v(0).x;
end

func spread2(e : E, v : (V * 2)) -> r : vector[verts](vector[2](float))
  r(v(0)) = e.k * v(1).u;
  r(v(1)) = e.k * v(0).u + v(1).u;
end

func stiff(e : E, v : (V * 2)) -> K : matrix[verts,verts](float)
  for i in 0:2
    for j in 0:2
      K(v(i), v(j)) = e.k + v(i).x * v(j).x;
    end
  end
end

func bump(inout p : V)
  p.y = 2.0 * p.x + p.y;
end

export func vector_result()
  verts.y = map spread to edges reduce +;
end

export func blocked_result()
  verts.u = map spread2 to edges reduce +;
end

export func matrix_result() -> K : matrix[verts,verts](float)
  K = map stiff to edges reduce +;
end

export func apply_field()
  apply bump to verts;
end

export func vector_statement() -> w : vector[verts](float)
  w = 3.0 * verts.x + verts.y;
end

export func field_statement()
  verts.y = 3.0 * verts.x + verts.y;
end
)";

// A path of 6 vertices and its 5 edges, renumbered (as a scene would) unless `plain`: vertex e
// is the mesh's 5 - e, edge e the mesh's (e + 2) mod 5.
struct Path {
  static constexpr int kVerts = 6, kEdges = 5;
  runtime::Set verts{"verts"};
  runtime::Set edges{"edges", {&verts, &verts}};
  std::vector<int32_t> vert_numbers, edge_numbers;

  explicit Path(bool plain) {
    verts.add_many(kVerts);
    verts.add_field("x", FieldType{ComponentKind::Float, {}, false});
    verts.add_field("y", FieldType{ComponentKind::Float, {}, false});
    verts.add_field("u", FieldType{ComponentKind::Float, {2}, false});
    for (int i = 0; i < kVerts; ++i) {
      verts.field(0).at<double>(i)[0] = 0.5 + 0.25 * i;
      verts.field(1).at<double>(i)[0] = 1.0 - 0.125 * i;
      verts.field(2).at<double>(i)[0] = 0.75 * i;
      verts.field(2).at<double>(i)[1] = 2.0 - 0.5 * i;
    }
    for (int e = 0; e < kEdges; ++e) edges.add({e, e + 1});
    edges.add_field("k", FieldType{ComponentKind::Float, {}, false});
    for (int e = 0; e < kEdges; ++e) edges.field(0).at<double>(e)[0] = 1.5 + e;
    if (plain) return;
    for (int e = 0; e < kVerts; ++e) vert_numbers.push_back(kVerts - 1 - e);
    for (int e = 0; e < kEdges; ++e) edge_numbers.push_back((e + 2) % kEdges);
    verts.set_mesh_numbers(vert_numbers);
    edges.set_mesh_numbers(edge_numbers);
  }
};

// Runs `func` once, compiled at once and checked, the JIT's first value corrupted; the error.
std::string check(const std::string& func, Path& path) {
  auto compiled = CompiledProgram::from_source("check_jit.sim", kProgram);
  EngineOptions o;
  o.executor.kind = ExecutorKind::Jit;
  o.executor.threshold = 0;
  o.executor.check = true;
  o.corrupt_for_test = true;
  Engine engine(compiled, o);
  engine.bind_set(*compiled->find_extern("verts"), path.verts);
  engine.bind_set(*compiled->find_extern("edges"), path.edges);
  try {
    engine.call(*compiled->find_func(func), {});
  } catch (const interp::RuntimeError& e) {
    return e.render();
  }
  return "(no error)";
}

// "at element M of set 'S':" with M the mesh number of internal element 0, from the
// permutation the test chose.
std::string at_first(const std::vector<int32_t>& numbers, const std::string& set) {
  return "at element " + std::to_string(numbers.at(0)) + " of set '" + set + "':";
}

bool has(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

TEST(CheckJitMeshNumbers, MapResultsNameTheMeshElement) {
  if (!api::jit_available()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  Path path(false);
  ASSERT_EQ(path.vert_numbers.at(0), 5);
  // Entry 0 of the vector is internal vertex 0.
  std::string error = check("vector_result", path);
  EXPECT_TRUE(has(
      error, "differs from the interpreter in result 'r' " + at_first(path.vert_numbers, "verts")))
      << error;
  EXPECT_FALSE(has(error, "entry 0")) << error;
  // Component 0 of vertex 0's block.
  error = check("blocked_result", path);
  EXPECT_TRUE(has(error, "differs from the interpreter in result 'r' component 0 " +
                             at_first(path.vert_numbers, "verts")))
      << error;
  // Block 0 is K(0, 0), which edge 0 (the only one on vertex 0) writes first.
  error = check("matrix_result", path);
  EXPECT_TRUE(has(error, "in result 'K' component 0 (block 0")) << error;
  EXPECT_TRUE(has(error, at_first(path.edge_numbers, "edges"))) << error;
}

TEST(CheckJitMeshNumbers, FieldsAndStatementsNameTheMeshElement) {
  if (!api::jit_available()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  Path path(false);
  // An apply's first written field, at its first byte: vertex 0.
  std::string error = check("apply_field", path);
  EXPECT_TRUE(has(
      error, "differs from the interpreter in field 'y' " + at_first(path.vert_numbers, "verts")))
      << error;
  // A compiled statement's vector, and its field.
  error = check("vector_statement", path);
  EXPECT_TRUE(
      has(error, "differs from the interpreter in 'w' " + at_first(path.vert_numbers, "verts")))
      << error;
  error = check("field_statement", path);
  EXPECT_TRUE(has(
      error, "differs from the interpreter in 'verts.y' " + at_first(path.vert_numbers, "verts")))
      << error;
}

// Without mesh numbers the messages keep the plain indices.
TEST(CheckJitMeshNumbers, PlainSetsKeepTheirIndices) {
  if (!api::jit_available()) GTEST_SKIP() << "this build has no JIT (SIMIT_WITH_LLVM=OFF)";
  Path path(true);
  std::string error = check("vector_result", path);
  EXPECT_TRUE(has(error, "in result 'r' component 0 (entry 0 of the vector):")) << error;
  error = check("apply_field", path);
  EXPECT_TRUE(has(error, "in field 'y' at element 0 of set 'verts':")) << error;
  error = check("vector_statement", path);
  EXPECT_TRUE(has(error, "in 'w' component 0 (element 0):")) << error;
}

}  // namespace
}  // namespace simit::jit
