// The parser driver: token cursor, errors and recovery, the name table of §3.6.1, and
// the program elements of LANGUAGE.md §3.2.
#include "frontend/parser.h"

#include "frontend/intrinsics.h"
#include "frontend/parser_impl.h"

namespace simit::frontend {
namespace parser_detail {

using namespace ast;

std::string describe(const Token& t) {
  switch (t.kind) {
    case TokenKind::Ident: return "identifier '" + std::string(t.text) + "'";
    case TokenKind::IntLiteral:
    case TokenKind::FloatLiteral:
    case TokenKind::StringLiteral:
      return std::string(token_spelling(t.kind)) + " " + std::string(t.text);
    case TokenKind::EndOfFile: return "end of file";
    default: return "'" + std::string(token_spelling(t.kind)) + "'";
  }
}

DepthGuard::DepthGuard(Parser& p, int amount) : p_(p), amount_(amount) {
  p_.depth_ += amount_;
  if (p_.depth_ > kMaxDepth) {
    p_.depth_ -= amount_;
    amount_ = 0;
    p_.fail("nested too deeply: more than " + std::to_string(kMaxDepth) +
            " levels of blocks, parentheses, calls or prefix operators");
  }
}

void DepthGuard::deepen() {
  ++p_.links_;
  ++links_;
  if (p_.depth_ + p_.links_ > kMaxTreeDepth)
    p_.fail("expression is too long: more than " + std::to_string(kMaxTreeDepth) +
            " levels of chained operators and nesting");
}

Parser::Parser(const std::vector<Token>& tokens, Diagnostics& diags)
    : tokens_(tokens), diags_(diags) {
  // A token the lexer dropped leaves a hole the parser would only report again.
  for (const auto& d : diags.items())
    if (d.category == DiagCategory::Lexical) suppress_ = 1;
  scopes_.emplace_back();
#define SIMIT_DECLARE_INTRINSIC(id, name) declare_function(name);
  SIMIT_INTRINSICS(SIMIT_DECLARE_INTRINSIC)
#undef SIMIT_DECLARE_INTRINSIC
}

// ---------------------------------------------------------------------------
// Cursor and errors

const Token& Parser::peek(size_t ahead) const {
  size_t i = pos_ + ahead;
  return i < tokens_.size() ? tokens_[i] : tokens_.back();
}

bool Parser::accept(TokenKind k) {
  if (!at(k)) return false;
  advance();
  return true;
}

const Token& Parser::advance() {
  const Token& t = peek();
  if (pos_ + 1 < tokens_.size()) ++pos_;
  return t;
}

const Token& Parser::expect(TokenKind k) {
  if (!at(k)) fail_expected(std::string("'") + token_spelling(k) + "'");
  return advance();
}

const Token& Parser::expect_ident(const char* what) {
  if (!at(TokenKind::Ident)) fail_expected(what);
  return advance();
}

void Parser::report(const Token& at, const std::string& message) {
  size_t index = static_cast<size_t>(&at - tokens_.data());
  if (suppress_ > 0 || index == last_error_pos_) return;
  last_error_pos_ = index;
  diags_.syntax(at.span, message);
}

void Parser::fail(const std::string& message) {
  report(peek(), message);
  throw SyntaxAbort{};
}

void Parser::fail_expected(const std::string& what) {
  fail("expected " + what + " but got " + describe(peek()));
}

SourceSpan Parser::span_from(size_t start) const {
  const Token& first = tokens_[start];
  if (pos_ <= start) return first.span;
  return SourceSpan::cover(first.span, tokens_[pos_ - 1].span);
}

// ---------------------------------------------------------------------------
// Recovery (§3.6.10): one typo should give one error.

bool Parser::at_program_keyword() const {
  switch (peek().kind) {
    case TokenKind::KwFunc:
    case TokenKind::KwExport:
    case TokenKind::KwElement:
    case TokenKind::KwExtern:
    case TokenKind::Test:
    case TokenKind::EndOfFile: return true;
    default: return false;
  }
}

bool starts_statement(TokenKind k) {
  switch (k) {
    case TokenKind::KwVar:
    case TokenKind::KwConst:
    case TokenKind::KwIvar:
    case TokenKind::KwIf:
    case TokenKind::KwWhile:
    case TokenKind::KwDo:
    case TokenKind::KwFor:
    case TokenKind::KwPrint:
    case TokenKind::KwPrintln:
    case TokenKind::KwError:
    case TokenKind::KwApply: return true;
    default: return false;
  }
}

bool is_block_opener(TokenKind k) {
  return k == TokenKind::KwIf || k == TokenKind::KwWhile || k == TokenKind::KwFor ||
         k == TokenKind::KwDo;
}

// Skips to just after the next `;`, stopping early before anything that ends a block or
// (when asked) starts a statement, so the enclosing block can go on from there.
void Parser::skip_past_semicolon(bool stop_at_statements) {
  while (!at_program_keyword()) {
    TokenKind k = peek().kind;
    if (k == TokenKind::Semicolon) {
      advance();
      return;
    }
    if (k == TokenKind::KwEnd || k == TokenKind::KwElif || k == TokenKind::KwElse) return;
    if (stop_at_statements && starts_statement(k)) return;
    if (!stop_at_statements && k == TokenKind::KwConst) return;
    advance();
  }
}

// Skips the rest of blocks whose opener was read but whose `end` was not, keeping
// count of the blocks nested inside them.
void Parser::skip_open_blocks(std::vector<TokenKind> open) {
  while (!open.empty() && !at_program_keyword()) {
    TokenKind k = advance().kind;
    if (is_block_opener(k)) {
      open.push_back(k);
    } else if (k == TokenKind::KwEnd) {
      TokenKind closed = open.back();
      open.pop_back();
      // `end while cond` closes a do-loop; that `while` opens nothing.
      if (closed == TokenKind::KwDo && at(TokenKind::KwWhile)) {
        if (open.empty()) return skip_do_condition();
        advance();
      }
    }
  }
}

void Parser::skip_do_condition() {
  advance();
  ++suppress_;
  try {
    parse_expr();
  } catch (const SyntaxAbort&) {
  }
  --suppress_;
}

void Parser::recover_statement(size_t start, size_t saved_blocks) {
  std::vector<TokenKind> open(open_blocks_.begin() + saved_blocks, open_blocks_.end());
  open_blocks_.resize(saved_blocks);
  if (!open.empty()) return skip_open_blocks(std::move(open));
  if (pos_ == start) advance();
  skip_past_semicolon(true);
}

// Skips to the next program element. Stray statements and blocks (say, the body of a
// mistyped function header) are skipped whole, their `end`s included.
void Parser::recover_top_level(size_t start, size_t saved_blocks) {
  std::vector<TokenKind> open(open_blocks_.begin() + saved_blocks, open_blocks_.end());
  open_blocks_.resize(saved_blocks);
  if (!open.empty()) return skip_open_blocks(std::move(open));
  if (pos_ == start) advance();
  int depth = 0;
  while (!at_program_keyword() && !(depth == 0 && at(TokenKind::KwConst))) {
    TokenKind k = advance().kind;
    if (is_block_opener(k)) ++depth;
    if (k == TokenKind::KwEnd && depth > 0) --depth;
  }
}

// ---------------------------------------------------------------------------
// Names (§3.6.1): the innermost declaration decides.

const NameInfo* Parser::lookup(std::string_view name) const {
  std::string key(name);
  for (auto it = scopes_.rbegin(); it != scopes_.rend(); ++it) {
    auto found = it->find(key);
    if (found != it->end()) return &found->second;
  }
  return nullptr;
}

void Parser::declare_value(const std::string& name, bool tuple) {
  NameInfo& info = scopes_.back()[name];
  info.value = true;
  info.tuple = tuple;
  // A value hides a function of an outer scope; at global scope the namespaces are
  // kept apart (§4.1 allows it), so an extern never hides an earlier function.
  if (scopes_.size() > 1) info.function = false;
}

void Parser::declare_function(const std::string& name) { scopes_.front()[name].function = true; }

// ---------------------------------------------------------------------------
// Program elements

// program = { program_element } ;
std::unique_ptr<Program> Parser::run() {
  auto program = std::make_unique<Program>();
  while (!at(TokenKind::EndOfFile)) {
    size_t start = pos_;
    size_t blocks = open_blocks_.size();
    try {
      program->decls.push_back(parse_program_element());
    } catch (const SyntaxAbort&) {
      recover_top_level(start, blocks);
    }
  }
  return program;
}

// program_element = element_decl | extern_decl | extern_func_decl
//                 | global_const_decl | func_decl | test ;
DeclPtr Parser::parse_program_element() {
  switch (peek().kind) {
    case TokenKind::KwElement: return parse_element();
    case TokenKind::KwExtern: return parse_extern();
    case TokenKind::KwConst: return parse_global_const();
    case TokenKind::KwFunc:
    case TokenKind::KwExport: return parse_func();
    case TokenKind::Test: return parse_test();
    default:
      if (at(TokenKind::Ident) && peek().text == "proc") fail_proc();
      fail_expected("a program element (element, extern, const, func, export or a test)");
  }
}

// The original Simit wrote an exported procedure `proc NAME ... end`; programs ported from
// it meet this first. The procedure is then skipped to its `end`, so that its body (which
// may declare `const`s) gives no further errors.
void Parser::fail_proc() {
  std::string name = peek(1).kind == TokenKind::Ident ? std::string(peek(1).text) : "NAME";
  report(peek(), "'proc' is not a keyword here: an exported procedure is written 'export func " +
                     name + "()'");
  advance();
  open_block(TokenKind::KwFunc);
  throw SyntaxAbort{};
}

// element_decl = "element" IDENT { field_decl } "end" ;
DeclPtr Parser::parse_element() {
  size_t start = pos_;
  advance();
  open_block(TokenKind::KwElement);
  auto element = std::make_unique<ElementDecl>(peek().span);
  const Token& name = expect_ident("an element type name");
  element->name = std::string(name.text);
  element->name_span = name.span;
  while (at(TokenKind::Ident)) {
    size_t field_start = pos_;
    try {
      parse_field(*element);
    } catch (const SyntaxAbort&) {
      if (pos_ == field_start) advance();
      skip_past_semicolon(false);
    }
  }
  expect(TokenKind::KwEnd);
  close_block();
  element->span = span_from(start);
  return element;
}

// field_decl = IDENT ":" tensor_type ";" ;
void Parser::parse_field(ElementDecl& element) {
  FieldDecl field;
  const Token& name = advance();
  field.name = std::string(name.text);
  field.span = name.span;
  expect(TokenKind::Colon);
  field.type_expr = parse_tensor_type();
  expect(TokenKind::Semicolon);
  element.fields.push_back(std::move(field));
}

// extern_decl = "extern" IDENT ":" type ";" ;
DeclPtr Parser::parse_extern() {
  if (peek(1).kind == TokenKind::KwFunc) return parse_func();
  size_t start = pos_;
  advance();
  auto decl = std::make_unique<ExternDecl>(peek().span);
  const Token& name = expect_ident("a name");
  decl->name = std::string(name.text);
  decl->name_span = name.span;
  expect(TokenKind::Colon);
  decl->type_expr = parse_type();
  expect(TokenKind::Semicolon);
  decl->span = span_from(start);
  declare_value(decl->name);
  return decl;
}

// global_const_decl = const_decl ;
DeclPtr Parser::parse_global_const() {
  size_t start = pos_;
  auto decl = std::make_unique<ConstDecl>(peek().span);
  decl->decl = parse_const_decl();
  decl->span = span_from(start);
  return decl;
}

// func_decl        = [ "export" ] "func" IDENT [ generic_params ] params [ results ]
//                    stmt_block "end" ;
// extern_func_decl = "extern" "func" IDENT [ generic_params ] params [ results ] ";" ;
DeclPtr Parser::parse_func() {
  size_t start = pos_;
  auto func = std::make_unique<FuncDecl>(peek().span);
  func->exported = accept(TokenKind::KwExport);
  if (!func->exported) func->is_extern = accept(TokenKind::KwExtern);
  expect(TokenKind::KwFunc);
  if (!func->is_extern) open_block(TokenKind::KwFunc);
  const Token& name = expect_ident("a function name");
  func->name = std::string(name.text);
  func->name_span = name.span;
  declare_function(func->name);
  ScopeGuard outer(*this);
  if (at(TokenKind::Less)) parse_generic_params(*func);
  func->params = parse_params();
  if (at(TokenKind::Arrow)) func->results = parse_results();
  if (func->is_extern) {
    expect(TokenKind::Semicolon);
  } else {
    func->body = parse_scoped_block();
    expect(TokenKind::KwEnd);
    close_block();
  }
  func->span = span_from(start);
  return func;
}

// generic_params = "<" generic_param { "," generic_param } ">" ;
// generic_param  = [ "0" ":" ] IDENT ;
void Parser::parse_generic_params(FuncDecl& func) {
  expect(TokenKind::Less);
  do {
    GenericParam param;
    if (at(TokenKind::IntLiteral)) {
      if (peek().int_value != 0) fail("the lower bound of a ranged generic parameter must be 0");
      advance();
      expect(TokenKind::Colon);
      param.ranged = true;
    }
    const Token& name = expect_ident("a generic parameter name");
    param.name = std::string(name.text);
    param.span = name.span;
    declare_value(param.name);
    func.generics.push_back(std::move(param));
  } while (accept(TokenKind::Comma));
  expect(TokenKind::Greater);
}

// params = "(" [ param { "," param } ] ")" ;
std::vector<Param> Parser::parse_params() {
  std::vector<Param> params;
  expect(TokenKind::LParen);
  if (!at(TokenKind::RParen)) {
    do {
      params.push_back(parse_param(true));
    } while (accept(TokenKind::Comma));
  }
  expect(TokenKind::RParen);
  return params;
}

// results = "->" ( result | "(" result { "," result } ")" ) ;
std::vector<Param> Parser::parse_results() {
  std::vector<Param> results;
  expect(TokenKind::Arrow);
  if (!accept(TokenKind::LParen)) {
    results.push_back(parse_param(false));
    return results;
  }
  do {
    results.push_back(parse_param(false));
  } while (accept(TokenKind::Comma));
  expect(TokenKind::RParen);
  return results;
}

// param  = [ "inout" ] IDENT ":" type ;
// result = IDENT ":" type ;
Param Parser::parse_param(bool allow_inout) {
  Param param;
  if (allow_inout) param.inout = accept(TokenKind::KwInout);
  const Token& name = expect_ident(allow_inout ? "a parameter name" : "a result name");
  param.name = std::string(name.text);
  param.span = name.span;
  expect(TokenKind::Colon);
  param.type_expr = parse_type();
  declare_value(param.name, param.type_expr->is<TupleTypeExpr>());
  return param;
}

// test = TEST IDENT "(" [ expr_list ] ")" "==" expr ";" ;
DeclPtr Parser::parse_test() {
  size_t start = pos_;
  advance();
  auto test = std::make_unique<TestDecl>(peek().span);
  const Token& name = expect_ident("the name of the tested function");
  test->func = std::string(name.text);
  test->func_span = name.span;
  expect(TokenKind::LParen);
  test->args = parse_expr_list(TokenKind::RParen);
  expect(TokenKind::RParen);
  expect(TokenKind::EqEq);
  test->expected = parse_expr();
  expect(TokenKind::Semicolon);
  test->span = span_from(start);
  return test;
}

}  // namespace parser_detail

std::unique_ptr<ast::Program> parse(const std::vector<Token>& tokens, Diagnostics& diags) {
  if (tokens.empty()) return std::make_unique<ast::Program>();
  return parser_detail::Parser(tokens, diags).run();
}

}  // namespace simit::frontend
