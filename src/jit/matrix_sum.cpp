// find_fused_sums (jit/matrix_sum.h): the sums whose scaled operand dies with them.
#include "jit/matrix_sum.h"

#include <functional>
#include <optional>

#include "frontend/ast_walk.h"

namespace simit::jit {

namespace ast = frontend::ast;

namespace {

bool system_matrix(const ast::Expr& e) {
  const frontend::Type* t = e.type.get();
  return t && t->kind == frontend::Type::Kind::Tensor && t->dims.size() == 2 &&
         t->dims[0].kind != frontend::IndexSet::Kind::Fixed &&
         t->dims[1].kind != frontend::IndexSet::Kind::Fixed &&
         t->component() == frontend::ScalarKind::Float;
}

bool float_scalar(const ast::Expr& e) {
  const frontend::Type* t = e.type.get();
  return t && t->kind == frontend::Type::Kind::Scalar && t->scalar == frontend::ScalarKind::Float;
}

const ast::Variable* var_of(const ast::Expr& e) {
  const auto* v = e.as<ast::VarRef>();
  return v ? v->var : nullptr;
}

// The sum `A = M +- s * K` of a statement, with its producer left unset; nothing otherwise.
std::optional<FusedSum> sum_of(const ast::Stmt& s) {
  const auto* a = s.as<ast::Assign>();
  if (!a || !s.system_level || a->index_notation || a->targets.size() != 1 || !a->value)
    return std::nullopt;
  const auto* b = a->value->as<ast::Binary>();
  if (!b || (b->op != ast::Binary::Op::Add && b->op != ast::Binary::Op::Sub)) return std::nullopt;
  const auto* m = b->rhs->as<ast::Binary>();
  if (!m || m->op != ast::Binary::Op::Mul) return std::nullopt;
  const bool scalar_first = float_scalar(*m->lhs);
  const ast::Expr& k = scalar_first ? *m->rhs : *m->lhs;
  const ast::Expr& f = scalar_first ? *m->lhs : *m->rhs;
  FusedSum out;
  out.target = var_of(*a->targets[0]);
  out.base = var_of(*b->lhs);
  out.scaled = var_of(k);
  out.factor = &f;
  out.subtract = b->op == ast::Binary::Op::Sub;
  if (!out.target || !out.base || !out.scaled || out.base == out.scaled || !float_scalar(f) ||
      !system_matrix(*b->lhs) || !system_matrix(k) ||
      (out.scaled->kind != ast::Variable::Kind::Local &&
       out.scaled->kind != ast::Variable::Kind::Implicit))
    return std::nullopt;
  return out;
}

// The map of `K = map ...` (or `var K = map ...`), or null.
const ast::Map* map_assigned_to(const ast::Stmt& s, const ast::Variable* k) {
  if (const auto* a = s.as<ast::Assign>()) {
    if (a->targets.size() == 1 && var_of(*a->targets[0]) == k && a->value)
      return a->value->as<ast::Map>();
  } else if (const auto* d = s.as<ast::VarDecl>()) {
    if (d->var == k && d->init) return d->init->as<ast::Map>();
  }
  return nullptr;
}

// How many times the function's statements name `v` (reads and assignments alike).
int mentions(const ast::Block& body, const ast::Variable* v) {
  int n = 0;
  std::function<void(const ast::Expr&)> expr = [&](const ast::Expr& e) {
    if (var_of(e) == v) ++n;
    ast::for_each_child(e, expr);
  };
  std::function<void(const ast::Block&)> block = [&](const ast::Block& b) {
    for (const auto& s : b) ast::for_each_stmt_part(*s, expr, block);
  };
  block(body);
  return n;
}

}  // namespace

FusedSums find_fused_sums(const ast::Program& program) {
  FusedSums out;
  for (const auto& d : program.decls) {
    const auto* f = d->as<ast::FuncDecl>();
    if (!f) continue;
    const ast::Block& body = f->body;  // statements outside loops only
    for (size_t i = 0; i < body.size(); ++i) {
      std::optional<FusedSum> sum = sum_of(*body[i]);
      if (!sum) continue;
      for (size_t j = 0; j < i; ++j) {
        const ast::Map* map = map_assigned_to(*body[j], sum->scaled);
        if (!map) continue;
        // The map's result and the sum's operand, and nothing else: no copy of K lives on.
        const int expected = body[j]->is<ast::Assign>() ? 2 : 1;
        if (mentions(body, sum->scaled) != expected) break;
        sum->producer = &map->assembly;
        sum->producer_line = static_cast<int>(map->span.start().line);
        out.keep_diagonal.insert(sum->producer);
        out.at.emplace(body[i].get(), *sum);
        break;
      }
    }
  }
  return out;
}

}  // namespace simit::jit
