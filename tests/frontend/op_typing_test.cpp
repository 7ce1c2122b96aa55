// Typing rules of operators and intrinsics (LANGUAGE.md §6.4-6.9, §9).
#include "frontend/op_typing.h"

#include <gtest/gtest.h>

#include "type_fixtures.h"

namespace simit::frontend {
namespace {

using Op = ast::Binary::Op;
using Cmp = ast::Compare::Op;
using K = SemanticKind;

class OpTypingTest : public ::testing::Test, public testing::TypeWorld {
 protected:
  // The spelling of the result type, or "error:<kind>" with the message checked non-empty.
  static std::string spell(const Typing& t) {
    if (t.ok()) return to_string(*t.type);
    EXPECT_FALSE(t.error.empty());
    return "error";
  }
  static std::string bin(Op op, const TypeRef& l, const TypeRef& r) {
    return spell(type_binary(op, *l, *r));
  }
  static K bin_kind(Op op, const TypeRef& l, const TypeRef& r) {
    Typing t = type_binary(op, *l, *r);
    EXPECT_FALSE(t.ok()) << to_string(*t.type);
    return t.kind;
  }

  IndexSet V() const { return set(nodes); }
  IndexSet P() const { return set(points); }
  TypeRef sysmat() const { return mat(V(), V(), mat(3, 3)); }
  TypeRef sysvec() const { return col(V(), col(3)); }
};

// ---------------------------------------------------------------------------
// + - .* ./

TEST_F(OpTypingTest, ElementwiseAcceptsEqualTypes) {
  EXPECT_EQ(bin(Op::Add, f(), f()), "float");
  EXPECT_EQ(bin(Op::Sub, i(), i()), "int");
  EXPECT_EQ(bin(Op::Add, c(), c()), "complex");
  EXPECT_EQ(bin(Op::Add, mat(2, 3), mat(2, 3)), "tensor[2,3](float)");
  EXPECT_EQ(bin(Op::ElemMul, row(3), row(3)), "vector[3](float)'");
  EXPECT_EQ(bin(Op::ElemDiv, sysvec(), sysvec()), "vector[nodes](vector[3](float))");
  EXPECT_EQ(bin(Op::Add, sysmat(), sysmat()), "tensor[nodes,nodes](tensor[3,3](float))");
  EXPECT_EQ(bin(Op::Sub, col(generic(N)), col(generic(N))), "vector[N](float)");
}

TEST_F(OpTypingTest, ElementwiseBroadcastsScalars) {
  EXPECT_EQ(bin(Op::Add, f(), col(3)), "vector[3](float)");
  EXPECT_EQ(bin(Op::Sub, row(3, i()), i()), "vector[3](int)'");
  EXPECT_EQ(bin(Op::ElemMul, f(), sysmat()), "tensor[nodes,nodes](tensor[3,3](float))");
  EXPECT_EQ(bin(Op::ElemDiv, sysmat(), f()), "tensor[nodes,nodes](tensor[3,3](float))");
  EXPECT_EQ(bin(Op::Add, sysvec(), f()), "vector[nodes](vector[3](float))");
  EXPECT_EQ(bin(Op::Add, c(), mat(2, 2, c())), "tensor[2,2](complex)");
}

TEST_F(OpTypingTest, StringConcatenationOnlyWithPlus) {
  EXPECT_EQ(bin(Op::Add, s(), s()), "string");
  EXPECT_EQ(bin_kind(Op::Sub, s(), s()), K::Type);
  EXPECT_EQ(bin_kind(Op::Add, s(), i()), K::Type);
  EXPECT_EQ(bin_kind(Op::ElemMul, s(), s()), K::Type);
}

TEST_F(OpTypingTest, ElementwiseRejections) {
  EXPECT_EQ(bin_kind(Op::Add, i(), f()), K::Type);
  EXPECT_EQ(bin_kind(Op::Add, col(3, i()), col(3)), K::Type);
  EXPECT_EQ(bin_kind(Op::Add, b(), b()), K::Type);
  EXPECT_EQ(bin_kind(Op::Add, element(&node), f()), K::Type);
  EXPECT_EQ(bin_kind(Op::Add, make_opaque(), make_opaque()), K::Type);
  EXPECT_EQ(bin_kind(Op::Add, col(3), col(4)), K::Dimension);
  EXPECT_EQ(bin_kind(Op::Add, col(3), mat(3, 1)), K::Dimension);
  EXPECT_EQ(bin_kind(Op::Add, col(V()), col(P())), K::Dimension);
  EXPECT_EQ(bin_kind(Op::Sub, mat(generic(N), generic(N)), mat(generic(M), generic(M))),
            K::Dimension);
  EXPECT_EQ(bin_kind(Op::Add, sysvec(), col(V())), K::Dimension);
  EXPECT_EQ(bin_kind(Op::ElemMul, col(3), row(3)), K::Type);  // orientation only
  EXPECT_EQ(bin_kind(Op::Add, sysvec(), row(V(), col(3))), K::Type);
}

TEST_F(OpTypingTest, ScalarPlusSystemMatrixIsRejected) {
  EXPECT_EQ(bin_kind(Op::Add, f(), sysmat()), K::Type);
  EXPECT_EQ(bin_kind(Op::Sub, mat(V(), V()), f()), K::Type);
  EXPECT_EQ(bin(Op::Add, f(), mat(3, 3)), "tensor[3,3](float)");
}

TEST_F(OpTypingTest, VoidAndMultiOperandsAreErrors) {
  EXPECT_EQ(bin_kind(Op::Add, make_void(), f()), K::Type);
  EXPECT_EQ(bin_kind(Op::Mul, f(), make_multi({f(), f()})), K::Type);
  EXPECT_FALSE(type_unary(ast::Unary::Op::Neg, *make_void()).ok());
  EXPECT_FALSE(type_transpose(*make_multi({f(), f()})).ok());
  EXPECT_FALSE(type_compare(Cmp::Eq, *make_void(), *make_void()).ok());
}

// ---------------------------------------------------------------------------
// *

TEST_F(OpTypingTest, MultiplyByScalar) {
  EXPECT_EQ(bin(Op::Mul, f(), f()), "float");
  EXPECT_EQ(bin(Op::Mul, f(), row(3)), "vector[3](float)'");
  EXPECT_EQ(bin(Op::Mul, sysmat(), f()), "tensor[nodes,nodes](tensor[3,3](float))");
  EXPECT_EQ(bin(Op::Mul, i(), make_tensor({fixed(2), fixed(2), fixed(2)}, i())),
            "tensor[2,2,2](int)");
}

TEST_F(OpTypingTest, VectorProducts) {
  EXPECT_EQ(bin(Op::Mul, row(3), col(3)), "float");
  EXPECT_EQ(bin(Op::Mul, col(3), row(2)), "tensor[3,2](float)");
  EXPECT_EQ(bin(Op::Mul, row(V()), col(V())), "float");
  EXPECT_EQ(bin(Op::Mul, row(V(), col(3)), sysvec()), "float");
  EXPECT_EQ(bin(Op::Mul, row(2, c()), col(2, c())), "complex");
  EXPECT_EQ(bin(Op::Mul, col(2, col(3)), row(4, col(2))), "tensor[2,4](tensor[3,2](float))");
}

TEST_F(OpTypingTest, VectorProductRejections) {
  EXPECT_EQ(bin_kind(Op::Mul, row(3), row(3)), K::Type);
  EXPECT_EQ(bin_kind(Op::Mul, col(3), col(3)), K::Type);
  EXPECT_EQ(bin_kind(Op::Mul, row(2), col(3)), K::Dimension);
  EXPECT_EQ(bin_kind(Op::Mul, row(V()), col(P())), K::Dimension);
  EXPECT_EQ(bin_kind(Op::Mul, row(V(), col(3)), col(V())), K::Dimension);
  EXPECT_EQ(bin_kind(Op::Mul, row(V(), col(3)), col(V(), col(2))), K::Dimension);
  // `u * v'` of global vectors would be a dense S x S matrix.
  EXPECT_EQ(bin_kind(Op::Mul, col(V()), row(V())), K::Type);
  EXPECT_EQ(bin_kind(Op::Mul, col(3), row(V())), K::Type);
}

TEST_F(OpTypingTest, MatrixProducts) {
  EXPECT_EQ(bin(Op::Mul, mat(2, 3), col(3)), "vector[2](float)");
  EXPECT_EQ(bin(Op::Mul, row(2), mat(2, 3)), "vector[3](float)'");
  EXPECT_EQ(bin(Op::Mul, mat(2, 3), mat(3, 4)), "tensor[2,4](float)");
  EXPECT_EQ(bin(Op::Mul, sysmat(), sysvec()), "vector[nodes](vector[3](float))");
  EXPECT_EQ(bin(Op::Mul, row(V(), col(3)), sysmat()), "vector[nodes](vector[3](float))'");
  EXPECT_EQ(bin(Op::Mul, sysmat(), sysmat()), "tensor[nodes,nodes](tensor[3,3](float))");
  EXPECT_EQ(bin(Op::Mul, mat(V(), P()), col(P())), "vector[nodes](float)");
  EXPECT_EQ(bin(Op::Mul, mat(V(), P(), mat(2, 3)), mat(P(), V(), mat(3, 2))),
            "tensor[nodes,nodes](tensor[2,2](float))");
  EXPECT_EQ(bin(Op::Mul, mat(generic(N), generic(M)), col(generic(M))), "vector[N](float)");
}

TEST_F(OpTypingTest, MatrixProductRejections) {
  EXPECT_EQ(bin_kind(Op::Mul, mat(2, 3), col(2)), K::Dimension);
  EXPECT_EQ(bin_kind(Op::Mul, row(3), mat(2, 3)), K::Dimension);
  EXPECT_EQ(bin_kind(Op::Mul, mat(2, 3), mat(2, 3)), K::Dimension);
  EXPECT_EQ(bin_kind(Op::Mul, mat(2, 3), row(3)), K::Type);
  EXPECT_EQ(bin_kind(Op::Mul, col(2), mat(2, 3)), K::Type);
  // Blocking must agree: a 3x3-blocked matrix needs 3-blocked vectors.
  EXPECT_EQ(bin_kind(Op::Mul, sysmat(), col(V())), K::Dimension);
  EXPECT_EQ(bin_kind(Op::Mul, sysmat(), col(V(), col(2))), K::Dimension);
  EXPECT_EQ(bin_kind(Op::Mul, mat(V(), V()), sysvec()), K::Dimension);
  EXPECT_EQ(bin_kind(Op::Mul, sysmat(), col(P(), col(3))), K::Dimension);
  EXPECT_EQ(bin_kind(Op::Mul, mat(generic(N), generic(N)), col(generic(M))), K::Dimension);
}

TEST_F(OpTypingTest, MultiplyOperandRules) {
  EXPECT_EQ(bin_kind(Op::Mul, f(), i()), K::Type);
  EXPECT_EQ(bin_kind(Op::Mul, mat(2, 2), col(2, i())), K::Type);
  EXPECT_EQ(bin_kind(Op::Mul, b(), b()), K::Type);
  EXPECT_EQ(bin_kind(Op::Mul, s(), f()), K::Type);
  TypeRef t3 = make_tensor({fixed(2), fixed(2), fixed(2)}, f());
  EXPECT_EQ(bin_kind(Op::Mul, t3, col(2)), K::Type);
  EXPECT_EQ(bin_kind(Op::Mul, mat(2, 2), t3), K::Type);
}

// ---------------------------------------------------------------------------
// / \ ^ and or xor

TEST_F(OpTypingTest, Division) {
  EXPECT_EQ(bin(Op::Div, f(), f()), "float");
  EXPECT_EQ(bin(Op::Div, i(), i()), "int");
  EXPECT_EQ(bin(Op::Div, c(), c()), "complex");
  EXPECT_EQ(bin(Op::Div, sysvec(), f()), "vector[nodes](vector[3](float))");
  EXPECT_EQ(bin(Op::Div, f(), row(3)), "vector[3](float)'");
  EXPECT_EQ(bin_kind(Op::Div, col(3), col(3)), K::Type);
  EXPECT_EQ(bin_kind(Op::Div, f(), b()), K::Type);
  EXPECT_EQ(bin_kind(Op::Div, col(3, i()), f()), K::Type);
}

TEST_F(OpTypingTest, Solve) {
  EXPECT_EQ(bin(Op::LeftDiv, mat(3, 3), col(3)), "vector[3](float)");
  EXPECT_EQ(bin(Op::LeftDiv, mat(V(), V()), col(V())), "vector[nodes](float)");
  EXPECT_EQ(bin(Op::LeftDiv, sysmat(), sysvec()), "vector[nodes](vector[3](float))");
  EXPECT_EQ(bin(Op::LeftDiv, mat(V(), P(), mat(3, 2)), col(V(), col(3))),
            "vector[points](vector[2](float))");
  EXPECT_EQ(bin(Op::LeftDiv, mat(2, 2, c()), col(2, c())), "vector[2](complex)");
}

TEST_F(OpTypingTest, SolveRejections) {
  EXPECT_EQ(bin_kind(Op::LeftDiv, col(3), col(3)), K::Type);
  EXPECT_EQ(bin_kind(Op::LeftDiv, mat(3, 3), row(3)), K::Type);
  EXPECT_EQ(bin_kind(Op::LeftDiv, mat(3, 3), f()), K::Type);
  EXPECT_EQ(bin_kind(Op::LeftDiv, mat(3, 3, i()), col(3)), K::Type);
  EXPECT_EQ(bin_kind(Op::LeftDiv, mat(3, 3), col(2)), K::Dimension);
  EXPECT_EQ(bin_kind(Op::LeftDiv, mat(V(), V()), col(P())), K::Dimension);
  EXPECT_EQ(bin_kind(Op::LeftDiv, sysmat(), col(V())), K::Dimension);
}

TEST_F(OpTypingTest, PowerIsAPlainSemanticError) {
  Typing t = type_binary(Op::Pow, *f(), *f());
  EXPECT_FALSE(t.ok());
  EXPECT_EQ(t.kind, K::None);
  EXPECT_NE(t.error.find("pow"), std::string::npos);
}

TEST_F(OpTypingTest, BooleanOperators) {
  EXPECT_EQ(bin(Op::And, b(), b()), "bool");
  EXPECT_EQ(bin(Op::Or, b(), b()), "bool");
  EXPECT_EQ(bin(Op::Xor, b(), b()), "bool");
  EXPECT_EQ(bin_kind(Op::And, i(), i()), K::Type);
  EXPECT_EQ(bin_kind(Op::Or, b(), f()), K::Type);
  EXPECT_EQ(bin_kind(Op::Xor, col(2, b()), b()), K::Type);
}

// ---------------------------------------------------------------------------
// Unary, transpose, comparisons

TEST_F(OpTypingTest, UnaryOperators) {
  using U = ast::Unary::Op;
  EXPECT_EQ(spell(type_unary(U::Neg, *f())), "float");
  EXPECT_EQ(spell(type_unary(U::Neg, *sysmat())), "tensor[nodes,nodes](tensor[3,3](float))");
  EXPECT_EQ(spell(type_unary(U::Plus, *row(3, c()))), "vector[3](complex)'");
  EXPECT_EQ(spell(type_unary(U::Not, *b())), "bool");
  EXPECT_EQ(type_unary(U::Neg, *b()).kind, K::Type);
  EXPECT_EQ(type_unary(U::Plus, *s()).kind, K::Type);
  EXPECT_EQ(type_unary(U::Not, *i()).kind, K::Type);
  EXPECT_EQ(type_unary(U::Not, *col(2, b())).kind, K::Type);
}

TEST_F(OpTypingTest, Transpose) {
  EXPECT_EQ(spell(type_transpose(*f())), "float");
  EXPECT_EQ(spell(type_transpose(*col(3))), "vector[3](float)'");
  EXPECT_EQ(spell(type_transpose(*row(3))), "vector[3](float)");
  EXPECT_EQ(spell(type_transpose(*sysvec())), "vector[nodes](vector[3](float))'");
  EXPECT_EQ(spell(type_transpose(*mat(2, 3))), "tensor[3,2](float)");
  EXPECT_EQ(spell(type_transpose(*mat(V(), P(), mat(2, 3, i())))),
            "tensor[points,nodes](tensor[3,2](int))");
  EXPECT_EQ(type_transpose(*make_tensor({fixed(2), fixed(2), fixed(2)}, f())).kind, K::Type);
  EXPECT_EQ(type_transpose(*element(&node)).kind, K::Type);
}

TEST_F(OpTypingTest, Comparisons) {
  EXPECT_EQ(spell(type_compare(Cmp::Lt, *f(), *f())), "bool");
  EXPECT_EQ(spell(type_compare(Cmp::Ge, *i(), *i())), "bool");
  EXPECT_EQ(spell(type_compare(Cmp::Le, *s(), *s())), "bool");
  EXPECT_EQ(spell(type_compare(Cmp::Eq, *b(), *b())), "bool");
  EXPECT_EQ(spell(type_compare(Cmp::Ne, *c(), *c())), "bool");
  EXPECT_EQ(type_compare(Cmp::Lt, *b(), *b()).kind, K::Type);
  EXPECT_EQ(type_compare(Cmp::Gt, *c(), *c()).kind, K::Type);
  EXPECT_EQ(type_compare(Cmp::Eq, *i(), *f()).kind, K::Type);
  EXPECT_EQ(type_compare(Cmp::Eq, *col(3), *col(3)).kind, K::Type);
  EXPECT_EQ(type_compare(Cmp::Eq, *element(&node), *element(&node)).kind, K::Type);
}

// ---------------------------------------------------------------------------
// Intrinsics

class IntrinsicTest : public OpTypingTest {
 protected:
  Typing call(const char* name, std::vector<TypeRef> args, std::vector<IndexSet> generics = {}) {
    std::optional<Intrinsic> id = find_intrinsic(name);
    EXPECT_TRUE(id.has_value()) << name;
    std::vector<const Type*> ptrs;
    for (const TypeRef& a : args) ptrs.push_back(a.get());
    return type_intrinsic_call(id.value_or(Intrinsic::None), ptrs, generics, bindings);
  }
  std::string ok(const char* name, std::vector<TypeRef> args, std::vector<IndexSet> generics = {}) {
    return spell(call(name, std::move(args), std::move(generics)));
  }
  K fails(const char* name, std::vector<TypeRef> args, std::vector<IndexSet> generics = {}) {
    Typing t = call(name, std::move(args), std::move(generics));
    EXPECT_FALSE(t.ok()) << name << " gave " << to_string(*t.type);
    return t.kind;
  }
  std::vector<IndexSet> bindings;
};

TEST_F(IntrinsicTest, NamesRoundTrip) {
  EXPECT_EQ(find_intrinsic("lusolve"), Intrinsic::LuSolve);
  EXPECT_EQ(find_intrinsic("triangularSolve"), Intrinsic::TriangularSolve);
  EXPECT_FALSE(find_intrinsic("solve").has_value());
  EXPECT_FALSE(find_intrinsic("").has_value());
  EXPECT_STREQ(intrinsic_name(Intrinsic::ComplexConj), "complexConj");
  EXPECT_STREQ(intrinsic_name(Intrinsic::Mod), "mod");
}

TEST_F(IntrinsicTest, ScalarMath) {
  EXPECT_EQ(ok("mod", {i(), i()}), "int");
  EXPECT_EQ(ok("sin", {f()}), "float");
  EXPECT_EQ(ok("atan2", {f(), f()}), "float");
  EXPECT_EQ(ok("pow", {f(), f()}), "float");
  EXPECT_EQ(ok("abs", {f()}), "float");
  EXPECT_EQ(ok("clock", {}), "float");
  EXPECT_EQ(ok("storeTime", {i(), f()}), "float");
  EXPECT_TRUE(bindings.empty());
  EXPECT_EQ(fails("mod", {f(), f()}), K::Type);
  EXPECT_EQ(fails("abs", {i()}), K::Type);
  EXPECT_EQ(fails("max", {i(), i()}), K::Type);
  EXPECT_EQ(fails("sqrt", {col(3)}), K::Type);
  EXPECT_EQ(fails("storeTime", {f(), f()}), K::Type);
}

TEST_F(IntrinsicTest, ArityErrors) {
  Typing t = call("sin", {f(), f()});
  EXPECT_EQ(t.kind, K::Arity);
  EXPECT_EQ(t.error, "passed in 2 arguments but function 'sin' expects 1");
  EXPECT_EQ(fails("clock", {f()}), K::Arity);
  EXPECT_EQ(fails("dot", {col(3)}), K::Arity);
  EXPECT_EQ(fails("sin", {f()}, {fixed(3)}), K::Arity);
  EXPECT_EQ(fails("lu", {mat(3, 3)}, {fixed(3), fixed(3)}), K::Arity);
}

TEST_F(IntrinsicTest, VoidAndMultiArgumentsAreErrors) {
  EXPECT_EQ(fails("sin", {make_void()}), K::Type);
  EXPECT_EQ(fails("sin", {make_multi({f(), f()})}), K::Type);
}

TEST_F(IntrinsicTest, SmallDenseLinearAlgebra) {
  EXPECT_EQ(ok("det", {mat(3, 3)}), "float");
  EXPECT_EQ(ok("det2", {mat(2, 2)}), "float");
  EXPECT_EQ(ok("det4", {mat(4, 4)}), "float");
  EXPECT_EQ(ok("inv", {mat(3, 3)}), "tensor[3,3](float)");
  EXPECT_EQ(ok("inv2", {mat(2, 2)}), "tensor[2,2](float)");
  EXPECT_EQ(ok("inv4", {mat(4, 4)}), "tensor[4,4](float)");
  EXPECT_EQ(ok("cross", {col(3), col(3)}), "vector[3](float)");
  EXPECT_EQ(fails("det", {mat(2, 2)}), K::Type);
  EXPECT_EQ(fails("inv2", {mat(3, 3)}), K::Type);
  EXPECT_EQ(fails("det", {mat(3, 3, i())}), K::Type);
  EXPECT_EQ(fails("det", {f()}), K::Type);
  EXPECT_EQ(fails("cross", {row(3), col(3)}), K::Type);
  EXPECT_EQ(fails("cross", {col(3), col(2)}), K::Type);
}

TEST_F(IntrinsicTest, NormAndDot) {
  EXPECT_EQ(ok("norm", {col(3)}), "float");
  EXPECT_EQ(ok("norm", {row(3)}), "float");
  EXPECT_EQ(ok("norm", {sysvec()}), "float");
  EXPECT_EQ(ok("norm", {col(generic(N))}), "float");
  EXPECT_EQ(fails("norm", {mat(3, 3)}), K::Type);
  EXPECT_EQ(fails("norm", {f()}), K::Type);
  EXPECT_EQ(fails("norm", {col(3, i())}), K::Type);
  EXPECT_EQ(fails("norm", {col(3, b())}), K::Type);

  EXPECT_EQ(ok("dot", {col(3), col(3)}), "float");
  EXPECT_EQ(ok("dot", {row(3), col(3)}), "float");
  EXPECT_EQ(ok("dot", {sysvec(), row(V(), col(3))}), "float");
  EXPECT_EQ(fails("dot", {col(3), col(4)}), K::Type);
  EXPECT_EQ(fails("dot", {col(V()), col(P())}), K::Type);
  EXPECT_EQ(fails("dot", {sysvec(), col(V())}), K::Type);
  EXPECT_EQ(fails("dot", {mat(3, 3), mat(3, 3)}), K::Type);
  EXPECT_EQ(fails("dot", {col(3, i()), col(3, i())}), K::Type);
  EXPECT_EQ(fails("dot", {col(3), col(3, i())}), K::Type);
}

TEST_F(IntrinsicTest, ComplexHelpers) {
  EXPECT_EQ(ok("createComplex", {f(), f()}), "complex");
  EXPECT_EQ(ok("complexGetReal", {c()}), "float");
  EXPECT_EQ(ok("complexGetImag", {c()}), "float");
  EXPECT_EQ(ok("complexNorm", {c()}), "float");
  EXPECT_EQ(ok("complexConj", {c()}), "complex");
  EXPECT_EQ(fails("complexConj", {f()}), K::Type);
  EXPECT_EQ(fails("createComplex", {i(), i()}), K::Type);
}

TEST_F(IntrinsicTest, Factorizations) {
  EXPECT_EQ(ok("lu", {mat(V(), V())}), "opaque");
  ASSERT_EQ(bindings.size(), 1u);
  EXPECT_EQ(bindings[0], V());
  EXPECT_EQ(ok("chol", {mat(V(), P())}), "opaque");  // squareness is not checked
  EXPECT_EQ(ok("chol", {mat(3, 3)}, {fixed(3)}), "opaque");
  EXPECT_EQ(ok("lu", {mat(V(), V())}, {P()}), "opaque");
  EXPECT_EQ(bindings[0], P());  // explicit arguments win
  EXPECT_EQ(fails("lu", {col(V())}), K::Type);
  EXPECT_EQ(fails("lu", {mat(V(), V(), b())}), K::Type);
  EXPECT_EQ(fails("chol", {mat(3, 3, i())}), K::Type);
  EXPECT_EQ(ok("lufree", {make_opaque()}), "void");
  EXPECT_EQ(ok("cholfree", {make_opaque()}), "void");
  EXPECT_EQ(fails("lufree", {mat(3, 3)}), K::Type);
}

TEST_F(IntrinsicTest, VectorSolvesNeedExplicitResultDimension) {
  EXPECT_EQ(ok("lusolve", {make_opaque(), col(V())}, {V(), V()}), "vector[nodes](float)");
  ASSERT_EQ(bindings.size(), 2u);
  EXPECT_EQ(bindings[0], V());
  EXPECT_EQ(bindings[1], V());
  // The right-hand side is not compared with the bound N (§9.5).
  EXPECT_EQ(ok("lltsolve", {make_opaque(), col(V())}, {P(), P()}), "vector[points](float)");
  EXPECT_EQ(bindings[0], P());
  EXPECT_EQ(ok("lusolve", {make_opaque(), row(3, i())}, {fixed(3), fixed(4)}), "vector[4](float)");

  Typing t = call("lusolve", {make_opaque(), col(V())}, {V()});
  EXPECT_EQ(t.kind, K::GenericUnresolved);
  EXPECT_EQ(t.error, "unable to resolve type parameter 'M' for call to function 'lusolve'");
  EXPECT_EQ(fails("lltsolve", {make_opaque(), col(V())}), K::GenericUnresolved);
  EXPECT_EQ(fails("lusolve", {col(V()), col(V())}, {V(), V()}), K::Type);
  EXPECT_EQ(fails("lusolve", {make_opaque(), mat(V(), V())}, {V(), V()}), K::Type);
  EXPECT_EQ(fails("lusolve", {make_opaque(), col(V())}, {V(), V(), V()}), K::Arity);
}

TEST_F(IntrinsicTest, MatrixSolves) {
  EXPECT_EQ(ok("lumatsolve", {make_opaque(), mat(V(), P())}, {V(), P(), V()}),
            "tensor[nodes,points](float)");
  EXPECT_EQ(ok("lltmatsolve", {make_opaque(), mat(V(), P())}, {V(), P(), P()}),
            "tensor[points,points](float)");
  ASSERT_EQ(bindings.size(), 3u);
  EXPECT_EQ(bindings[2], P());
  EXPECT_EQ(fails("lumatsolve", {make_opaque(), mat(V(), P())}, {V(), P()}), K::GenericUnresolved);
  EXPECT_EQ(fails("lltmatsolve", {make_opaque(), col(V())}, {V(), P(), V()}), K::Type);
  EXPECT_EQ(fails("lltmatsolve", {f(), mat(V(), P())}, {V(), P(), V()}), K::Type);
}

TEST_F(IntrinsicTest, TriangularSolveDeducesFromTheMatrix) {
  EXPECT_EQ(ok("triangularSolve", {mat(V(), P()), col(V())}), "vector[points](float)");
  ASSERT_EQ(bindings.size(), 2u);
  EXPECT_EQ(bindings[0], V());
  EXPECT_EQ(bindings[1], P());
  EXPECT_EQ(ok("triangularSolve", {mat(3, 3), col(3)}), "vector[3](float)");
  EXPECT_EQ(fails("triangularSolve", {mat(V(), V()), col(P())}), K::Type);
  EXPECT_EQ(fails("triangularSolve", {mat(V(), V()), row(V())}), K::Type);
  EXPECT_EQ(fails("triangularSolve", {mat(V(), V(), mat(3, 3)), sysvec()}), K::Type);
  EXPECT_EQ(fails("triangularSolve", {mat(3, 3, i()), col(3)}), K::Type);
  // Explicit arguments are bound first, then checked against the actual matrix.
  EXPECT_EQ(fails("triangularSolve", {mat(V(), V()), col(V())}, {P()}), K::Type);
  EXPECT_EQ(fails("triangularSolve", {f(), col(V())}), K::GenericUnresolved);
}

}  // namespace
}  // namespace simit::frontend
