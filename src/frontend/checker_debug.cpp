// Type checker: debugger expressions, checked by the same rules as program text in the scope
// of one point of a function (frontend/debug_expr.h).
#include "frontend/checker_impl.h"

namespace simit::frontend::checker_detail {

TypeRef Checker::check_debug_expr(ast::Expr& e, const ast::FuncDecl* func,
                                  const std::vector<const ast::Variable*>& locals) {
  // The checker only reads the program here: no declaration is checked, so no variable is
  // created, and the names below are only looked up.
  for (const auto& d : program_.decls) {
    if (const auto* el = d->as<ast::ElementDecl>()) elements_.emplace(el->name, el);
    if (const auto* f = d->as<ast::FuncDecl>()) funcs_.emplace(f->name, f);
  }
  scopes_.push();
  for (const ast::Variable* g : program_.globals)
    if (g) scopes_.declare(const_cast<ast::Variable*>(g));
  scopes_.push();
  for (const ast::Variable* v : locals) scopes_.declare(const_cast<ast::Variable*>(v));
  func_ = const_cast<ast::FuncDecl*>(func);
  info_ = nullptr;
  debug_expr_ = true;
  return check_value(e, "a debugger expression");
}

}  // namespace simit::frontend::checker_detail
