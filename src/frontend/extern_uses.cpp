// Which externs a function needs: a walk over its body and everything it calls or maps.
#include "frontend/extern_uses.h"

#include <set>

#include "frontend/ast_walk.h"

namespace simit::frontend {

namespace {

class ExternUses {
 public:
  void func(const ast::FuncDecl& f) {
    if (!funcs_.insert(&f).second) return;
    for (const auto& p : f.params) variable(p.var);
    for (const auto& r : f.results) variable(r.var);
    block(f.body);
  }
  std::set<const ast::Variable*> found;

 private:
  void variable(const ast::Variable* v) {
    if (!v) return;
    if (v->kind == ast::Variable::Kind::Extern) {
      if (!found.insert(v).second) return;
    }
    if (v->type) type(*v->type);
  }
  void index_set(const IndexSet& d) {
    if (d.kind == IndexSet::Kind::Set) variable(d.var);
  }
  void type(const Type& t) {
    for (const IndexSet& d : t.dims) index_set(d);
    for (const IndexSet& d : t.endpoints) index_set(d);
    if (t.has_source) index_set(t.source);
    if (t.block) type(*t.block);
    for (const auto& m : t.members)
      if (m) type(*m);
  }
  void assembly(const ast::Assembly& a) {
    for (const auto& e : a.args) expr(*e);
    variable(a.target_set);
    if (a.callee) func(*a.callee);
  }
  void expr(const ast::Expr& e) {
    if (e.type) type(*e.type);
    if (const auto* r = e.as<ast::VarRef>()) variable(r->var);
    if (const auto* c = e.as<ast::Call>(); c && c->func) func(*c->func);
    if (const auto* m = e.as<ast::Map>()) {
      assembly(m->assembly);
      variable(m->through_set);
      return;  // the map's arguments were visited by assembly()
    }
    ast::for_each_child(e, [&](const ast::Expr& child) { expr(child); });
  }
  void block(const ast::Block& b) {
    for (const auto& s : b) stmt(*s);
  }
  void stmt(const ast::Stmt& s) {
    declared(s);
    ast::for_each_stmt_part(
        s, [&](const ast::Expr& e) { expr(e); }, [&](const ast::Block& b) { block(b); });
  }
  // What a statement names besides its expressions: the variables it declares, and an
  // apply's function and target set.
  void declared(const ast::Stmt& s) {
    using K = ast::NodeKind;
    switch (s.kind) {
      case K::VarDecl: variable(static_cast<const ast::VarDecl&>(s).var); break;
      case K::Assign:
        for (const auto* v : static_cast<const ast::Assign&>(s).declares) variable(v);
        break;
      case K::ForSet: {
        const auto& f = static_cast<const ast::ForSet&>(s);
        variable(f.domain_var);
        variable(f.var);
        break;
      }
      case K::Apply: {
        const ast::Assembly& a = static_cast<const ast::Apply&>(s).assembly;
        variable(a.target_set);
        if (a.callee) func(*a.callee);
        break;
      }
      default: break;
    }
  }

  std::set<const ast::FuncDecl*> funcs_;
};

}  // namespace

void plan_extern_uses(ast::Program& program) {
  for (const auto& decl : program.decls) {
    auto* f = decl->as<ast::FuncDecl>();
    if (!f) continue;
    ExternUses uses;
    uses.func(*f);
    f->extern_uses.clear();
    for (const ast::Variable* g : program.globals)
      if (g && uses.found.count(g)) f->extern_uses.push_back(g);
  }
}

}  // namespace simit::frontend
