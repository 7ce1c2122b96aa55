// The hoisting plan: nested calls of each root expression, in the order they run.
#include "frontend/hoisting.h"

#include "frontend/ast_walk.h"

namespace simit::frontend {

namespace {

void collect_calls(const ast::Expr& e, std::vector<const ast::Call*>& out) {
  ast::for_each_child(e, [&](const ast::Expr& c) { collect_calls(c, out); });
  if (const auto* call = e.as<ast::Call>(); call && call->func) out.push_back(call);
}

void plan_root(const ast::Expr& root) {
  std::vector<const ast::Call*> calls;
  collect_calls(root, calls);
  if (!calls.empty() && calls.back() == &root) calls.pop_back();
  // The tree is read-only for executors; this pass is the one writer of the plan.
  const_cast<ast::Expr&>(root).hoisted = std::move(calls);
}

void plan_block(const ast::Block& block) {
  for (const auto& s : block) ast::for_each_stmt_part(*s, plan_root, plan_block);
}

}  // namespace

void plan_hoisting(ast::Program& program) {
  for (const auto& decl : program.decls)
    if (const auto* f = decl->as<ast::FuncDecl>()) plan_block(f->body);
}

}  // namespace simit::frontend
