// Types of LANGUAGE.md §3.5, with the tuple and set lookahead rules stated there.
#include "frontend/parser_impl.h"

namespace simit::frontend::parser_detail {

using namespace ast;

namespace {

// Larger shorthand arities are surely mistakes; expanding them would only waste memory.
constexpr long long kMaxShorthandArity = 4096;

bool is_scalar_keyword(TokenKind k, ScalarKind& out) {
  switch (k) {
    case TokenKind::KwInt: out = ScalarKind::Int; return true;
    case TokenKind::KwFloat: out = ScalarKind::Float; return true;
    case TokenKind::KwBool: out = ScalarKind::Bool; return true;
    case TokenKind::KwComplex: out = ScalarKind::Complex; return true;
    case TokenKind::KwString: out = ScalarKind::String; return true;
    default: return false;
  }
}

bool is_tensor_keyword(TokenKind k) {
  return k == TokenKind::KwTensor || k == TokenKind::KwVector || k == TokenKind::KwMatrix;
}

}  // namespace

// type = IDENT | set_type | grid_type | tuple_type | tensor_type | "opaque" ;
TypeExprPtr Parser::parse_type() {
  DepthGuard guard(*this);
  const Token& t = peek();
  switch (t.kind) {
    case TokenKind::Ident:
      advance();
      return std::make_unique<NamedTypeExpr>(t.span, std::string(t.text));
    case TokenKind::KwSet: return parse_set_type();
    case TokenKind::KwGrid: return parse_grid_type();
    case TokenKind::LParen: return parse_tuple_type();
    case TokenKind::KwOpaque: advance(); return std::make_unique<OpaqueTypeExpr>(t.span);
    default: return parse_tensor_type();
  }
}

// tensor_type = scalar_type | matrix_type | ( vector_type | nd_tensor_type ) [ "'" ] ;
// scalar_type = "int" | "float" | "bool" | "complex" | "string" ;
TypeExprPtr Parser::parse_tensor_type() {
  size_t start = pos_;
  ScalarKind scalar;
  if (is_scalar_keyword(peek().kind, scalar))
    return std::make_unique<ScalarTypeExpr>(advance().span, scalar);
  if (!is_tensor_keyword(peek().kind)) fail_expected("a tensor type");
  auto tensor = parse_tensor_body();
  if (tensor->spelling != TensorTypeExpr::Spelling::Matrix && accept(TokenKind::Apostrophe)) {
    tensor->transposed = true;
    tensor->span = span_from(start);
  }
  return tensor;
}

// vector_type    = "vector" [ "[" index_set "]" ] "(" ( vector_type | scalar_type ) ")" ;
// matrix_type    = "matrix" [ "[" index_set "," index_set "]" ]
//                  "(" ( matrix_type | scalar_type ) ")" ;
// nd_tensor_type = "tensor" [ "[" index_set_list "]" ] "(" ( nd_tensor_type | scalar_type ) ")" ;
std::unique_ptr<TensorTypeExpr> Parser::parse_tensor_body() {
  DepthGuard guard(*this);
  size_t start = pos_;
  TokenKind keyword = advance().kind;
  auto tensor = std::make_unique<TensorTypeExpr>(tokens_[start].span);
  tensor->spelling = keyword == TokenKind::KwVector   ? TensorTypeExpr::Spelling::Vector
                     : keyword == TokenKind::KwMatrix ? TensorTypeExpr::Spelling::Matrix
                                                      : TensorTypeExpr::Spelling::Tensor;
  if (accept(TokenKind::LBracket)) {
    if (keyword == TokenKind::KwTensor) {
      tensor->dims = parse_index_set_list();
    } else {
      tensor->dims.push_back(parse_index_set());
      if (keyword == TokenKind::KwMatrix) {
        expect(TokenKind::Comma);
        tensor->dims.push_back(parse_index_set());
      }
    }
    expect(TokenKind::RBracket);
  }
  expect(TokenKind::LParen);
  ScalarKind scalar;
  if (is_scalar_keyword(peek().kind, scalar)) {
    const Token& t = advance();
    tensor->block = std::make_unique<ScalarTypeExpr>(t.span, scalar);
  } else if (at(keyword)) {
    tensor->block = parse_tensor_body();
  } else {
    fail_expected(std::string("'") + token_spelling(keyword) + "' or a scalar type");
  }
  expect(TokenKind::RParen);
  tensor->span = span_from(start);
  return tensor;
}

// set_type = "set" "{" IDENT "}"
//            [ "(" ( IDENT "*" INT_LITERAL | IDENT { "," IDENT } ) ")" ] ;
TypeExprPtr Parser::parse_set_type() {
  size_t start = pos_;
  advance();
  auto set = std::make_unique<SetTypeExpr>(peek().span);
  expect(TokenKind::LBrace);
  const Token& element = expect_ident("an element type name");
  set->element = std::string(element.text);
  set->element_span = element.span;
  expect(TokenKind::RBrace);
  if (accept(TokenKind::LParen)) {
    if (peek(1).kind == TokenKind::Star) {
      IndexSetExpr endpoint;
      endpoint.span = peek().span;
      endpoint.name = std::string(expect_ident("an endpoint set name").text);
      expect(TokenKind::Star);
      set->shorthand = true;
      set->shorthand_count = expect_int();
      if (set->shorthand_count > kMaxShorthandArity) fail("edge set arity is too large");
      for (long long i = 0; i < set->shorthand_count; ++i) set->endpoints.push_back(endpoint);
    } else {
      do {
        IndexSetExpr endpoint;
        endpoint.span = peek().span;
        endpoint.name = std::string(expect_ident("an endpoint set name").text);
        set->endpoints.push_back(std::move(endpoint));
      } while (accept(TokenKind::Comma));
    }
    expect(TokenKind::RParen);
  }
  set->span = span_from(start);
  return set;
}

// grid_type = "grid" "[" INT_LITERAL "]" "{" IDENT "}" "(" IDENT ")" ;
TypeExprPtr Parser::parse_grid_type() {
  size_t start = pos_;
  advance();
  auto grid = std::make_unique<GridTypeExpr>(peek().span);
  expect(TokenKind::LBracket);
  grid->dims = expect_int();
  expect(TokenKind::RBracket);
  expect(TokenKind::LBrace);
  const Token& element = expect_ident("an element type name");
  grid->element = std::string(element.text);
  grid->element_span = element.span;
  expect(TokenKind::RBrace);
  expect(TokenKind::LParen);
  grid->point_set.span = peek().span;
  grid->point_set.name = std::string(expect_ident("a point set name").text);
  expect(TokenKind::RParen);
  grid->span = span_from(start);
  return grid;
}

// tuple_type = "(" IDENT "*" INT_LITERAL ")"
//            | "(" IDENT ":" IDENT { "," IDENT ":" IDENT } ")" ;
// Named when the token two positions after "(" is ":".
TypeExprPtr Parser::parse_tuple_type() {
  size_t start = pos_;
  auto tuple = std::make_unique<TupleTypeExpr>(peek().span);
  expect(TokenKind::LParen);
  if (peek(1).kind == TokenKind::Colon) {
    tuple->named = true;
    do {
      tuple->names.push_back(std::string(expect_ident("a tuple element name").text));
      expect(TokenKind::Colon);
      const Token& element = expect_ident("an element type name");
      tuple->elements.push_back(std::string(element.text));
      tuple->element_spans.push_back(element.span);
    } while (accept(TokenKind::Comma));
    tuple->count = static_cast<long long>(tuple->elements.size());
  } else {
    const Token& element = expect_ident("an element type name");
    tuple->elements.push_back(std::string(element.text));
    tuple->element_spans.push_back(element.span);
    expect(TokenKind::Star);
    tuple->count = expect_int();
  }
  expect(TokenKind::RParen);
  tuple->span = span_from(start);
  return tuple;
}

long long Parser::expect_int() {
  if (!at(TokenKind::IntLiteral)) fail_expected("an integer literal");
  return advance().int_value;
}

}  // namespace simit::frontend::parser_detail
