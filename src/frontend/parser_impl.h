// The parser's private state, shared by the parser_*.cpp files (LANGUAGE.md §3).
#pragma once

#include <complex>
#include <cstdint>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

#include "frontend/parser.h"

namespace simit::frontend::parser_detail {

// Thrown after a syntax error has been reported; caught at the nearest statement or
// program-element boundary, which then skips to a synchronisation point.
struct SyntaxAbort {};

// What a name denotes in the declare-before-use table of §3.6.1.
struct NameInfo {
  bool function = false;  // an intrinsic, `func` or `extern func`
  bool value = false;     // any value declaration
  bool tuple = false;     // a parameter or result of tuple type
};

// A dense literal while it is being assembled (§3.4, §6.2.2).
struct DenseParts {
  ScalarKind kind = ScalarKind::Int;
  std::vector<int> shape;
  std::vector<long long> ints;
  std::vector<double> floats;
  std::vector<std::complex<double>> complexes;
  std::string error;  // semantic: ragged rows, mismatched shapes or kinds
};

class Parser {
 public:
  Parser(const std::vector<Token>& tokens, Diagnostics& diags);
  std::unique_ptr<ast::Program> run();
  ast::ExprPtr run_expression(const std::vector<ExprName>& names);  // parser_debug.cpp

 private:
  friend class DepthGuard;
  friend class ScopeGuard;

  // --- cursor and errors (parser.cpp)
  const Token& peek(size_t ahead = 0) const;
  bool at(TokenKind k) const { return peek().kind == k; }
  bool accept(TokenKind k);
  const Token& advance();
  const Token& expect(TokenKind k);
  const Token& expect_ident(const char* what);
  [[noreturn]] void fail(const std::string& message);
  [[noreturn]] void fail_expected(const std::string& what);
  void report(const Token& at, const std::string& message);
  SourceSpan span_from(size_t start) const;

  // --- recovery (parser.cpp)
  void open_block(TokenKind opener) { open_blocks_.push_back(opener); }
  void close_block() { open_blocks_.pop_back(); }
  void recover_statement(size_t start, size_t saved_blocks);
  void recover_top_level(size_t start, size_t saved_blocks);
  void skip_open_blocks(std::vector<TokenKind> open);
  void skip_do_condition();
  void skip_past_semicolon(bool stop_at_statements);
  bool at_program_keyword() const;

  // --- names (parser.cpp)
  const NameInfo* lookup(std::string_view name) const;
  void declare_value(const std::string& name, bool tuple = false);
  void declare_function(const std::string& name);

  // --- program elements (parser.cpp)
  ast::DeclPtr parse_program_element();
  [[noreturn]] void fail_proc();
  ast::DeclPtr parse_element();
  void parse_field(ast::ElementDecl& element);
  ast::DeclPtr parse_extern();
  ast::DeclPtr parse_global_const();
  ast::DeclPtr parse_func();
  void parse_generic_params(ast::FuncDecl& func);
  std::vector<ast::Param> parse_params();
  std::vector<ast::Param> parse_results();
  ast::Param parse_param(bool allow_inout);
  ast::DeclPtr parse_test();

  // --- statements (parser_stmt.cpp)
  ast::Block parse_block();
  ast::Block parse_scoped_block();
  bool at_block_end() const;
  ast::StmtPtr parse_stmt();
  std::unique_ptr<ast::VarDecl> parse_var_decl();
  std::unique_ptr<ast::VarDecl> parse_const_decl();
  ast::StmtPtr parse_ivar();
  ast::StmtPtr parse_if();
  ast::StmtPtr parse_while();
  ast::StmtPtr parse_do_while();
  ast::StmtPtr parse_for();
  ast::StmtPtr parse_for_range(size_t start, const Token& var);
  ast::StmtPtr parse_print();
  ast::StmtPtr parse_apply();
  ast::StmtPtr parse_expr_or_assign();
  void parse_assembly(ast::Assembly& assembly);

  // --- expressions (parser_expr.cpp)
  ast::ExprPtr parse_expr();
  ast::ExprPtr parse_map();
  ast::ExprPtr parse_or();
  ast::ExprPtr parse_and();
  ast::ExprPtr parse_xor();
  ast::ExprPtr parse_cmp();
  ast::ExprPtr parse_term();
  ast::ExprPtr parse_add();
  ast::ExprPtr parse_mul();
  ast::ExprPtr parse_neg();
  ast::ExprPtr parse_exp();
  ast::ExprPtr parse_transpose();
  ast::ExprPtr parse_read();
  ast::ExprPtr parse_field_read();
  ast::ExprPtr parse_set_read();
  ast::ExprPtr parse_factor();
  ast::ExprPtr parse_identifier();
  ast::ExprPtr parse_call();
  ast::ExprPtr parse_tuple_read();
  bool generic_call_ahead() const;
  std::vector<ast::ExprPtr> parse_expr_list(TokenKind close);
  std::vector<ast::IndexSetExpr> parse_index_set_list();
  ast::IndexSetExpr parse_index_set();
  ast::ExprPtr fold_sign(size_t start, bool negate, ast::ExprPtr operand);
  ast::ExprPtr fold_transpose(size_t start, ast::ExprPtr operand);

  // --- literals (parser_literal.cpp)
  ast::ExprPtr parse_literal();
  ast::ExprPtr parse_complex_literal();
  std::complex<double> parse_complex_value();
  double parse_signed_float();
  ast::ExprPtr parse_dense_literal();
  void parse_dense(DenseParts& out);
  void parse_dense_nested(DenseParts& out);
  void parse_dense_rows(DenseParts& out);
  int parse_dense_row(DenseParts& out, ScalarKind& kind);
  void parse_dense_entry(DenseParts& out, ScalarKind kind);
  bool at_dense_entry() const;

  // --- types (parser_types.cpp)
  ast::TypeExprPtr parse_type();
  ast::TypeExprPtr parse_tensor_type();
  std::unique_ptr<ast::TensorTypeExpr> parse_tensor_body();
  ast::TypeExprPtr parse_set_type();
  ast::TypeExprPtr parse_grid_type();
  ast::TypeExprPtr parse_tuple_type();
  long long expect_int();

  const std::vector<Token>& tokens_;
  Diagnostics& diags_;
  size_t pos_ = 0;
  int depth_ = 0;     // nesting: parentheses, calls, blocks, prefix operators...
  int links_ = 0;     // links of the left-deep operator chains open around the cursor
  int suppress_ = 0;  // >0: errors are not reported (still abort)
  size_t last_error_pos_ = SIZE_MAX;    // one report per token
  std::vector<TokenKind> open_blocks_;  // openers whose `end` is not yet read
  std::vector<std::unordered_map<std::string, NameInfo>> scopes_;
};

// Bounds the nesting of expressions, statements and types so that no input can exhaust
// the stack of the parser or of later tree walks. A flat chain such as a + b + ... + z is
// not nesting, but it is a left-deep tree that the later walks descend link by link: the
// depth of the tree (nesting plus links) has a limit of its own.
class DepthGuard {
 public:
  static constexpr int kMaxDepth = 256;
  // Measured: a Release build descends about 13,000 levels in 8 MB of stack, a sanitizer
  // build a third of that; 1024 leaves room for both.
  static constexpr int kMaxTreeDepth = 1024;
  explicit DepthGuard(Parser& p, int amount = 1);
  ~DepthGuard() {
    p_.depth_ -= amount_;
    p_.links_ -= links_;
  }
  DepthGuard(const DepthGuard&) = delete;
  DepthGuard& operator=(const DepthGuard&) = delete;
  // Adds a link to a left-deep operator chain.
  void deepen();

 private:
  Parser& p_;
  int amount_;
  int links_ = 0;
};

// One scope of the name table, popped on every exit (including aborts).
class ScopeGuard {
 public:
  explicit ScopeGuard(Parser& p) : p_(p) { p_.scopes_.emplace_back(); }
  ~ScopeGuard() { p_.scopes_.pop_back(); }
  ScopeGuard(const ScopeGuard&) = delete;
  ScopeGuard& operator=(const ScopeGuard&) = delete;

 private:
  Parser& p_;
};

// "identifier 'x'", "'end'", "end of file": how a token is named in messages.
std::string describe(const Token& t);

}  // namespace simit::frontend::parser_detail
