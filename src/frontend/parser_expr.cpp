// Expressions of LANGUAGE.md §3.4 with the precedence of §6.1, the name rules of
// §3.6.1-3.6.3 and the constant folding of §6.2.6.
#include <optional>

#include "frontend/parser_impl.h"

namespace simit::frontend::parser_detail {

using namespace ast;

namespace {

std::optional<Binary::Op> mul_op(TokenKind k) {
  switch (k) {
    case TokenKind::Star: return Binary::Op::Mul;
    case TokenKind::Slash: return Binary::Op::Div;
    case TokenKind::Backslash: return Binary::Op::LeftDiv;
    case TokenKind::DotStar: return Binary::Op::ElemMul;
    case TokenKind::DotSlash: return Binary::Op::ElemDiv;
    default: return std::nullopt;
  }
}

std::optional<Compare::Op> compare_op(TokenKind k) {
  switch (k) {
    case TokenKind::EqEq: return Compare::Op::Eq;
    case TokenKind::NotEq: return Compare::Op::Ne;
    case TokenKind::Less: return Compare::Op::Lt;
    case TokenKind::Greater: return Compare::Op::Gt;
    case TokenKind::LessEq: return Compare::Op::Le;
    case TokenKind::GreaterEq: return Compare::Op::Ge;
    default: return std::nullopt;
  }
}

ExprPtr make_binary(SourceSpan span, Binary::Op op, ExprPtr lhs, ExprPtr rhs) {
  return std::make_unique<Binary>(span, op, std::move(lhs), std::move(rhs));
}

void negate(DenseLit& lit) {
  for (auto& v : lit.ints) v = -v;
  for (auto& v : lit.floats) v = -v;
  for (auto& v : lit.complexes) v = -v;
}

}  // namespace

// expr = map_expr | or_expr ;
ExprPtr Parser::parse_expr() {
  DepthGuard guard(*this);
  if (at(TokenKind::KwMap)) return parse_map();
  return parse_or();
}

// map_expr = "map" IDENT [ "<" index_set_list ">" ] [ "(" [ expr_list ] ")" ]
//            "to" IDENT [ "through" IDENT ] [ "reduce" "+" ] ;
ExprPtr Parser::parse_map() {
  size_t start = pos_;
  advance();
  auto map = std::make_unique<Map>(peek().span);
  parse_assembly(map->assembly);
  if (accept(TokenKind::KwThrough)) {
    const Token& grid = expect_ident("a grid set name");
    map->through = std::string(grid.text);
    map->through_span = grid.span;
  }
  if (accept(TokenKind::KwReduce)) {
    expect(TokenKind::Plus);
    map->reduce = true;
  }
  map->span = span_from(start);
  return map;
}

// or_expr = and_expr { "or" and_expr } ;
ExprPtr Parser::parse_or() {
  size_t start = pos_;
  DepthGuard guard(*this, 0);
  ExprPtr lhs = parse_and();
  while (accept(TokenKind::KwOr)) {
    guard.deepen();
    ExprPtr rhs = parse_and();
    lhs = make_binary(span_from(start), Binary::Op::Or, std::move(lhs), std::move(rhs));
  }
  return lhs;
}

// and_expr = xor_expr { "and" xor_expr } ;
ExprPtr Parser::parse_and() {
  size_t start = pos_;
  DepthGuard guard(*this, 0);
  ExprPtr lhs = parse_xor();
  while (accept(TokenKind::KwAnd)) {
    guard.deepen();
    ExprPtr rhs = parse_xor();
    lhs = make_binary(span_from(start), Binary::Op::And, std::move(lhs), std::move(rhs));
  }
  return lhs;
}

// xor_expr = cmp_expr { "xor" cmp_expr } ;
ExprPtr Parser::parse_xor() {
  size_t start = pos_;
  DepthGuard guard(*this, 0);
  ExprPtr lhs = parse_cmp();
  while (accept(TokenKind::KwXor)) {
    guard.deepen();
    ExprPtr rhs = parse_cmp();
    lhs = make_binary(span_from(start), Binary::Op::Xor, std::move(lhs), std::move(rhs));
  }
  return lhs;
}

// cmp_expr = term { cmp_op term } ;   (* one Compare node for a whole chain *)
// cmp_op   = "==" | "!=" | "<" | ">" | "<=" | ">=" ;
ExprPtr Parser::parse_cmp() {
  size_t start = pos_;
  ExprPtr first = parse_term();
  if (!compare_op(peek().kind)) return first;
  auto cmp = std::make_unique<Compare>(first->span);
  cmp->operands.push_back(std::move(first));
  while (auto op = compare_op(peek().kind)) {
    advance();
    cmp->ops.push_back(*op);
    cmp->operands.push_back(parse_term());
  }
  cmp->span = span_from(start);
  return cmp;
}

// term = "not" term | add_expr ;
ExprPtr Parser::parse_term() {
  if (!at(TokenKind::KwNot)) return parse_add();
  DepthGuard guard(*this);
  size_t start = pos_;
  advance();
  ExprPtr operand = parse_term();
  return std::make_unique<Unary>(span_from(start), Unary::Op::Not, std::move(operand));
}

// add_expr = mul_expr { ( "+" | "-" ) mul_expr } ;
ExprPtr Parser::parse_add() {
  size_t start = pos_;
  DepthGuard guard(*this, 0);
  ExprPtr lhs = parse_mul();
  while (at(TokenKind::Plus) || at(TokenKind::Minus)) {
    guard.deepen();
    auto op = advance().kind == TokenKind::Plus ? Binary::Op::Add : Binary::Op::Sub;
    ExprPtr rhs = parse_mul();
    lhs = make_binary(span_from(start), op, std::move(lhs), std::move(rhs));
  }
  return lhs;
}

// mul_expr = neg_expr { ( "*" | "/" | "\" | ".*" | "./" ) neg_expr } ;
ExprPtr Parser::parse_mul() {
  size_t start = pos_;
  DepthGuard guard(*this, 0);
  ExprPtr lhs = parse_neg();
  while (auto op = mul_op(peek().kind)) {
    guard.deepen();
    advance();
    ExprPtr rhs = parse_neg();
    lhs = make_binary(span_from(start), *op, std::move(lhs), std::move(rhs));
  }
  return lhs;
}

// neg_expr = ( "-" | "+" ) neg_expr | exp_expr ;
ExprPtr Parser::parse_neg() {
  if (!at(TokenKind::Minus) && !at(TokenKind::Plus)) return parse_exp();
  DepthGuard guard(*this);
  size_t start = pos_;
  bool negate = advance().kind == TokenKind::Minus;
  ExprPtr operand = parse_neg();
  return fold_sign(start, negate, std::move(operand));
}

// §6.2.6: a sign on a numeric or dense literal is folded into it.
ExprPtr Parser::fold_sign(size_t start, bool negate_it, ExprPtr operand) {
  SourceSpan span = span_from(start);
  bool folded = true;
  if (auto* i = operand->as<IntLit>()) {
    if (negate_it) i->value = -i->value;
  } else if (auto* f = operand->as<FloatLit>()) {
    if (negate_it) f->value = -f->value;
  } else if (auto* c = operand->as<ComplexLit>()) {
    if (negate_it) c->value = -c->value;
  } else if (auto* d = operand->as<DenseLit>()) {
    if (negate_it) negate(*d);
  } else {
    folded = false;
  }
  if (folded) {
    operand->span = span;
    return operand;
  }
  return std::make_unique<Unary>(span, negate_it ? Unary::Op::Neg : Unary::Op::Plus,
                                 std::move(operand));
}

// exp_expr = transpose_expr [ "^" exp_expr ] ;
ExprPtr Parser::parse_exp() {
  size_t start = pos_;
  ExprPtr base = parse_transpose();
  if (!at(TokenKind::Caret)) return base;
  DepthGuard guard(*this);
  advance();
  ExprPtr exponent = parse_exp();
  return make_binary(span_from(start), Binary::Op::Pow, std::move(base), std::move(exponent));
}

// transpose_expr = read_expr { "'" } ;
ExprPtr Parser::parse_transpose() {
  size_t start = pos_;
  DepthGuard guard(*this, 0);
  ExprPtr e = parse_read();
  while (accept(TokenKind::Apostrophe)) {
    guard.deepen();
    e = fold_transpose(start, std::move(e));
  }
  return e;
}

// §6.2.6: `'` on a scalar literal is the literal; on an order-1 dense literal it flips
// the orientation.
ExprPtr Parser::fold_transpose(size_t start, ExprPtr operand) {
  SourceSpan span = span_from(start);
  switch (operand->kind) {
    case NodeKind::IntLit:
    case NodeKind::FloatLit:
    case NodeKind::ComplexLit:
    case NodeKind::BoolLit:
    case NodeKind::StringLit: operand->span = span; return operand;
    case NodeKind::DenseLit: {
      auto* d = operand->as<DenseLit>();
      if (d->shape.size() != 1 || !d->shape_error.empty()) break;
      d->column = !d->column;
      d->span = span;
      return operand;
    }
    default: break;
  }
  return std::make_unique<Transpose>(span, std::move(operand));
}

// read_expr  = field_expr { "(" [ read_param { "," read_param } ] ")" } ;
// read_param = ":" | expr ;
ExprPtr Parser::parse_read() {
  size_t start = pos_;
  DepthGuard guard(*this, 0);
  ExprPtr e = parse_field_read();
  while (accept(TokenKind::LParen)) {
    guard.deepen();
    auto read = std::make_unique<TensorRead>(e->span);
    read->base = std::move(e);
    if (!at(TokenKind::RParen)) {
      do {
        if (accept(TokenKind::Colon)) {
          read->indices.push_back(nullptr);
          if (!at(TokenKind::Comma) && !at(TokenKind::RParen)) fail_expected("',' or ')'");
        } else {
          read->indices.push_back(parse_expr());
        }
      } while (accept(TokenKind::Comma));
    }
    expect(TokenKind::RParen);
    read->span = span_from(start);
    e = std::move(read);
  }
  return e;
}

// field_expr = setread_expr [ "." IDENT ] ;
ExprPtr Parser::parse_field_read() {
  size_t start = pos_;
  ExprPtr base = parse_set_read();
  if (!accept(TokenKind::Dot)) return base;
  auto read = std::make_unique<FieldRead>(base->span);
  read->base = std::move(base);
  const Token& field = expect_ident("a field name");
  read->field = std::string(field.text);
  read->field_span = field.span;
  read->span = span_from(start);
  return read;
}

// setread_expr = factor [ "[" [ expr_list [ ";" expr_list ] ] "]" ] ;
ExprPtr Parser::parse_set_read() {
  size_t start = pos_;
  ExprPtr base = parse_factor();
  if (!accept(TokenKind::LBracket)) return base;
  auto read = std::make_unique<SetRead>(base->span);
  read->base = std::move(base);
  read->first = parse_expr_list(TokenKind::RBracket);
  if (!read->first.empty() && accept(TokenKind::Semicolon)) {
    read->has_semicolon = true;
    read->second = parse_expr_list(TokenKind::RBracket);
    if (read->second.empty()) fail_expected("an expression");
  }
  expect(TokenKind::RBracket);
  read->span = span_from(start);
  return read;
}

// factor = "(" expr ")" | call_expr | tuple_read | IDENT | literal ;
ExprPtr Parser::parse_factor() {
  switch (peek().kind) {
    case TokenKind::LParen: {
      advance();
      ExprPtr inner = parse_expr();
      expect(TokenKind::RParen);
      return inner;
    }
    case TokenKind::Ident: return parse_identifier();
    case TokenKind::IntLiteral:
    case TokenKind::FloatLiteral:
    case TokenKind::StringLiteral:
    case TokenKind::KwTrue:
    case TokenKind::KwFalse:
    case TokenKind::Less:  // §3.6.5: `<` here starts a complex literal
    case TokenKind::LBracket: return parse_literal();
    default: fail_expected("an expression");
  }
}

// §3.6.1: the innermost declaration of the name decides between a call, a tuple read
// and a variable; §3.6.2: the generic-call heuristic for names not declared at all.
ExprPtr Parser::parse_identifier() {
  const NameInfo* info = lookup(peek().text);
  if (info && info->function) return parse_call();
  if (!info && generic_call_ahead()) return parse_call();
  TokenKind next = peek(1).kind;
  if (info && info->tuple && (next == TokenKind::LParen || next == TokenKind::Dot))
    return parse_tuple_read();
  const Token& name = advance();
  return std::make_unique<VarRef>(name.span, std::string(name.text));
}

// IDENT "<" X "," ...  or  IDENT "<" X ">" "(" ")"
bool Parser::generic_call_ahead() const {
  if (peek(1).kind != TokenKind::Less) return false;
  TokenKind x = peek(2).kind;
  if (x != TokenKind::Ident && x != TokenKind::IntLiteral) return false;
  if (peek(3).kind == TokenKind::Comma) return true;
  return peek(3).kind == TokenKind::Greater && peek(4).kind == TokenKind::LParen &&
         peek(5).kind == TokenKind::RParen;
}

// call_expr = IDENT [ "<" index_set_list ">" ] "(" [ expr_list ] ")" ;
ExprPtr Parser::parse_call() {
  size_t start = pos_;
  const Token& name = advance();
  auto call = std::make_unique<Call>(name.span);
  call->callee = std::string(name.text);
  call->callee_span = name.span;
  if (accept(TokenKind::Less)) {
    call->generic_args = parse_index_set_list();
    expect(TokenKind::Greater);
  }
  if (!at(TokenKind::LParen)) fail_expected("'(' after the function name '" + call->callee + "'");
  advance();
  call->args = parse_expr_list(TokenKind::RParen);
  expect(TokenKind::RParen);
  call->span = span_from(start);
  return call;
}

// tuple_read = IDENT "(" expr ")" | IDENT "." IDENT ;
ExprPtr Parser::parse_tuple_read() {
  size_t start = pos_;
  const Token& name = advance();
  auto read = std::make_unique<TupleRead>(name.span);
  read->base = std::make_unique<VarRef>(name.span, std::string(name.text));
  if (accept(TokenKind::Dot)) {
    read->member = std::string(expect_ident("a tuple element name").text);
  } else {
    expect(TokenKind::LParen);
    read->index = parse_expr();
    expect(TokenKind::RParen);
  }
  read->span = span_from(start);
  return read;
}

// expr_list = expr { "," expr } ;   (* here optional: empty when `close` follows *)
std::vector<ExprPtr> Parser::parse_expr_list(TokenKind close) {
  std::vector<ExprPtr> list;
  if (at(close)) return list;
  do {
    list.push_back(parse_expr());
  } while (accept(TokenKind::Comma));
  return list;
}

// index_set_list = index_set { "," index_set } ;
std::vector<IndexSetExpr> Parser::parse_index_set_list() {
  std::vector<IndexSetExpr> list;
  do {
    list.push_back(parse_index_set());
  } while (accept(TokenKind::Comma));
  return list;
}

// index_set = INT_LITERAL | IDENT ;
IndexSetExpr Parser::parse_index_set() {
  IndexSetExpr index;
  index.span = peek().span;
  if (at(TokenKind::IntLiteral)) {
    index.is_int = true;
    index.value = advance().int_value;
  } else if (at(TokenKind::Ident)) {
    index.name = std::string(advance().text);
  } else {
    fail_expected("an integer literal or a set name");
  }
  return index;
}

}  // namespace simit::frontend::parser_detail
