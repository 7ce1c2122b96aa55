// Which externs a function needs: a walk over its body and everything it calls or maps.
#include <set>

#include "interp/ast_walk.h"
#include "api/compiled_program.h"

namespace simit::api {

namespace ast = frontend::ast;
using frontend::IndexSet;
using frontend::Type;

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
    interp::for_each_child(e, [&](const ast::Expr& child) { expr(child); });
  }
  void block(const ast::Block& b) {
    for (const auto& s : b) stmt(*s);
  }
  void stmt(const ast::Stmt& s) {
    using K = ast::NodeKind;
    switch (s.kind) {
      case K::VarDecl: {
        const auto& d = static_cast<const ast::VarDecl&>(s);
        variable(d.var);
        if (d.init) expr(*d.init);
        break;
      }
      case K::Assign: {
        const auto& a = static_cast<const ast::Assign&>(s);
        for (const auto& t : a.targets) expr(*t);
        for (const auto* v : a.declares) variable(v);
        if (a.value) expr(*a.value);
        break;
      }
      case K::ExprStmt: expr(*static_cast<const ast::ExprStmt&>(s).expr); break;
      case K::If: {
        const auto& i = static_cast<const ast::If&>(s);
        for (const auto& c : i.conditions) expr(*c);
        for (const auto& b : i.branches) block(b);
        block(i.else_branch);
        break;
      }
      case K::While: {
        const auto& w = static_cast<const ast::While&>(s);
        expr(*w.condition);
        block(w.body);
        break;
      }
      case K::DoWhile: {
        const auto& w = static_cast<const ast::DoWhile&>(s);
        block(w.body);
        expr(*w.condition);
        break;
      }
      case K::ForRange: {
        const auto& f = static_cast<const ast::ForRange&>(s);
        expr(*f.lo);
        expr(*f.hi);
        block(f.body);
        break;
      }
      case K::ForSet: {
        const auto& f = static_cast<const ast::ForSet&>(s);
        variable(f.domain_var);
        variable(f.var);
        block(f.body);
        break;
      }
      case K::Print:
        for (const auto& a : static_cast<const ast::Print&>(s).args) expr(*a);
        break;
      case K::Apply: assembly(static_cast<const ast::Apply&>(s).assembly); break;
      default: break;
    }
  }

  std::set<const ast::FuncDecl*> funcs_;
};

}  // namespace

std::vector<const ast::Variable*> externs_used_by(const ast::Program& program,
                                                  const ast::FuncDecl& func) {
  ExternUses uses;
  uses.func(func);
  std::vector<const ast::Variable*> out;
  for (const ast::Variable* g : program.globals)
    if (g && uses.found.count(g)) out.push_back(g);
  return out;
}

}  // namespace simit::api
