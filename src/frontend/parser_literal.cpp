// Literals of LANGUAGE.md §3.4: scalars, complex literals and dense tensor literals,
// which are flattened row-major with their shape (§6.2.2, §3.6.4).
#include "frontend/parser_impl.h"

namespace simit::frontend::parser_detail {

using namespace ast;

namespace {

const char* kind_token_name(ScalarKind k) {
  switch (k) {
    case ScalarKind::Int: return "an integer literal";
    case ScalarKind::Float: return "a float literal";
    default: return "a complex literal";
  }
}

// Appends the entries of `from` to `to` (kinds may differ when a shape error is recorded).
void append_values(DenseParts& to, DenseParts& from) {
  to.ints.insert(to.ints.end(), from.ints.begin(), from.ints.end());
  to.floats.insert(to.floats.end(), from.floats.begin(), from.floats.end());
  to.complexes.insert(to.complexes.end(), from.complexes.begin(), from.complexes.end());
}

}  // namespace

// literal = INT_LITERAL | FLOAT_LITERAL | STRING_LITERAL | "true" | "false"
//         | complex_literal | dense_literal ;
ExprPtr Parser::parse_literal() {
  const Token& t = peek();
  switch (t.kind) {
    case TokenKind::IntLiteral: advance(); return std::make_unique<IntLit>(t.span, t.int_value);
    case TokenKind::FloatLiteral:
      advance();
      return std::make_unique<FloatLit>(t.span, t.float_value);
    case TokenKind::StringLiteral:
      advance();
      return std::make_unique<StringLit>(t.span, t.string_value);
    case TokenKind::KwTrue:
    case TokenKind::KwFalse:
      advance();
      return std::make_unique<BoolLit>(t.span, t.kind == TokenKind::KwTrue);
    case TokenKind::Less: return parse_complex_literal();
    case TokenKind::LBracket: return parse_dense_literal();
    default: fail_expected("a literal");
  }
}

// complex_literal = "<" signed_float "," signed_float ">" ;
ExprPtr Parser::parse_complex_literal() {
  size_t start = pos_;
  std::complex<double> value = parse_complex_value();
  return std::make_unique<ComplexLit>(span_from(start), value);
}

std::complex<double> Parser::parse_complex_value() {
  expect(TokenKind::Less);
  double re = parse_signed_float();
  expect(TokenKind::Comma);
  double im = parse_signed_float();
  expect(TokenKind::Greater);
  return {re, im};
}

// signed_float = [ "+" | "-" ] FLOAT_LITERAL ;
double Parser::parse_signed_float() {
  bool negative = at(TokenKind::Minus);
  if (negative || at(TokenKind::Plus)) advance();
  if (!at(TokenKind::FloatLiteral)) fail_expected("a float literal");
  double v = advance().float_value;
  return negative ? -v : v;
}

// dense_literal = "[" dense_inner "]" ;
ExprPtr Parser::parse_dense_literal() {
  size_t start = pos_;
  DenseParts parts;
  parse_dense(parts);
  auto lit = std::make_unique<DenseLit>(span_from(start));
  lit->component = parts.kind;
  lit->shape = std::move(parts.shape);
  lit->ints = std::move(parts.ints);
  lit->floats = std::move(parts.floats);
  lit->complexes = std::move(parts.complexes);
  lit->shape_error = std::move(parts.error);
  return lit;
}

void Parser::parse_dense(DenseParts& out) {
  DepthGuard guard(*this);
  expect(TokenKind::LBracket);
  if (at(TokenKind::LBracket)) {
    parse_dense_nested(out);
  } else {
    parse_dense_rows(out);
  }
  expect(TokenKind::RBracket);
}

// dense_inner = dense_literal { [ "," ] dense_literal } | dense_rows ;
// Nested literals of equal shape S give shape k × S.
void Parser::parse_dense_nested(DenseParts& out) {
  int count = 0;
  std::vector<int> inner;
  while (true) {
    DenseParts sub;
    parse_dense(sub);
    if (count == 0) {
      out.kind = sub.kind;
      inner = sub.shape;
      out.error = sub.error;
    } else if (out.error.empty()) {
      if (!sub.error.empty())
        out.error = sub.error;
      else if (sub.kind != out.kind)
        out.error = "mismatched element types";
      else if (sub.shape != inner)
        out.error = "mismatched dimension sizes";
    }
    append_values(out, sub);
    ++count;
    if (accept(TokenKind::Comma)) {
      if (!at(TokenKind::LBracket)) fail_expected("'['");
    } else if (!at(TokenKind::LBracket)) {
      break;
    }
  }
  out.shape.push_back(count);
  out.shape.insert(out.shape.end(), inner.begin(), inner.end());
}

// dense_rows = dense_row { ";" dense_row } ;   one row: order 1; several: a matrix
void Parser::parse_dense_rows(DenseParts& out) {
  ScalarKind first_kind = ScalarKind::Int;
  int columns = parse_dense_row(out, first_kind);
  out.kind = first_kind;
  int rows = 1;
  while (accept(TokenKind::Semicolon)) {
    ScalarKind kind = first_kind;
    int n = parse_dense_row(out, kind);
    ++rows;
    if (!out.error.empty()) continue;
    if (kind != first_kind)
      out.error = "mismatched element types";
    else if (n != columns)
      out.error = "mismatched dimension sizes";
  }
  if (rows == 1) {
    out.shape = {columns};
  } else {
    out.shape = {rows, columns};
  }
}

// dense_row = signed_int { [ "," ] signed_int } | signed_float { [ "," ] signed_float }
//           | complex_literal { [ "," ] complex_literal } ;
// The first entry fixes the kind of the row; `kind` returns it.
int Parser::parse_dense_row(DenseParts& out, ScalarKind& kind) {
  size_t number = (at(TokenKind::Minus) || at(TokenKind::Plus)) ? 1 : 0;
  switch (peek(number).kind) {
    case TokenKind::IntLiteral: kind = ScalarKind::Int; break;
    case TokenKind::FloatLiteral: kind = ScalarKind::Float; break;
    case TokenKind::Less:
      if (number == 0) {
        kind = ScalarKind::Complex;
        break;
      }
      [[fallthrough]];
    default: pos_ += number; fail_expected("a number");
  }
  int count = 0;
  while (true) {
    parse_dense_entry(out, kind);
    ++count;
    if (accept(TokenKind::Comma)) continue;
    if (!at_dense_entry()) break;
  }
  return count;
}

bool Parser::at_dense_entry() const {
  switch (peek().kind) {
    case TokenKind::Minus:
    case TokenKind::Plus:
    case TokenKind::IntLiteral:
    case TokenKind::FloatLiteral:
    case TokenKind::Less: return true;
    default: return false;
  }
}

// One signed number or complex literal of the row's kind (§3.6.4: signs belong to it).
void Parser::parse_dense_entry(DenseParts& out, ScalarKind kind) {
  if (kind == ScalarKind::Complex) {
    if (!at(TokenKind::Less)) fail_expected(kind_token_name(kind));
    out.complexes.push_back(parse_complex_value());
    return;
  }
  bool negative = at(TokenKind::Minus);
  if (negative || at(TokenKind::Plus)) advance();
  TokenKind want = kind == ScalarKind::Int ? TokenKind::IntLiteral : TokenKind::FloatLiteral;
  if (!at(want)) fail_expected(kind_token_name(kind));
  const Token& t = advance();
  if (kind == ScalarKind::Int) {
    out.ints.push_back(negative ? -t.int_value : t.int_value);
  } else {
    out.floats.push_back(negative ? -t.float_value : t.float_value);
  }
}

}  // namespace simit::frontend::parser_detail
