// Literal values of `%@` directives (LANGUAGE.md §2.6, §3.4, §6.2).
#include "testing/literal.h"

#include <gtest/gtest.h>

namespace simit::tools {
namespace {

using frontend::ScalarKind;

Literal ok(const char* text) {
  LiteralResult r = parse_literal(text);
  EXPECT_TRUE(r.literal) << text << ": " << r.error;
  return r.literal ? *r.literal : Literal{};
}

std::string error_of(const char* text) {
  LiteralResult r = parse_literal(text);
  EXPECT_FALSE(r.literal) << text;
  return r.error;
}

TEST(Literal, Scalars) {
  EXPECT_EQ(ok("42").ints, std::vector<long long>{42});
  EXPECT_EQ(ok("-3").ints, std::vector<long long>{-3});
  EXPECT_EQ(ok("--+-1.5").floats, std::vector<double>{-1.5});
  EXPECT_EQ(ok("2e3").floats, std::vector<double>{2000.0});
  EXPECT_EQ(ok("1E-3").kind, ScalarKind::Float);
  Literal t = ok("true");
  EXPECT_EQ(t.kind, ScalarKind::Bool);
  EXPECT_EQ(t.ints, std::vector<long long>{1});
  EXPECT_EQ(ok("false").ints, std::vector<long long>{0});
  Literal c = ok("<1.5, -0.25>");
  EXPECT_EQ(c.kind, ScalarKind::Complex);
  EXPECT_EQ(c.complexes[0], std::complex<double>(1.5, -0.25));
  Literal s = ok(R"("a\tb\"c")");
  EXPECT_EQ(s.kind, ScalarKind::String);
  EXPECT_EQ(s.string_value, "a\tb\"c");
  EXPECT_TRUE(ok("7").is_scalar());
  EXPECT_EQ(ok("  7  ").text, "  7  ");
}

TEST(Literal, DenseRowsAndOrientation) {
  Literal row = ok("[1.0, 2.0, 3.0]");
  EXPECT_EQ(row.shape, std::vector<int>{3});
  EXPECT_FALSE(row.column);
  EXPECT_TRUE(ok("[1.0, 2.0]'").column);
  EXPECT_FALSE(ok("[1.0, 2.0]''").column);
  Literal m = ok("[1, 2, 3; 4, 5, 6]");
  EXPECT_EQ(m.shape, (std::vector<int>{2, 3}));
  EXPECT_EQ(m.ints, (std::vector<long long>{1, 2, 3, 4, 5, 6}));
  EXPECT_EQ(ok("[4.0; 5.0]").shape, (std::vector<int>{2, 1}));
  EXPECT_EQ(ok("[7]").shape, std::vector<int>{7 / 7});
  EXPECT_EQ(ok("[1 -2 +3]").ints, (std::vector<long long>{1, -2, 3}));
  EXPECT_EQ(ok("-[1, -2]").ints, (std::vector<long long>{-1, 2}));
  EXPECT_EQ(ok("5'").ints, std::vector<long long>{5});
}

TEST(Literal, NestedDense) {
  Literal m = ok("[[1, 2], [3, 4]]");
  EXPECT_EQ(m.shape, (std::vector<int>{2, 2}));
  EXPECT_EQ(m.ints, (std::vector<long long>{1, 2, 3, 4}));
  EXPECT_EQ(ok("[[1.0]]").shape, (std::vector<int>{1, 1}));
  EXPECT_EQ(ok("[[1.0, 2.0; 3.0, 4.0] [5.0, 6.0; 7.0, 8.0]]").shape, (std::vector<int>{2, 2, 2}));
  Literal c = ok("[<1.0,0.0>, <0.0,1.0>]'");
  EXPECT_EQ(c.kind, ScalarKind::Complex);
  EXPECT_TRUE(c.column);
}

TEST(Literal, Errors) {
  EXPECT_NE(error_of("1 + 1").find("after the literal"), std::string::npos);
  EXPECT_NE(error_of("[1, 2; 3]").find("mismatched dimension sizes"), std::string::npos);
  EXPECT_NE(error_of("[1, 2.0]").find("mixed element types"), std::string::npos);
  EXPECT_NE(error_of("[1, 2; 3.0, 4.0]").find("mismatched element types"), std::string::npos);
  EXPECT_NE(error_of("[[1, 2], [3]]").find("mismatched dimension sizes"), std::string::npos);
  EXPECT_NE(error_of("[1, 2; 3, 4]'").find("transposed matrix"), std::string::npos);
  EXPECT_NE(error_of("<1, 2>").find("must be floats"), std::string::npos);
  EXPECT_NE(error_of("x").find("not a literal"), std::string::npos);
  EXPECT_NE(error_of("-true").find("sign"), std::string::npos);
  EXPECT_NE(error_of("1.").find("digit"), std::string::npos);
  EXPECT_NE(error_of("1e").find("exponent"), std::string::npos);
  EXPECT_NE(error_of("2147483648").find("out of range"), std::string::npos);
  EXPECT_NE(error_of("\"abc").find("unclosed"), std::string::npos);
  EXPECT_NE(error_of("\"\\q\"").find("escape"), std::string::npos);
  EXPECT_NE(error_of("[]").find("empty"), std::string::npos);
  EXPECT_NE(error_of("").find("missing"), std::string::npos);
  EXPECT_NE(error_of("[1, 2").find("expected ']'"), std::string::npos);
}

TEST(Literal, NestingIsLimited) {
  // 64 levels are read (a shape of 64 ones); 100,000 are refused without recursing into them.
  Literal deep = ok((std::string(64, '[') + "1" + std::string(64, ']')).c_str());
  EXPECT_EQ(deep.shape, std::vector<int>(64, 1));
  std::string text = std::string(100000, '[') + "1" + std::string(100000, ']');
  EXPECT_EQ(error_of(text.c_str()), "bad literal '" + std::string(60, '[') +
                                        "...': a dense literal is nested more than 64 levels deep");
}

TEST(Literal, SplitTopLevel) {
  EXPECT_EQ(split_top_level("1.0, [1.0, 2.0], <1.0,2.0>, \"a,b\""),
            (std::vector<std::string>{"1.0", "[1.0, 2.0]", "<1.0,2.0>", "\"a,b\""}));
  EXPECT_EQ(split_top_level("(0,1), (1,2)"), (std::vector<std::string>{"(0,1)", "(1,2)"}));
  EXPECT_TRUE(split_top_level("   ").empty());
  EXPECT_EQ(split_top_level("a,,b"), (std::vector<std::string>{"a", "", "b"}));
  EXPECT_EQ(split_top_level(R"("x\",y", 2)"), (std::vector<std::string>{R"("x\",y")", "2"}));
}

}  // namespace
}  // namespace simit::tools
