// The index-range plan of index-notation assignments.
#include "frontend/index_ranges.h"

#include <algorithm>

#include "frontend/ast_walk.h"

namespace simit::frontend {

namespace {

void add_once(std::vector<const ast::Variable*>& list, const ast::Variable* v) {
  if (std::find(list.begin(), list.end(), v) == list.end()) list.push_back(v);
}

// The outermost index-notation reads below e (a nested `K(i, j)(k, l)` is one read).
void ranging_reads(const ast::Expr& e, std::vector<const ast::TensorRead*>& out) {
  if (const auto* r = e.as<ast::TensorRead>(); r && r->index_notation) {
    out.push_back(r);
    return;
  }
  ast::for_each_child(e, [&](const ast::Expr& c) { ranging_reads(c, out); });
}

void plan(ast::Assign& a) {
  for (const auto* v : a.free_vars) add_once(a.loop_free, v);
  for (const auto* v : a.reduction_vars)
    if (std::find(a.loop_free.begin(), a.loop_free.end(), v) == a.loop_free.end())
      add_once(a.loop_reduction, v);
  ranging_reads(*a.targets.at(0), a.ranging_reads);
  ranging_reads(*a.value, a.ranging_reads);
}

void plan_block(const ast::Block& block) {
  for (const auto& s : block) {
    if (auto* a = s->as<ast::Assign>(); a && a->index_notation) plan(*a);
    ast::for_each_stmt_part(
        *s, [](const ast::Expr&) {}, plan_block);
  }
}

}  // namespace

void plan_index_ranges(ast::Program& program) {
  for (const auto& decl : program.decls)
    if (const auto* f = decl->as<ast::FuncDecl>()) plan_block(f->body);
}

}  // namespace simit::frontend
