// Type construction, equality (LANGUAGE.md §10.2) and spelling.
#include "frontend/types.h"

#include <gtest/gtest.h>

#include "type_fixtures.h"

namespace simit::frontend {
namespace {

class TypesTest : public ::testing::Test, public testing::TypeWorld {};

TEST_F(TypesTest, ScalarsEqualByKind) {
  EXPECT_TRUE(types_equal(*f(), *f()));
  EXPECT_FALSE(types_equal(*f(), *i()));
  EXPECT_FALSE(types_equal(*c(), *f()));
  EXPECT_TRUE(types_equal(*s(), *s()));
}

TEST_F(TypesTest, TensorWithoutDimensionsIsItsBlock) {
  TypeRef t = make_tensor({}, f());
  EXPECT_TRUE(t->is_scalar());
  EXPECT_TRUE(types_equal(*t, *f()));
}

TEST_F(TypesTest, IndexSetEquality) {
  EXPECT_EQ(fixed(3), fixed(3));
  EXPECT_NE(fixed(3), fixed(4));
  EXPECT_EQ(set(nodes), set(nodes));
  // Two sets of identical type are still different dimensions.
  EXPECT_NE(set(nodes), set(points));
  EXPECT_EQ(generic(N), generic(N));
  EXPECT_NE(generic(N), generic(M));
  EXPECT_NE(generic(N), set(nodes));
  EXPECT_NE(fixed(0), set(nodes));
}

TEST_F(TypesTest, TensorEqualityComparesDimensionsAndComponents) {
  EXPECT_TRUE(types_equal(*mat(2, 3), *mat(2, 3)));
  EXPECT_FALSE(types_equal(*mat(2, 3), *mat(3, 2)));
  EXPECT_FALSE(types_equal(*mat(2, 3), *mat(2, 3, i())));
  EXPECT_FALSE(types_equal(*col(3), *mat(3, 1)));
  EXPECT_FALSE(types_equal(*col(3), *f()));
  EXPECT_TRUE(types_equal(*col(set(nodes)), *col(set(nodes))));
  EXPECT_FALSE(types_equal(*col(set(nodes)), *col(set(points))));
  EXPECT_FALSE(types_equal(*col(generic(N)), *col(generic(M))));
  EXPECT_FALSE(types_equal(*col(generic(N)), *col(set(nodes))));
}

TEST_F(TypesTest, OrientationMattersForVectorsOnly) {
  EXPECT_FALSE(types_equal(*col(3), *row(3)));
  EXPECT_TRUE(types_equal(*row(3), *row(3)));
  // make_tensor drops the flag for matrices: orientation is not tracked there.
  TypeRef m = make_tensor({fixed(2), fixed(2)}, f(), true);
  EXPECT_FALSE(m->row);
  EXPECT_TRUE(types_equal(*m, *mat(2, 2)));
}

TEST_F(TypesTest, BlockedDimensionsCompareLevelByLevel) {
  TypeRef blocked = col(set(nodes), col(3));
  EXPECT_TRUE(types_equal(*blocked, *col(set(nodes), col(3))));
  EXPECT_FALSE(types_equal(*blocked, *col(set(nodes))));
  EXPECT_FALSE(types_equal(*blocked, *col(set(nodes), col(2))));
  EXPECT_FALSE(types_equal(*blocked, *col(set(nodes), col(3, i()))));
  EXPECT_FALSE(types_equal(*mat(4, 4, mat(2, 2)), *mat(8, 8)));
  EXPECT_TRUE(types_equal(*col(2, col(2, col(3))), *col(2, col(2, col(3)))));
  EXPECT_FALSE(types_equal(*col(2, col(2, col(3))), *col(2, col(3, col(2)))));
}

TEST_F(TypesTest, ComponentAndGlobal) {
  EXPECT_EQ(col(set(nodes), col(3, c()))->component(), ScalarKind::Complex);
  EXPECT_EQ(i()->component(), ScalarKind::Int);
  EXPECT_TRUE(col(set(nodes))->is_global());
  EXPECT_TRUE(col(generic(N))->is_global());
  EXPECT_FALSE(mat(3, 3)->is_global());
  EXPECT_FALSE(f()->is_global());
  EXPECT_EQ(mat(set(nodes), set(nodes), mat(3, 3))->order(), 2);
  EXPECT_EQ(f()->order(), 0);
}

TEST_F(TypesTest, ElementsEqualByDeclarationAndKnownSource) {
  EXPECT_TRUE(types_equal(*element(&node), *element(&node)));
  EXPECT_FALSE(types_equal(*element(&node), *element(&bar)));
  EXPECT_TRUE(types_equal(*element(&node), *element_of(&node, set(nodes))));
  EXPECT_TRUE(types_equal(*element_of(&node, set(nodes)), *element_of(&node, set(nodes))));
  EXPECT_FALSE(types_equal(*element_of(&node, set(nodes)), *element_of(&node, set(points))));
  EXPECT_FALSE(types_equal(*element_of(&node, generic(N)), *element_of(&node, set(nodes))));
  // A Fixed(0) source means unknown even when flagged.
  EXPECT_TRUE(types_equal(*element_of(&node, fixed(0)), *element_of(&node, set(nodes))));
}

TEST_F(TypesTest, TuplesCompareMembersAndNamesWhereBothNamed) {
  TypeRef n = element(&node);
  EXPECT_TRUE(types_equal(*tuple({n, n}), *tuple({n, n})));
  EXPECT_FALSE(types_equal(*tuple({n, n}), *tuple({n, n, n})));
  EXPECT_FALSE(types_equal(*tuple({n, n}), *tuple({n, element(&bar)})));
  EXPECT_TRUE(types_equal(*tuple({n, n}, {"a", "b"}), *tuple({n, n})));
  EXPECT_TRUE(types_equal(*tuple({n, n}, {"a", "b"}), *tuple({n, n}, {"a", "b"})));
  EXPECT_FALSE(types_equal(*tuple({n, n}, {"a", "b"}), *tuple({n, n}, {"b", "a"})));
}

TEST_F(TypesTest, SetsCompareElementAndEndpointElementTypes) {
  EXPECT_TRUE(types_equal(*vertex_set(&node), *vertex_set(&node)));
  EXPECT_FALSE(types_equal(*vertex_set(&node), *vertex_set(&bar)));
  TypeRef over_nodes = edge_set(&bar, {set(nodes), set(nodes)});
  // Endpoints are compared by their element types, not by set identity.
  EXPECT_TRUE(types_equal(*over_nodes, *edge_set(&bar, {set(points), set(nodes)})));
  EXPECT_FALSE(types_equal(*over_nodes, *edge_set(&bar, {set(nodes)})));
  EXPECT_FALSE(types_equal(*over_nodes, *edge_set(&bar, {set(nodes), set(springs)})));
  EXPECT_FALSE(types_equal(*over_nodes, *vertex_set(&bar)));
}

TEST_F(TypesTest, GridsCompareDimensionCountAndPointSet) {
  EXPECT_TRUE(types_equal(*grid(&bar, 2, set(points)), *grid(&bar, 2, set(points))));
  EXPECT_FALSE(types_equal(*grid(&bar, 2, set(points)), *grid(&bar, 3, set(points))));
  EXPECT_FALSE(types_equal(*grid(&bar, 2, set(points)), *grid(&bar, 2, set(nodes))));
  EXPECT_FALSE(types_equal(*grid(&bar, 1, set(points)), *edge_set(&bar, {set(points)})));
}

TEST_F(TypesTest, OpaqueVoidAndMulti) {
  EXPECT_TRUE(types_equal(*make_opaque(), *make_opaque()));
  EXPECT_FALSE(types_equal(*make_opaque(), *f()));
  EXPECT_TRUE(types_equal(*make_void(), *make_void()));
  EXPECT_TRUE(types_equal(*make_multi({f(), i()}), *make_multi({f(), i()})));
  EXPECT_FALSE(types_equal(*make_multi({f(), i()}), *make_multi({i(), f()})));
}

TEST_F(TypesTest, Spellings) {
  EXPECT_EQ(to_string(*f()), "float");
  EXPECT_EQ(to_string(*c()), "complex");
  EXPECT_EQ(to_string(ScalarKind::String), "string");
  EXPECT_EQ(to_string(*mat(2, 2)), "tensor[2,2](float)");
  EXPECT_EQ(to_string(*col(3, i())), "vector[3](int)");
  EXPECT_EQ(to_string(*row(3)), "vector[3](float)'");
  EXPECT_EQ(to_string(*row(set(nodes), col(3))), "vector[nodes](vector[3](float))'");
  EXPECT_EQ(to_string(*mat(set(nodes), generic(N), mat(3, 3))),
            "tensor[nodes,N](tensor[3,3](float))");
  EXPECT_EQ(to_string(*make_tensor({fixed(2), fixed(2), fixed(2)}, f())), "tensor[2,2,2](float)");
  EXPECT_EQ(to_string(*element(&node)), "Node");
  EXPECT_EQ(to_string(*vertex_set(&node)), "set{Node}");
  EXPECT_EQ(to_string(*springs.type), "set{Bar}(nodes,nodes)");
  EXPECT_EQ(to_string(*grid(&bar, 2, set(points))), "grid[2]{Bar}(points)");
  EXPECT_EQ(to_string(*tuple({element(&node), element(&node)})), "(Node*2)");
  EXPECT_EQ(to_string(*tuple({element(&node), element(&bar)}, {"a", "b"})), "(a : Node, b : Bar)");
  EXPECT_EQ(to_string(*make_opaque()), "opaque");
  EXPECT_EQ(to_string(*make_void()), "void");
  EXPECT_EQ(to_string(*make_multi({f(), i()})), "(float, int)");
}

}  // namespace
}  // namespace simit::frontend
