// Unit tests of the lexer (LANGUAGE.md §2): token kinds, literal values, comments,
// line counting and every lexical error with its location.
#include <gtest/gtest.h>

#include <memory>
#include <string>
#include <vector>

#include "frontend/lexer.h"

namespace simit::frontend {
namespace {

struct Lexed {
  std::unique_ptr<SourceFile> file;
  Diagnostics diags;
  std::vector<Token> tokens;
};

std::unique_ptr<Lexed> lex_text(const std::string& text) {
  auto l = std::make_unique<Lexed>();
  l->file = std::make_unique<SourceFile>("test.sim", text);
  l->tokens = lex(*l->file, l->diags);
  return l;
}

// The kinds of all tokens but the final EndOfFile.
std::vector<TokenKind> kinds(const std::string& text) {
  auto l = lex_text(text);
  EXPECT_FALSE(l->diags.has_errors()) << l->diags.render_all();
  std::vector<TokenKind> out;
  for (const auto& t : l->tokens)
    if (t.kind != TokenKind::EndOfFile) out.push_back(t.kind);
  return out;
}

// "line:col message" of the first diagnostic.
std::string first_error(const std::string& text) {
  auto l = lex_text(text);
  if (!l->diags.has_errors()) return "no error";
  const Diagnostic& d = l->diags.items()[0];
  EXPECT_EQ(d.category, DiagCategory::Lexical);
  LineCol lc = d.span.start();
  return std::to_string(lc.line) + ":" + std::to_string(lc.column) + " " + d.message;
}

using K = TokenKind;

TEST(Lexer, EveryKeyword) {
#define SIMIT_CHECK_KEYWORD(name, spelling) \
  EXPECT_EQ(kinds(spelling), std::vector<K>{K::name}) << spelling;
  SIMIT_KEYWORD_TOKENS(SIMIT_CHECK_KEYWORD)
#undef SIMIT_CHECK_KEYWORD
}

TEST(Lexer, EveryPunctuation) {
#define SIMIT_CHECK_PUNCT(name, spelling) \
  EXPECT_EQ(kinds(spelling), std::vector<K>{K::name}) << spelling;
  SIMIT_PUNCT_TOKENS(SIMIT_CHECK_PUNCT)
#undef SIMIT_CHECK_PUNCT
}

TEST(Lexer, GreedyPunctuation) {
  EXPECT_EQ(kinds("a->b"), (std::vector<K>{K::Ident, K::Arrow, K::Ident}));
  EXPECT_EQ(kinds("x.*y"), (std::vector<K>{K::Ident, K::DotStar, K::Ident}));
  EXPECT_EQ(kinds("x./y"), (std::vector<K>{K::Ident, K::DotSlash, K::Ident}));
  EXPECT_EQ(kinds("a<=b>=c==d!=e"),
            (std::vector<K>{K::Ident, K::LessEq, K::Ident, K::GreaterEq, K::Ident, K::EqEq,
                            K::Ident, K::NotEq, K::Ident}));
  EXPECT_EQ(kinds("a- >b"), (std::vector<K>{K::Ident, K::Minus, K::Greater, K::Ident}));
  EXPECT_EQ(kinds("= ="), (std::vector<K>{K::Assign, K::Assign}));
  EXPECT_EQ(kinds(".5"), (std::vector<K>{K::Dot, K::IntLiteral}));
  EXPECT_EQ(kinds("e.f"), (std::vector<K>{K::Ident, K::Dot, K::Ident}));
}

TEST(Lexer, IdentifiersAreCaseSensitiveAndNeverKeywords) {
  auto l = lex_text("_a1 foo_bar If END proc x9");
  ASSERT_EQ(l->tokens.size(), 7u);
  for (int i = 0; i < 6; ++i) EXPECT_EQ(l->tokens[i].kind, K::Ident);
  EXPECT_EQ(l->tokens[0].text, "_a1");
  EXPECT_EQ(l->tokens[2].text, "If");
  EXPECT_EQ(l->tokens[6].kind, K::EndOfFile);
}

TEST(Lexer, IntegerLiterals) {
  auto l = lex_text("0 7 42 2147483647");
  ASSERT_FALSE(l->diags.has_errors());
  EXPECT_EQ(l->tokens[0].int_value, 0);
  EXPECT_EQ(l->tokens[1].int_value, 7);
  EXPECT_EQ(l->tokens[2].int_value, 42);
  EXPECT_EQ(l->tokens[3].int_value, 2147483647);
  for (int i = 0; i < 4; ++i) EXPECT_EQ(l->tokens[i].kind, K::IntLiteral);
}

TEST(Lexer, FloatLiterals) {
  auto l = lex_text("0.5 12.0 3e8 1E-3 2.5e+4 0.0");
  ASSERT_FALSE(l->diags.has_errors()) << l->diags.render_all();
  std::vector<double> want = {0.5, 12.0, 3e8, 1e-3, 2.5e4, 0.0};
  for (size_t i = 0; i < want.size(); ++i) {
    EXPECT_EQ(l->tokens[i].kind, K::FloatLiteral);
    EXPECT_DOUBLE_EQ(l->tokens[i].float_value, want[i]);
  }
}

TEST(Lexer, StringLiteralsDecodeEscapes) {
  auto l = lex_text(R"("a\tb\n\\\"\'\?\a\b\f\v\r" "")");
  ASSERT_FALSE(l->diags.has_errors()) << l->diags.render_all();
  EXPECT_EQ(l->tokens[0].kind, K::StringLiteral);
  EXPECT_EQ(l->tokens[0].string_value, std::string("a\tb\n\\\"'?\a\b\f\v\r"));
  EXPECT_EQ(l->tokens[1].string_value, "");
  EXPECT_EQ(l->tokens[0].text.front(), '"');
}

TEST(Lexer, Comments) {
  EXPECT_EQ(kinds("a % comment b\nc"), (std::vector<K>{K::Ident, K::Ident}));
  EXPECT_EQ(kinds("%% x\n%%% y\n%- z\na"), (std::vector<K>{K::Ident}));
  EXPECT_EQ(kinds("a %{ b \n c %} d"), (std::vector<K>{K::Ident, K::Ident}));
  // Block comments do not nest: the first `%}` closes.
  EXPECT_EQ(kinds("%{ %{ x %} y"), (std::vector<K>{K::Ident}));
  // `%{!` is an ordinary block comment (no multi-line tests).
  EXPECT_EQ(kinds("%{! f(1) == 2; !%} a"), (std::vector<K>{K::Ident}));
}

TEST(Lexer, TestLines) {
  EXPECT_EQ(kinds("%! f(1) == 2;"),
            (std::vector<K>{K::Test, K::Ident, K::LParen, K::IntLiteral, K::RParen, K::EqEq,
                            K::IntLiteral, K::Semicolon}));
  EXPECT_EQ(kinds("%%! f(1) == 2;"), std::vector<K>{});
}

TEST(Lexer, SpansAndLines) {
  auto l = lex_text("func\r\n  f\r(x)\n\n  y");
  ASSERT_FALSE(l->diags.has_errors());
  auto at = [&](size_t i) {
    LineCol lc = l->tokens[i].span.start();
    return std::to_string(lc.line) + ":" + std::to_string(lc.column);
  };
  EXPECT_EQ(at(0), "1:1");
  EXPECT_EQ(at(1), "2:3");
  EXPECT_EQ(at(2), "3:1");
  EXPECT_EQ(at(3), "3:2");
  EXPECT_EQ(at(5), "5:3");
  for (const auto& t : l->tokens) {
    EXPECT_EQ(t.span.file, l->file.get());
    EXPECT_EQ(l->file->text().substr(t.span.begin, t.span.end - t.span.begin), t.text);
  }
  EXPECT_EQ(l->tokens.back().kind, K::EndOfFile);
}

TEST(Lexer, EmptyInputGivesEndOfFile) {
  auto l = lex_text("");
  ASSERT_EQ(l->tokens.size(), 1u);
  EXPECT_EQ(l->tokens[0].kind, K::EndOfFile);
}

TEST(Lexer, UnexpectedSymbols) {
  EXPECT_EQ(first_error("a\n  @b"), "2:3 unexpected symbol '@'");
  EXPECT_EQ(first_error("x ! y"), "1:3 unexpected symbol '!'");
  EXPECT_EQ(first_error("#"), "1:1 unexpected symbol '#'");
  EXPECT_EQ(first_error("a $"), "1:3 unexpected symbol '$'");
  EXPECT_EQ(first_error("`"), "1:1 unexpected symbol '`'");
  EXPECT_EQ(first_error("a ? b"), "1:3 unexpected symbol '?'");
}

TEST(Lexer, MalformedNumbers) {
  EXPECT_EQ(first_error("x = 1.c;").substr(0, 26), "1:5 unexpected symbol '.' ");
  EXPECT_EQ(first_error("1.;").substr(0, 3), "1:1");
  EXPECT_EQ(first_error("1.e5").substr(0, 3), "1:1");
  EXPECT_EQ(first_error("\n3e"), "2:1 exponent of float literal has no digits");
  EXPECT_EQ(first_error("1e+;"), "1:1 exponent of float literal has no digits");
  EXPECT_EQ(first_error("2.5E-x"), "1:1 exponent of float literal has no digits");
  EXPECT_EQ(first_error("a 007"), "1:3 integer literal '007' has a leading zero");
  EXPECT_EQ(first_error("2147483648"), "1:1 integer literal '2147483648' is out of range");
}

TEST(Lexer, StringErrors) {
  EXPECT_EQ(first_error("x \"abc"), "1:3 unclosed string literal");
  EXPECT_EQ(first_error("\"ab\ncd\""), "1:1 unclosed string literal");
  EXPECT_EQ(first_error("  \"a\\qb\""), "1:5 unrecognized escape sequence '\\q'");
  EXPECT_EQ(first_error("\"\\x41\""), "1:2 unrecognized escape sequence '\\x'");
}

TEST(Lexer, CommentErrors) {
  EXPECT_EQ(first_error("a\n %{ never closed"), "2:2 unclosed comment");
  EXPECT_EQ(first_error("a %} b"), "1:3 '%}' without an open block comment");
}

TEST(Lexer, GoesOnAfterAnError) {
  auto l = lex_text("a @ b\nc \"x\\q\" d");
  EXPECT_EQ(l->diags.size(), 2u);
  std::vector<std::string> idents;
  for (const auto& t : l->tokens)
    if (t.kind == K::Ident) idents.emplace_back(t.text);
  EXPECT_EQ(idents, (std::vector<std::string>{"a", "b", "c", "d"}));
}

TEST(Lexer, TokenSpellings) {
  EXPECT_STREQ(token_spelling(K::KwFunc), "func");
  EXPECT_STREQ(token_spelling(K::DotStar), ".*");
  EXPECT_STREQ(token_spelling(K::Test), "%!");
  EXPECT_STREQ(token_spelling(K::Ident), "identifier");
  EXPECT_STREQ(token_spelling(K::EndOfFile), "end of file");
}

}  // namespace
}  // namespace simit::frontend
