// Debugger expressions: the variables visible at a point of a function, and expressions
// checked there by the real checker with the debugger's differences (elements compare as
// indices, ints index sets, calls of user functions refused).
#include "frontend/debug_expr.h"

#include <gtest/gtest.h>

#include <algorithm>

#include "frontend/frontend.h"

namespace simit::frontend {
namespace {

const char* const kSource =
    "element Vertex\n"                                                // 1
    "  x : vector[3](float);\n"                                       // 2
    "end\n"                                                           // 3
    "extern verts : set{Vertex};\n"                                   // 4
    "extern edges : set{Vertex}(verts, verts);\n"                     // 5
    "func twice(a : float) -> b : float\n"                            // 6
    "  b = 2.0 * a;\n"                                                // 7
    "end\n"                                                           // 8
    "func f(e : Vertex, p : (Vertex * 2), s : float) -> r : float\n"  // 9
    "  u = s + 1.0;\n"                                                // 10
    "  for i in 0:3\n"                                                // 11
    "    w = u * 2.0;\n"                                              // 12
    "    r = r + w;\n"                                                // 13
    "  end\n"                                                         // 14
    "  if u > 0.0\n"                                                  // 15
    "    var u : int = 3;\n"                                          // 16
    "    r = r + twice(s);\n"                                         // 17
    "  end\n"                                                         // 18
    "end\n";                                                          // 19

class DebugExpr : public ::testing::Test {
 protected:
  void SetUp() override {
    c_ = compile_source("debug.sim", kSource);
    ASSERT_TRUE(c_->ok()) << c_->diagnostics.render_all();
    f_ = c_->program->find_func("f");
  }
  // The byte offset of the first statement on `line` (its begin) or, with `after`, its end.
  uint32_t at(int line, bool after = false) const {
    const ast::Stmt* found = nullptr;
    std::vector<const ast::Block*> blocks{&f_->body};
    while (!blocks.empty() && !found) {
      const ast::Block* b = blocks.back();
      blocks.pop_back();
      for (const auto& s : *b) {
        if (s->span.start().line == line) found = s.get();
        if (const auto* r = s->as<ast::ForRange>()) blocks.push_back(&r->body);
        if (const auto* i = s->as<ast::If>())
          for (const auto& br : i->branches) blocks.push_back(&br);
      }
    }
    EXPECT_NE(found, nullptr) << "no statement on line " << line;
    return after ? found->span.end : found->span.begin;
  }
  std::vector<std::string> names(uint32_t offset) const {
    std::vector<std::string> out;
    for (const ast::Variable* v : visible_variables(*f_, offset)) out.push_back(v->name);
    return out;
  }
  std::string type_of(const std::string& text, uint32_t offset) const {
    DebugExpression e = check_debug_expression(*c_->program, f_, offset, text);
    return e.ok() ? to_string(*e.expr->type) : "error: " + e.error;
  }

  std::unique_ptr<Compilation> c_;
  const ast::FuncDecl* f_ = nullptr;
};

using Names = std::vector<std::string>;

TEST_F(DebugExpr, VisibleVariablesFollowTheScopes) {
  EXPECT_EQ(names(at(10)), (Names{"e", "p", "s", "r"}));
  EXPECT_EQ(names(at(10, true)), (Names{"e", "p", "s", "r", "u"}));
  EXPECT_EQ(names(at(11)), (Names{"e", "p", "s", "r", "u"}));  // not i before the loop starts
  EXPECT_EQ(names(at(12)), (Names{"e", "p", "s", "r", "u", "i"}));
  EXPECT_EQ(names(at(13)), (Names{"e", "p", "s", "r", "u", "i", "w"}));
  EXPECT_EQ(names(at(15)), (Names{"e", "p", "s", "r", "u"}));  // the loop's names are gone
  // Inside the `if`, the inner `u` comes last and hides the outer one.
  EXPECT_EQ(names(at(17)), (Names{"e", "p", "s", "r", "u", "u"}));
}

TEST_F(DebugExpr, ExpressionsAreTypedInTheirScope) {
  EXPECT_EQ(type_of("u * 2.0", at(12)), "float");
  EXPECT_EQ(type_of("u", at(17)), "int");  // the inner declaration
  EXPECT_EQ(type_of("p(1).x", at(10)), "vector[3](float)");
  EXPECT_EQ(type_of("norm(p(0).x - e.x)", at(10)), "float");
  EXPECT_EQ(type_of("verts.x", at(10)), "vector[verts](vector[3](float))");
  EXPECT_EQ(type_of("u", at(10)), "error: undeclared variable or constant 'u'");
  EXPECT_EQ(type_of("w", at(15)), "error: undeclared variable or constant 'w'");
  EXPECT_EQ(type_of("1 +", at(10)), "error: expected an expression but got end of file");
  EXPECT_EQ(type_of("s s", at(10)),
            "error: expected the end of the expression but got identifier 's'");
  EXPECT_EQ(type_of("e + 1", at(10)).rfind("error: ", 0), 0u);
}

TEST_F(DebugExpr, ElementsCompareAsIndicesAndIntsIndexSets) {
  EXPECT_EQ(type_of("e == 17", at(10)), "bool");
  EXPECT_EQ(type_of("17 != e", at(10)), "bool");
  EXPECT_EQ(type_of("p(0) < p(1)", at(10)), "bool");
  EXPECT_EQ(type_of("verts.x(3)", at(10)), "vector[3](float)");
  EXPECT_EQ(type_of("e == 1.5", at(10)).rfind("error: ", 0), 0u);
}

TEST_F(DebugExpr, CallsOfUserFunctionsAreRefused) {
  EXPECT_EQ(type_of("twice(s)", at(10)),
            "error: calls of user functions ('twice') are not supported in debugger expressions");
  EXPECT_EQ(type_of("sqrt(s) + det([1.0, 0.0, 0.0; 0.0, 1.0, 0.0; 0.0, 0.0, 2.0])", at(10)),
            "float");
}

TEST_F(DebugExpr, WithoutAFunctionOnlyGlobalsAreVisible) {
  DebugExpression e = check_debug_expression(*c_->program, nullptr, 0, "verts.x(0)");
  ASSERT_TRUE(e.ok()) << e.error;
  EXPECT_FALSE(check_debug_expression(*c_->program, nullptr, 0, "s").ok());
}

}  // namespace
}  // namespace simit::frontend
