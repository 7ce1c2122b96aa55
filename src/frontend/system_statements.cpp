// The system-statement marks: statements over set-indexed tensors, and loops made of them.
#include "frontend/system_statements.h"

#include "frontend/ast_walk.h"

namespace simit::frontend {

namespace {

bool has_set_dim(const Type* t) {
  if (!t || t->kind != Type::Kind::Tensor) return false;
  for (const IndexSet& d : t->dims)
    if (d.kind == IndexSet::Kind::Set) return true;
  return false;
}

bool mentions_system(const ast::Expr& e) {
  if (has_set_dim(e.type.get())) return true;
  bool found = false;
  ast::for_each_child(e, [&](const ast::Expr& c) { found = found || mentions_system(c); });
  return found;
}

bool calls_user_code(const ast::Expr& e) {
  if (const auto* c = e.as<ast::Call>(); c && c->func) return true;
  if (e.is<ast::Map>()) return true;
  bool found = false;
  ast::for_each_child(e, [&](const ast::Expr& c) { found = found || calls_user_code(c); });
  return found;
}

bool is_scalar(const Type* t) { return t && t->kind == Type::Kind::Scalar; }

// A declaration of a scalar with a value, or an assignment to scalar variables.
bool assigns_scalars(const ast::Stmt& s) {
  if (const auto* d = s.as<ast::VarDecl>())
    return d->init && d->var && is_scalar(d->var->type.get());
  const auto& a = *s.as<ast::Assign>();
  if (a.index_notation || a.targets.empty()) return false;
  for (const auto& t : a.targets)
    if (!t->is<ast::VarRef>() || !is_scalar(t->type.get())) return false;
  return is_scalar(a.value->type.get());
}

struct Marks {
  bool system = false;  // some statement computes on system tensors
  bool calls = false;   // some expression calls a user function or maps
};

Marks mark_block(const ast::Block& block);

Marks mark_stmt(ast::Stmt& s) {
  Marks m;
  auto root = [&](const ast::Expr& e) {
    m.system = m.system || mentions_system(e);
    m.calls = m.calls || calls_user_code(e);
  };
  auto block = [&](const ast::Block& b) {
    Marks inner = mark_block(b);
    m.system = m.system || inner.system;
    m.calls = m.calls || inner.calls;
  };
  ast::for_each_stmt_part(s, root, block);
  if (s.is<ast::Apply>()) m.calls = true;
  switch (s.kind) {
    case ast::NodeKind::Assign:
    case ast::NodeKind::VarDecl:
      s.system_level = m.system && !m.calls;
      s.scalar_level = !m.system && !m.calls && assigns_scalars(s);
      break;
    case ast::NodeKind::ExprStmt: s.system_level = m.system && !m.calls; break;
    case ast::NodeKind::While:
    case ast::NodeKind::DoWhile: s.system_level = m.system && !m.calls; break;
    default: break;
  }
  return m;
}

Marks mark_block(const ast::Block& block) {
  Marks m;
  for (const auto& s : block) {
    Marks one = mark_stmt(*s);
    m.system = m.system || one.system;
    m.calls = m.calls || one.calls;
  }
  return m;
}

}  // namespace

void mark_system_statements(ast::Program& program) {
  for (const auto& decl : program.decls)
    if (const auto* f = decl->as<ast::FuncDecl>()) mark_block(f->body);
}

}  // namespace simit::frontend
