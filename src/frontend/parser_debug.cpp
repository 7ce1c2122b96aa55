// Standalone expressions for the debugger: the expression grammar of §3.5 over a given
// table of names, the whole input one expression.
#include "frontend/parser_impl.h"

namespace simit::frontend {
namespace parser_detail {

ast::ExprPtr Parser::run_expression(const std::vector<ExprName>& names) {
  for (const ExprName& n : names)
    if (!n.local) n.function ? declare_function(n.name) : declare_value(n.name, n.tuple);
  ScopeGuard locals(*this);
  for (const ExprName& n : names)
    if (n.local) declare_value(n.name, n.tuple);
  try {
    if (at(TokenKind::EndOfFile)) fail_expected("an expression");
    ast::ExprPtr e = parse_expr();
    if (!at(TokenKind::EndOfFile)) fail_expected("the end of the expression");
    return e;
  } catch (const SyntaxAbort&) {
    return nullptr;
  }
}

}  // namespace parser_detail

ast::ExprPtr parse_expression(const std::vector<Token>& tokens, Diagnostics& diags,
                              const std::vector<ExprName>& names) {
  return parser_detail::Parser(tokens, diags).run_expression(names);
}

}  // namespace simit::frontend
