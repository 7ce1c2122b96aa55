// Statements of LANGUAGE.md §3.3, with the rules of §3.6.6-3.6.9.
#include "frontend/parser_impl.h"

namespace simit::frontend::parser_detail {

using namespace ast;

bool Parser::at_block_end() const {
  switch (peek().kind) {
    case TokenKind::KwEnd:
    case TokenKind::KwElif:
    case TokenKind::KwElse: return true;
    default: return at_program_keyword() && !at(TokenKind::Test);
  }
}

// stmt_block = { stmt } ;   (* ends at "end", "elif", "else" or end of file *)
Block Parser::parse_block() {
  DepthGuard guard(*this);
  Block block;
  while (!at_block_end()) {
    if (at(TokenKind::Test)) {
      // §3.6.9: tests are program elements only.
      report(peek(), "a test ('%!') is only allowed at the top level, not inside a function");
      advance();
      skip_past_semicolon(false);
      continue;
    }
    size_t start = pos_;
    size_t blocks = open_blocks_.size();
    try {
      if (StmtPtr stmt = parse_stmt()) block.push_back(std::move(stmt));
    } catch (const SyntaxAbort&) {
      recover_statement(start, blocks);
    }
  }
  return block;
}

// A block that is its own scope (§4.6.1).
Block Parser::parse_scoped_block() {
  ScopeGuard scope(*this);
  return parse_block();
}

// stmt = var_decl | const_decl | ivar_decl | if_stmt | while_stmt | do_while_stmt
//      | for_stmt | print_stmt | apply_stmt | expr_or_assign_stmt ;
StmtPtr Parser::parse_stmt() {
  switch (peek().kind) {
    case TokenKind::KwVar: return parse_var_decl();
    case TokenKind::KwConst: return parse_const_decl();
    case TokenKind::KwIvar: return parse_ivar();
    case TokenKind::KwIf: return parse_if();
    case TokenKind::KwWhile: return parse_while();
    case TokenKind::KwDo: return parse_do_while();
    case TokenKind::KwFor: return parse_for();
    case TokenKind::KwPrint:
    case TokenKind::KwPrintln:
    case TokenKind::KwError: return parse_print();
    case TokenKind::KwApply: return parse_apply();
    case TokenKind::Semicolon: advance(); return nullptr;  // the empty statement
    default: return parse_expr_or_assign();
  }
}

// var_decl = "var" IDENT ( "=" expr | ":" tensor_type [ "=" expr ] ) ";" ;
std::unique_ptr<VarDecl> Parser::parse_var_decl() {
  size_t start = pos_;
  advance();
  auto decl = std::make_unique<VarDecl>(peek().span);
  const Token& name = expect_ident("a variable name");
  decl->name = std::string(name.text);
  decl->name_span = name.span;
  if (accept(TokenKind::Colon)) {
    decl->declared = parse_tensor_type();
    if (accept(TokenKind::Assign)) decl->init = parse_expr();
  } else if (accept(TokenKind::Assign)) {
    decl->init = parse_expr();
  } else {
    fail_expected("':' or '='");
  }
  expect(TokenKind::Semicolon);
  decl->span = span_from(start);
  declare_value(decl->name);
  return decl;
}

// const_decl = "const" IDENT [ ":" tensor_type ] "=" expr ";" ;
std::unique_ptr<VarDecl> Parser::parse_const_decl() {
  size_t start = pos_;
  advance();
  auto decl = std::make_unique<VarDecl>(peek().span);
  decl->is_const = true;
  const Token& name = expect_ident("a constant name");
  decl->name = std::string(name.text);
  decl->name_span = name.span;
  if (accept(TokenKind::Colon)) decl->declared = parse_tensor_type();
  expect(TokenKind::Assign);
  decl->init = parse_expr();
  expect(TokenKind::Semicolon);
  decl->span = span_from(start);
  declare_value(decl->name);
  return decl;
}

// ivar_decl = "ivar" IDENT ;   (* a following ";" is an empty statement, §3.6.8 *)
StmtPtr Parser::parse_ivar() {
  size_t start = pos_;
  advance();
  const Token& name = expect_ident("an index variable name");
  auto decl = std::make_unique<IvarDecl>(span_from(start), std::string(name.text));
  declare_value(decl->name);
  return decl;
}

// if_stmt = "if" expr stmt_block { "elif" expr stmt_block } [ "else" stmt_block ] "end" ;
StmtPtr Parser::parse_if() {
  size_t start = pos_;
  advance();
  open_block(TokenKind::KwIf);
  auto stmt = std::make_unique<If>(peek().span);
  stmt->conditions.push_back(parse_expr());
  stmt->branches.push_back(parse_scoped_block());
  while (accept(TokenKind::KwElif)) {
    stmt->conditions.push_back(parse_expr());
    stmt->branches.push_back(parse_scoped_block());
  }
  if (accept(TokenKind::KwElse)) {
    stmt->has_else = true;
    stmt->else_branch = parse_scoped_block();
  }
  expect(TokenKind::KwEnd);
  close_block();
  stmt->span = span_from(start);
  return stmt;
}

// while_stmt = "while" expr stmt_block "end" ;
StmtPtr Parser::parse_while() {
  size_t start = pos_;
  advance();
  open_block(TokenKind::KwWhile);
  auto stmt = std::make_unique<While>(peek().span);
  stmt->condition = parse_expr();
  stmt->body = parse_scoped_block();
  expect(TokenKind::KwEnd);
  close_block();
  stmt->span = span_from(start);
  return stmt;
}

// do_while_stmt = "do" stmt_block "end" "while" expr ;   (* no ";" required, §3.6.7 *)
StmtPtr Parser::parse_do_while() {
  size_t start = pos_;
  advance();
  open_block(TokenKind::KwDo);
  auto stmt = std::make_unique<DoWhile>(peek().span);
  stmt->body = parse_scoped_block();
  expect(TokenKind::KwEnd);
  close_block();
  expect(TokenKind::KwWhile);
  stmt->condition = parse_expr();
  stmt->span = span_from(start);
  return stmt;
}

// for_stmt   = "for" IDENT "in" for_domain stmt_block "end" ;
// for_domain = IDENT   (* only when not followed by ":", §3.6.6 *)
//            | expr ":" expr ;
StmtPtr Parser::parse_for() {
  size_t start = pos_;
  advance();
  open_block(TokenKind::KwFor);
  const Token& var = expect_ident("a loop variable name");
  expect(TokenKind::KwIn);
  if (!(at(TokenKind::Ident) && peek(1).kind != TokenKind::Colon))
    return parse_for_range(start, var);
  auto stmt = std::make_unique<ForSet>(peek().span);
  stmt->var_name = std::string(var.text);
  stmt->var_span = var.span;
  const Token& domain = advance();
  stmt->domain = std::string(domain.text);
  stmt->domain_span = domain.span;
  {
    ScopeGuard scope(*this);  // the loop variable shares the body's scope
    declare_value(stmt->var_name);
    stmt->body = parse_block();
  }
  expect(TokenKind::KwEnd);
  close_block();
  stmt->span = span_from(start);
  return stmt;
}

// The range form of for_domain: expr ":" expr, then the body.
StmtPtr Parser::parse_for_range(size_t start, const Token& var) {
  auto stmt = std::make_unique<ForRange>(peek().span);
  stmt->var_name = std::string(var.text);
  stmt->var_span = var.span;
  stmt->lo = parse_expr();
  expect(TokenKind::Colon);
  stmt->hi = parse_expr();
  {
    ScopeGuard scope(*this);  // the loop variable shares the body's scope
    declare_value(stmt->var_name);
    stmt->body = parse_block();
  }
  expect(TokenKind::KwEnd);
  close_block();
  stmt->span = span_from(start);
  return stmt;
}

// print_stmt = ( "print" | "println" | "error" ) expr { "," expr } ";" ;
StmtPtr Parser::parse_print() {
  size_t start = pos_;
  auto stmt = std::make_unique<Print>(peek().span);
  switch (advance().kind) {
    case TokenKind::KwPrintln: stmt->mode = Print::Mode::Println; break;
    case TokenKind::KwError: stmt->mode = Print::Mode::Error; break;
    default: stmt->mode = Print::Mode::Print; break;
  }
  do {
    stmt->args.push_back(parse_expr());
  } while (accept(TokenKind::Comma));
  expect(TokenKind::Semicolon);
  stmt->span = span_from(start);
  return stmt;
}

// apply_stmt = "apply" IDENT [ "<" index_set_list ">" ]
//              [ "(" [ expr_list ] ")" ] "to" IDENT ";" ;
StmtPtr Parser::parse_apply() {
  size_t start = pos_;
  advance();
  auto stmt = std::make_unique<Apply>(peek().span);
  parse_assembly(stmt->assembly);
  expect(TokenKind::Semicolon);
  stmt->span = span_from(start);
  return stmt;
}

// The part shared by map and apply:
// IDENT [ "<" index_set_list ">" ] [ "(" [ expr_list ] ")" ] "to" IDENT
void Parser::parse_assembly(Assembly& assembly) {
  const Token& func = expect_ident("a function name");
  assembly.func = std::string(func.text);
  assembly.func_span = func.span;
  if (accept(TokenKind::Less)) {
    assembly.generic_args = parse_index_set_list();
    expect(TokenKind::Greater);
  }
  if (accept(TokenKind::LParen)) {
    assembly.args = parse_expr_list(TokenKind::RParen);
    expect(TokenKind::RParen);
  }
  expect(TokenKind::KwTo);
  const Token& target = expect_ident("a set name");
  assembly.target = std::string(target.text);
  assembly.target_span = target.span;
}

// expr_or_assign_stmt = [ [ expr { "," expr } "=" ] expr ] ";" ;
StmtPtr Parser::parse_expr_or_assign() {
  size_t start = pos_;
  ExprPtr first = parse_expr();
  if (!at(TokenKind::Comma) && !at(TokenKind::Assign)) {
    expect(TokenKind::Semicolon);
    return std::make_unique<ExprStmt>(span_from(start), std::move(first));
  }
  auto stmt = std::make_unique<Assign>(first->span);
  stmt->targets.push_back(std::move(first));
  while (accept(TokenKind::Comma)) stmt->targets.push_back(parse_expr());
  expect(TokenKind::Assign);
  stmt->value = parse_expr();
  expect(TokenKind::Semicolon);
  stmt->span = span_from(start);
  // An assignment to an unknown plain name declares it (§4.6); it hides nothing,
  // but it is a value from here on.
  for (const auto& target : stmt->targets) {
    if (const auto* ref = target->as<VarRef>(); ref && !lookup(ref->name)) declare_value(ref->name);
  }
  return stmt;
}

}  // namespace simit::frontend::parser_detail
