// Debugger expressions: the scope at a point of a function, then the real lexer, parser and
// checker over it.
#include "frontend/debug_expr.h"

#include "frontend/checker_impl.h"
#include "frontend/lexer.h"
#include "frontend/parser.h"

namespace simit::frontend {

namespace {

void declared_by(const ast::Stmt& s, std::vector<const ast::Variable*>& out) {
  if (const auto* d = s.as<ast::VarDecl>(); d && d->var) out.push_back(d->var);
  if (const auto* d = s.as<ast::IvarDecl>(); d && d->var) out.push_back(d->var);
  if (const auto* a = s.as<ast::Assign>())
    for (const ast::Variable* v : a->declares)
      if (v) out.push_back(v);
}

bool encloses(const ast::Block& b, uint32_t offset) {
  return !b.empty() && b.front()->span.begin <= offset && offset <= b.back()->span.end;
}

void walk(const ast::Block& block, uint32_t offset, std::vector<const ast::Variable*>& out) {
  for (const auto& sp : block) {
    const ast::Stmt& s = *sp;
    if (s.span.end <= offset) {
      declared_by(s, out);
      continue;
    }
    // Before `s` (its own loop variable is not bound yet) or past the point.
    if (s.span.begin >= offset) return;
    // `s` encloses the point: only the block holding it adds names.
    if (const auto* i = s.as<ast::If>()) {
      for (const ast::Block& b : i->branches)
        if (encloses(b, offset)) return walk(b, offset, out);
      if (encloses(i->else_branch, offset)) walk(i->else_branch, offset, out);
    } else if (const auto* w = s.as<ast::While>()) {
      walk(w->body, offset, out);
    } else if (const auto* d = s.as<ast::DoWhile>()) {
      walk(d->body, offset, out);
    } else if (const auto* f = s.as<ast::ForRange>()) {
      if (f->var) out.push_back(f->var);
      walk(f->body, offset, out);
    } else if (const auto* f = s.as<ast::ForSet>()) {
      if (f->var) out.push_back(f->var);
      walk(f->body, offset, out);
    }
    return;
  }
}

// Why the debugger cannot evaluate `e` (it would run statements); empty when it can.
std::string refusal(const ast::Expr& e) {
  if (const auto* c = e.as<ast::Call>(); c && c->func)
    return "calls of user functions ('" + c->callee +
           "') are not supported in debugger expressions";
  if (e.is<ast::Map>()) return "maps are not supported in debugger expressions";
  std::vector<const ast::Expr*> children;
  auto add = [&](const ast::ExprPtr& c) {
    if (c) children.push_back(c.get());
  };
  if (const auto* u = e.as<ast::Unary>()) add(u->operand);
  if (const auto* t = e.as<ast::Transpose>()) add(t->operand);
  if (const auto* b = e.as<ast::Binary>()) add(b->lhs), add(b->rhs);
  if (const auto* c = e.as<ast::Compare>())
    for (const auto& o : c->operands) add(o);
  if (const auto* c = e.as<ast::Call>())
    for (const auto& a : c->args) add(a);
  if (const auto* r = e.as<ast::TensorRead>()) {
    add(r->base);
    for (const auto& i : r->indices) add(i);
  }
  if (const auto* f = e.as<ast::FieldRead>()) add(f->base);
  if (const auto* t = e.as<ast::TupleRead>()) add(t->base), add(t->index);
  if (const auto* s = e.as<ast::SetRead>()) {
    add(s->base);
    for (const auto& i : s->first) add(i);
    for (const auto& i : s->second) add(i);
  }
  for (const ast::Expr* c : children)
    if (std::string why = refusal(*c); !why.empty()) return why;
  return "";
}

bool is_tuple(const ast::Variable& v) { return v.type && v.type->kind == Type::Kind::Tuple; }

}  // namespace

std::vector<const ast::Variable*> visible_variables(const ast::FuncDecl& func, uint32_t offset) {
  std::vector<const ast::Variable*> out;
  for (const auto& g : func.generics)
    if (g.var) out.push_back(g.var);
  for (const auto& p : func.params)
    if (p.var) out.push_back(p.var);
  for (const auto& r : func.results)
    if (r.var) out.push_back(r.var);
  walk(func.body, offset, out);
  return out;
}

DebugExpression check_debug_expression(const ast::Program& program, const ast::FuncDecl* func,
                                       uint32_t offset, const std::string& text) {
  DebugExpression r;
  r.source = std::make_unique<SourceFile>("<expression>", text);
  Diagnostics diags;
  auto failed = [&] {
    r.error = diags.items().empty() ? "invalid expression" : diags.items().front().message;
    return std::move(r);
  };
  std::vector<Token> tokens = lex(*r.source, diags);
  if (diags.has_errors()) return failed();
  std::vector<const ast::Variable*> locals;
  if (func) locals = visible_variables(*func, offset);
  std::vector<ExprName> names;
  for (const auto& d : program.decls)
    if (const auto* f = d->as<ast::FuncDecl>()) names.push_back({f->name, true, false, false});
  for (const ast::Variable* g : program.globals)
    if (g) names.push_back({g->name, false, is_tuple(*g), false});
  for (const ast::Variable* v : locals) names.push_back({v->name, false, is_tuple(*v), true});
  ast::ExprPtr e = parse_expression(tokens, diags, names);
  if (!e || diags.has_errors()) return failed();
  // The checker never writes to a checked program's declarations when it checks an
  // expression (it creates no variables), so the program stays as the interpreter sees it.
  checker_detail::Checker checker(const_cast<ast::Program&>(program), diags);
  checker.check_debug_expr(*e, func, locals);
  if (diags.has_errors()) return failed();
  if (std::string why = refusal(*e); !why.empty()) {
    r.error = why;
    return r;
  }
  r.expr = std::move(e);
  return r;
}

}  // namespace simit::frontend
