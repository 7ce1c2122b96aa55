// Type checker entry point and program elements (§4): element types, externs, global
// constants, functions and `%!` tests, checked in textual order.
#include "frontend/checker.h"

#include <unordered_set>

#include "frontend/checker_impl.h"

namespace simit::frontend {

void check(ast::Program& program, Diagnostics& diags) {
  checker_detail::Checker(program, diags).run();
}

namespace checker_detail {

using ast::Variable;

ast::Variable* Scopes::lookup(const std::string& name) const {
  for (auto it = frames_.rbegin(); it != frames_.rend(); ++it) {
    auto found = it->find(name);
    if (found != it->end()) return found->second;
  }
  return nullptr;
}

ast::Variable* Scopes::lookup_innermost(const std::string& name) const {
  if (frames_.empty()) return nullptr;
  auto found = frames_.back().find(name);
  return found == frames_.back().end() ? nullptr : found->second;
}

void Checker::error(SemanticKind kind, SourceSpan span, std::string message) {
  diags_->semantic(kind, span, std::move(message));
}

void Checker::undeclared(const std::string& what, const std::string& name, SourceSpan span) {
  if (undeclared_.insert(what + " " + name).second)
    error(SemanticKind::Undeclared, span, what + " '" + name + "'");
}

ast::Variable* Checker::new_variable(Variable::Kind kind, const std::string& name, SourceSpan span,
                                     TypeRef type, bool writable) {
  auto v = std::make_unique<Variable>();
  v->kind = kind;
  v->name = name;
  v->span = span;
  v->type = std::move(type);
  v->writable = writable;
  v->func = func_;
  if (kind == Variable::Kind::Extern || kind == Variable::Kind::GlobalConst) {
    v->slot = static_cast<int>(program_.globals.size());
    program_.globals.push_back(v.get());
  } else if (func_) {
    v->slot = func_->frame_size++;
  }
  Variable* raw = v.get();
  program_.variables.push_back(std::move(v));
  return raw;
}

void Checker::run() {
  scopes_.push();
  // `%!` tests may name functions declared anywhere in the file (§4.1).
  for (auto& d : program_.decls)
    if (auto* f = d->as<ast::FuncDecl>()) all_funcs_.emplace(f->name, f);
  for (auto& d : program_.decls) check_decl(*d);
}

void Checker::check_decl(ast::Decl& d) {
  switch (d.kind) {
    case ast::NodeKind::ElementDecl: check_element(*d.as<ast::ElementDecl>()); break;
    case ast::NodeKind::ExternDecl: check_extern(*d.as<ast::ExternDecl>()); break;
    case ast::NodeKind::ConstDecl: check_global_const(*d.as<ast::ConstDecl>()); break;
    case ast::NodeKind::FuncDecl: check_func(*d.as<ast::FuncDecl>()); break;
    case ast::NodeKind::TestDecl: check_test(*d.as<ast::TestDecl>()); break;
    default: SIMIT_ASSERT(false, "not a program element");
  }
}

void Checker::check_element(ast::ElementDecl& e) {
  bool fresh = elements_.find(e.name) == elements_.end();
  if (!fresh)
    error(SemanticKind::Redefinition, e.name_span, "redefinition of element type '" + e.name + "'");
  std::unordered_set<std::string> seen;
  for (auto& f : e.fields) {
    if (!seen.insert(f.name).second) {
      error(SemanticKind::Redefinition, f.span, "redefinition of element field '" + f.name + "'");
      continue;
    }
    if (f.type_expr) f.type = resolve_type(*f.type_expr, TypePos::Field);
    // The host API stores int, float, bool and complex fields only (§4.2 Rec.).
    if (f.type && f.type->component() == ScalarKind::String) {
      error(SemanticKind::Type, f.type_expr->span, "element fields cannot have string components");
      f.type = nullptr;
    }
  }
  if (fresh) elements_[e.name] = &e;
}

void Checker::check_extern(ast::ExternDecl& e) {
  if (scopes_.lookup_innermost(e.name)) {
    error(SemanticKind::Redefinition, e.name_span,
          "redefinition of variable or constant '" + e.name + "'");
    return;
  }
  TypeRef t = e.type_expr ? resolve_type(*e.type_expr, TypePos::Extern) : nullptr;
  e.var = new_variable(Variable::Kind::Extern, e.name, e.name_span, t, true);
  scopes_.declare(e.var);
}

// §6.2.5: literals after folding of signs and of `'` on scalars and order-1 literals.
enum class LiteralClass { None, Number, Other, Vector, Matrix };

static LiteralClass literal_class(const ast::Expr& e) {
  switch (e.kind) {
    case ast::NodeKind::IntLit:
    case ast::NodeKind::FloatLit:
    case ast::NodeKind::ComplexLit: return LiteralClass::Number;
    case ast::NodeKind::BoolLit:
    case ast::NodeKind::StringLit: return LiteralClass::Other;
    case ast::NodeKind::DenseLit:
      return e.as<ast::DenseLit>()->shape.size() == 1 ? LiteralClass::Vector : LiteralClass::Matrix;
    case ast::NodeKind::Unary: {
      const auto* u = e.as<ast::Unary>();
      if (u->op == ast::Unary::Op::Not || !u->operand) return LiteralClass::None;
      LiteralClass c = literal_class(*u->operand);
      return c == LiteralClass::Other ? LiteralClass::None : c;
    }
    case ast::NodeKind::Transpose: {
      const auto* t = e.as<ast::Transpose>();
      LiteralClass c = t->operand ? literal_class(*t->operand) : LiteralClass::None;
      return c == LiteralClass::Matrix ? LiteralClass::None : c;
    }
    default: return LiteralClass::None;
  }
}

static bool is_literal(const ast::Expr& e) { return literal_class(e) != LiteralClass::None; }

void Checker::check_global_const(ast::ConstDecl& c) {
  if (!c.decl) return;
  ast::VarDecl& v = *c.decl;
  if (scopes_.lookup_innermost(v.name)) {
    error(SemanticKind::Redefinition, v.name_span,
          "redefinition of variable or constant '" + v.name + "'");
    return;
  }
  TypeRef declared = v.declared ? resolve_type(*v.declared, TypePos::GlobalConst) : nullptr;
  TypeRef type = declared;
  bool ok = !v.declared || declared;
  if (ok && v.init && !is_literal(*v.init)) {
    error(SemanticKind::LiteralRequired, v.init->span,
          "global constant must be initialized to a literal");
    ok = false;
  }
  if (ok && v.init) {
    TypeRef init = check_expr(*v.init);
    if (init && declared) check_initializer(v.init->span, *declared, *init, true, true);
    if (!declared) type = init;
  }
  v.var = new_variable(Variable::Kind::GlobalConst, v.name, v.name_span, type, false);
  scopes_.declare(v.var);
}

void Checker::declare_generics(ast::FuncDecl& f, FuncInfo& info) {
  for (auto& g : f.generics) {
    if (scopes_.lookup_innermost(g.name)) {
      error(SemanticKind::Redefinition, g.span,
            "redefinition of generic parameter '" + g.name + "'");
      info.signature_ok = false;
      continue;
    }
    g.var = new_variable(Variable::Kind::Generic, g.name, g.span, nullptr, false);
    g.var->ranged = g.ranged;
    scopes_.declare(g.var);
  }
}

void Checker::declare_params(std::vector<ast::Param>& params, Variable::Kind kind, FuncInfo& info) {
  TypePos pos = kind == Variable::Kind::Result ? TypePos::Result : TypePos::Param;
  for (auto& p : params) {
    if (scopes_.lookup_innermost(p.name)) {
      error(SemanticKind::Redefinition, p.span,
            "redefinition of function parameter '" + p.name + "'");
      info.signature_ok = false;
      continue;
    }
    TypeRef t = p.type_expr ? resolve_type(*p.type_expr, pos) : nullptr;
    if (!t) info.signature_ok = false;
    bool writable = kind == Variable::Kind::Result || p.inout;
    p.var = new_variable(kind, p.name, p.span, t, writable);
    p.var->inout = p.inout;
    scopes_.declare(p.var);
  }
}

void Checker::check_func(ast::FuncDecl& f) {
  bool fresh = funcs_.find(f.name) == funcs_.end();
  if (find_intrinsic(f.name)) {
    // Still registered (the first one): later calls and maps of the name are checked
    // against the function as written, where checking them against the intrinsic would
    // add a knock-on error to this one.
    error(SemanticKind::Redefinition, f.name_span,
          "redefinition of intrinsic function '" + f.name + "'");
  } else if (!fresh) {
    error(SemanticKind::Redefinition, f.name_span,
          "redefinition of function or procedure '" + f.name + "'");
  } else if (f.exported && !f.generics.empty()) {
    error(SemanticKind::None, f.name_span, "exported function cannot have generic parameters");
  }
  FuncInfo& info = infos_[&f];
  func_ = &f;
  info_ = &info;
  f.frame_size = 0;
  scopes_.push();
  declare_generics(f, info);
  declare_params(f.params, Variable::Kind::Param, info);
  declare_params(f.results, Variable::Kind::Result, info);
  if (!f.is_extern) check_body(f, info);
  scopes_.pop();
  func_ = nullptr;
  info_ = nullptr;
  // Registered only now: a function is not visible to itself (§4.5.2).
  if (fresh) funcs_[f.name] = &f;
}

static bool lacks_source(const TypeRef& t) {
  if (!t) return false;
  if (t->kind == Type::Kind::Element) return !t->has_source;
  if (t->kind != Type::Kind::Tuple) return false;
  for (const auto& m : t->members)
    if (lacks_source(m)) return true;
  return false;
}

// §8.5.6 infers element sources before bodies are checked: a silent first walk of the
// body refines the parameters' types at their first uses as indices, and every use is
// then checked against the inferred sources. Variables the first walk creates are left
// orphaned (nodes may still point at them) and their frame slots are reused.
void Checker::infer_sources(ast::FuncDecl& f, FuncInfo& info) {
  Diagnostics scratch;
  Diagnostics* saved = diags_;
  auto saved_undeclared = undeclared_;
  int frame_size = f.frame_size;
  diags_ = &scratch;
  check_scoped_block(f.body);
  diags_ = saved;
  undeclared_ = std::move(saved_undeclared);
  f.frame_size = frame_size;
  info.misuses_result = false;
  info.misused_result.clear();
}

void Checker::check_body(ast::FuncDecl& f, FuncInfo& info) {
  bool infer = false;
  for (const auto& p : f.params) infer = infer || (p.var && lacks_source(p.var->type));
  if (infer) infer_sources(f, info);
  size_t before = diags_->size();
  check_scoped_block(f.body);
  info.body_ok = diags_->size() == before;
}

void Checker::check_test(ast::TestDecl& t) {
  auto it = all_funcs_.find(t.func);
  t.callee = it == all_funcs_.end() ? nullptr : it->second;
  for (auto& a : t.args) {
    if (!a) continue;
    if (!is_literal(*a)) {
      error(SemanticKind::LiteralRequired, a->span, "input to test must be a literal");
      continue;
    }
    check_expr(*a);
  }
  if (!t.expected) return;
  if (!is_literal(*t.expected)) {
    error(SemanticKind::LiteralRequired, t.expected->span,
          "expected value for test must be a literal");
    return;
  }
  check_expr(*t.expected);
}

}  // namespace checker_detail
}  // namespace simit::frontend
