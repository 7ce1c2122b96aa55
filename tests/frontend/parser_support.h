// What the parser's tests share (tests/frontend/parser_test.cpp, parser_recovery_test.cpp):
// a parsed text with its diagnostics, an expression parsed inside a function and printed back,
// and the location of the first syntax error.
#pragma once

#include <gtest/gtest.h>

#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "frontend/lexer.h"
#include "frontend/parser.h"
#include "frontend/printer.h"

namespace simit::frontend::parser_support {

using namespace ast;

struct Parsed {
  std::unique_ptr<SourceFile> file;
  Diagnostics diags;
  std::unique_ptr<Program> program;

  std::string errors() const { return diags.render_all(); }
  const FuncDecl& func(size_t i = 0) const {
    size_t seen = 0;
    for (const auto& d : program->decls)
      if (const auto* f = d->as<FuncDecl>(); f && seen++ == i) return *f;
    throw std::runtime_error("no such function");
  }
  // The last function's body.
  const Block& body() const {
    const FuncDecl* last = nullptr;
    for (const auto& d : program->decls)
      if (const auto* f = d->as<FuncDecl>()) last = f;
    if (!last) throw std::runtime_error("no function");
    return last->body;
  }
};

inline std::unique_ptr<Parsed> parse_text(const std::string& text) {
  auto p = std::make_unique<Parsed>();
  p->file = std::make_unique<SourceFile>("test.sim", text);
  std::vector<Token> tokens = lex(*p->file, p->diags);
  p->program = parse(tokens, p->diags);
  return p;
}

inline std::unique_ptr<Parsed> parse_ok(const std::string& text) {
  auto p = parse_text(text);
  EXPECT_FALSE(p->diags.has_errors()) << text << "\n" << p->errors();
  return p;
}

// The value of `r = <expr>;` inside a function, after `decls` (declarations before it).
struct ParsedExpr {
  std::unique_ptr<Parsed> parsed;
  const Expr* expr = nullptr;
};

inline ParsedExpr parse_expr_text(const std::string& expr, const std::string& decls = "") {
  ParsedExpr out;
  out.parsed = parse_ok(decls + "\nfunc test_fn()\n  r = " + expr + ";\nend\n");
  const Block& body = out.parsed->body();
  if (!body.empty())
    if (const auto* a = body.back()->as<Assign>()) out.expr = a->value.get();
  EXPECT_NE(out.expr, nullptr) << expr;
  return out;
}

// The expression as print_source writes it (parenthesised fully).
inline std::string printed(const std::string& expr, const std::string& decls = "") {
  auto p = parse_expr_text(expr, decls);
  std::string text = print_source(*p.parsed->program);
  size_t at = text.find("  r = ");
  if (at == std::string::npos) return "<missing>";
  size_t end = text.find(";\n", at);
  return text.substr(at + 6, end - at - 6);
}

inline std::string repeat(const std::string& s, int n) {
  std::string out;
  for (int i = 0; i < n; ++i) out += s;
  return out;
}

// "line:col message" of the first diagnostic, which must be a syntax error.
inline std::string first_error(const std::string& text) {
  auto p = parse_text(text);
  if (!p->diags.has_errors()) return "no error";
  const Diagnostic& d = p->diags.items()[0];
  EXPECT_EQ(d.category, DiagCategory::Syntax) << p->errors();
  LineCol lc = d.span.start();
  return std::to_string(lc.line) + ":" + std::to_string(lc.column) + " " + d.message;
}

inline std::string first_error_at(const std::string& text) {
  std::string e = first_error(text);
  return e.substr(0, e.find(' '));
}

}  // namespace simit::frontend::parser_support
