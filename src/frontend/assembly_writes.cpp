// The assembly-write marks: assignment targets that index a system-tensor result.
#include "frontend/assembly_writes.h"

#include "frontend/ast_walk.h"

namespace simit::frontend {

namespace {

bool has_set_dim(const Type* t) {
  if (!t || t->kind != Type::Kind::Tensor) return false;
  for (const IndexSet& d : t->dims)
    if (d.kind == IndexSet::Kind::Set) return true;
  return false;
}

// The position of `v` among the system-tensor results of `f`, or -1.
int result_position(const ast::FuncDecl& f, const ast::Variable* v) {
  for (size_t i = 0; i < f.results.size(); ++i)
    if (f.results[i].var == v) return has_set_dim(v->type.get()) ? static_cast<int>(i) : -1;
  return -1;
}

void mark_target(const ast::FuncDecl& f, ast::Expr& target) {
  auto* r = target.as<ast::TensorRead>();
  if (!r) return;
  // `K(a, b)(i, j)`: the write lands in the block of K(a, b).
  ast::TensorRead* outer = r;
  if (auto* inner = r->base->as<ast::TensorRead>()) r = inner;
  const auto* base = r->base->as<ast::VarRef>();
  if (!base || !base->var || base->var->kind != ast::Variable::Kind::Result) return;
  const int position = result_position(f, base->var);
  r->assembles_result = position;
  outer->assembles_result = position;
}

void mark_block(const ast::FuncDecl& f, const ast::Block& block) {
  for (const auto& s : block) {
    if (auto* a = s->as<ast::Assign>())
      for (auto& t : a->targets) mark_target(f, *t);
    ast::for_each_stmt_part(
        *s, [](const ast::Expr&) {}, [&](const ast::Block& b) { mark_block(f, b); });
  }
}

}  // namespace

void mark_assembly_writes(ast::Program& program) {
  for (const auto& decl : program.decls)
    if (const auto* f = decl->as<ast::FuncDecl>()) mark_block(*f, f->body);
}

}  // namespace simit::frontend
