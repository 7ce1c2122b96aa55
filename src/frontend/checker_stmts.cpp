// Type checker: statements (§7) — declarations, assignments, control flow, print, apply.
#include "frontend/checker_impl.h"

namespace simit::frontend::checker_detail {

using ast::Variable;

void Checker::check_scoped_block(ast::Block& b) {
  scopes_.push();
  check_block(b);
  scopes_.pop();
}

void Checker::check_block(ast::Block& b) {
  for (auto& s : b)
    if (s) check_stmt(*s);
}

void Checker::check_stmt(ast::Stmt& s) {
  switch (s.kind) {
    case ast::NodeKind::VarDecl: check_var_decl(*s.as<ast::VarDecl>()); break;
    case ast::NodeKind::IvarDecl: check_ivar_decl(*s.as<ast::IvarDecl>()); break;
    case ast::NodeKind::Assign: check_assign(*s.as<ast::Assign>()); break;
    case ast::NodeKind::ExprStmt: {
      auto& e = *s.as<ast::ExprStmt>();
      if (e.expr) check_expr(*e.expr);
      break;
    }
    case ast::NodeKind::If: {
      auto& i = *s.as<ast::If>();
      for (size_t k = 0; k < i.conditions.size(); ++k) {
        if (i.conditions[k]) check_condition(*i.conditions[k]);
        if (k < i.branches.size()) check_scoped_block(i.branches[k]);
      }
      if (i.has_else) check_scoped_block(i.else_branch);
      break;
    }
    case ast::NodeKind::While: {
      auto& w = *s.as<ast::While>();
      if (w.condition) check_condition(*w.condition);
      check_scoped_block(w.body);
      break;
    }
    case ast::NodeKind::DoWhile: {
      auto& d = *s.as<ast::DoWhile>();
      check_scoped_block(d.body);  // names of the body are not visible in the condition
      if (d.condition) check_condition(*d.condition);
      break;
    }
    case ast::NodeKind::ForRange: check_for_range(*s.as<ast::ForRange>()); break;
    case ast::NodeKind::ForSet: check_for_set(*s.as<ast::ForSet>()); break;
    case ast::NodeKind::Print: check_print(*s.as<ast::Print>()); break;
    case ast::NodeKind::Apply: check_apply(*s.as<ast::Apply>()); break;
    default: SIMIT_ASSERT(false, "not a statement node");
  }
}

// ---------------------------------------------------------------------------
// Declarations

// §10.3 lenient const typing: equal blocks, and dimension lists equal once leading
// 1-sized integer dimensions are dropped, orientation ignored.
static bool const_lenient(const Type& declared, const Type& value) {
  if (declared.kind != Type::Kind::Tensor || value.kind != Type::Kind::Tensor) return false;
  if (!declared.block || !value.block || !types_equal(*declared.block, *value.block)) return false;
  auto strip = [](const std::vector<IndexSet>& dims) {
    size_t k = 0;
    while (k + 1 < dims.size() && dims[k] == IndexSet::fixed(1)) ++k;
    return std::vector<IndexSet>(dims.begin() + static_cast<long>(k), dims.end());
  };
  return strip(declared.dims) == strip(value.dims);
}

// Vector types that differ only in orientation print alike but for one `'`; the messages
// name the orientations instead and suggest the transpose.
static bool differ_in_orientation(const Type& a, const Type& b) {
  if (a.kind != Type::Kind::Tensor || b.kind != Type::Kind::Tensor || a.order() != 1 ||
      a.row == b.row)
    return false;
  Type flipped = b;
  flipped.row = a.row;
  return same_type(a, flipped);
}

// "row vector (vector[3](float)')", or with `what` "column vector target (vector[3](float))".
static std::string oriented(const Type& t, const std::string& what = "") {
  return std::string(t.row ? "row" : "column") + " vector " + (what.empty() ? "" : what + " ") +
         "(" + type_name(t) + ")";
}

static const char* const kTransposeHint = ": transpose it with the ' operator";

bool Checker::check_initializer(SourceSpan at, const Type& declared, const Type& value,
                                bool is_const, bool global) {
  if (!value.is_tensor()) {
    error(SemanticKind::Type, at,
          "cannot declare a non-tensor variable: the initial value has type " + quoted(value));
    return false;
  }
  if (same_type(declared, value)) return true;
  if (value.is_scalar() && !declared.is_scalar()) {
    if (global) {
      error(SemanticKind::Type, at,
            "a non-scalar global constant cannot be initialized with a scalar literal");
      return false;
    }
    if (value.scalar == declared.component()) return true;
  }
  if (is_const && const_lenient(declared, value)) return true;
  if (differ_in_orientation(declared, value)) {
    error(SemanticKind::Type, at,
          "cannot initialize a " + oriented(declared, "variable") + " with a " + oriented(value) +
              kTransposeHint);
    return false;
  }
  error(SemanticKind::Type, at,
        "cannot initialize a variable of type " + quoted(declared) + " with a value of type " +
            quoted(value));
  return false;
}

void Checker::check_var_decl(ast::VarDecl& v) {
  if (scopes_.lookup_innermost(v.name)) {
    error(SemanticKind::Redefinition, v.name_span,
          "redefinition of variable or constant '" + v.name + "'");
    return;
  }
  TypeRef declared = v.declared ? resolve_type(*v.declared, TypePos::Local) : nullptr;
  TypeRef type = declared;
  if (v.init && (declared || !v.declared)) {
    TypeRef init = check_expr(*v.init);
    if (init && init->kind == Type::Kind::Multi) {
      error(SemanticKind::Arity, v.init->span,
            "cannot assign an expression returning " + std::to_string(init->members.size()) +
                " values to 1 targets");
    } else if (init && init->kind == Type::Kind::Void) {
      error(SemanticKind::Type, v.init->span, "cannot initialize a variable with a void value");
    } else if (init && declared) {
      check_initializer(v.init->span, *declared, *init, v.is_const, false);
    } else if (init && !init->is_tensor()) {
      error(SemanticKind::Type, v.init->span,
            "cannot declare a non-tensor variable of type " + quoted(*init));
    } else if (!declared) {
      type = init;
    }
  }
  v.var = new_variable(Variable::Kind::Local, v.name, v.name_span, type, !v.is_const);
  scopes_.declare(v.var);
}

void Checker::check_ivar_decl(ast::IvarDecl& v) {
  if (scopes_.lookup_innermost(v.name)) {
    error(SemanticKind::Redefinition, v.span,
          "redefinition of variable or constant '" + v.name + "'");
    return;
  }
  v.var = new_variable(Variable::Kind::IndexVar, v.name, v.span, nullptr, false);
  scopes_.declare(v.var);
}

// ---------------------------------------------------------------------------
// Assignment (§7.1)

void Checker::check_assign(ast::Assign& a) {
  bool index_notation = a.value && mentions_ivar(*a.value);
  for (const auto& t : a.targets) index_notation = index_notation || (t && mentions_ivar(*t));
  a.declares.assign(a.targets.size(), nullptr);
  if (index_notation) {
    check_index_assign(a);
    return;
  }
  TypeRef value = a.value ? check_expr(*a.value) : nullptr;
  size_t count = !value                             ? 0
                 : value->kind == Type::Kind::Void  ? 0
                 : value->kind == Type::Kind::Multi ? value->members.size()
                                                    : 1;
  if (value && count != a.targets.size()) {
    error(SemanticKind::Arity, a.span,
          "cannot assign an expression returning " + std::to_string(count) + " values to " +
              std::to_string(a.targets.size()) + " targets");
    value = nullptr;
  }
  for (size_t i = 0; i < a.targets.size(); ++i) {
    if (!a.targets[i]) continue;
    TypeRef v = !value ? nullptr : count == 1 ? value : value->members[i];
    assign_target(a, i, v);
  }
}

// `value` is null after an error in the right side: names are still declared so that
// later statements do not report them as undeclared.
void Checker::assign_target(ast::Assign& a, size_t i, const TypeRef& value) {
  ast::Expr& t = *a.targets[i];
  auto* ref = t.as<ast::VarRef>();
  if (ref && !scopes_.lookup(ref->name)) {
    declare_implicit(a, i, value);
    return;
  }
  if (!value) return;
  TypeRef target = check_place(t);
  if (!target) return;
  if (!target->is_tensor() && target->kind != Type::Kind::Opaque) {
    error(SemanticKind::Type, t.span, "cannot assign to a target of type " + quoted(*target));
    return;
  }
  if (!t.writable) {
    not_writable(t);
    return;
  }
  if (!is_tensor_or_opaque(*value)) {
    error(SemanticKind::Type, a.value->span,
          "cannot assign a non-tensor/opaque value of type " + quoted(*value) + " to a variable");
    return;
  }
  if (!check_assignable(a.value->span, *target, *value)) return;
  if (ref && ref->var && ref->var->kind == Variable::Kind::Result && info_ &&
      !info_->misuses_result) {
    info_->misuses_result = true;
    info_->misuse_span = t.span;
    info_->misused_result = ref->name;
  }
}

// The variable a target names, read whole or through element reads (`v`, `v(i)`, `A(i,j)`),
// or null for anything else: a slice, a field, a literal or a call.
static const Variable* named_target(const ast::Expr& t) {
  const ast::Expr* e = &t;
  while (const auto* r = e->as<ast::TensorRead>()) {
    for (const auto& index : r->indices)
      if (!index) return nullptr;
    if (!r->base) return nullptr;
    e = r->base.get();
  }
  const auto* ref = e->as<ast::VarRef>();
  return ref ? ref->var : nullptr;
}

// Programs ported from the original Simit bind a name more than once; where declaring the
// name with `var` would make the assignment legal, the message says so.
void Checker::not_writable(const ast::Expr& t) {
  std::string message = "assignment target is not writable";
  const Variable* v = named_target(t);
  if (v && !v->writable && v->type && v->type->is_tensor()) {
    const std::string& n = v->name;
    if (v->kind == Variable::Kind::Implicit)
      message += ": '" + n +
                 "' was declared by its first assignment, which makes it read-only; declare it "
                 "with 'var' to assign it again";
    else if (v->kind == Variable::Kind::Local)
      message += ": '" + n + "' is a local 'const'; declare it with 'var' to assign it again";
    else if (v->kind == Variable::Kind::Param)
      message += ": parameter '" + n +
                 "' is read-only; to change a copy, declare one with 'var' ('var " + n + " = " + n +
                 ";')";
  }
  error(SemanticKind::NotWritable, t.span, std::move(message));
}

void Checker::declare_implicit(ast::Assign& a, size_t i, const TypeRef& value) {
  auto& ref = *a.targets[i]->as<ast::VarRef>();
  TypeRef type = value;
  if (value && !is_tensor_or_opaque(*value)) {
    error(SemanticKind::Type, a.value->span,
          "cannot assign a non-tensor/opaque value of type " + quoted(*value) + " to a variable");
    type = nullptr;
  }
  Variable* v = new_variable(Variable::Kind::Implicit, ref.name, ref.span, type, false);
  scopes_.declare(v);
  ref.var = v;
  ref.type = type;
  a.declares[i] = v;
}

bool Checker::check_assignable(SourceSpan at, const Type& target, const Type& value) {
  if (same_type(target, value)) return true;
  if (value.is_scalar() && target.kind == Type::Kind::Tensor && value.scalar == target.component())
    return true;
  if (differ_in_orientation(target, value)) {
    error(SemanticKind::Type, at,
          "cannot assign a " + oriented(value) + " to a " + oriented(target, "target") +
              kTransposeHint);
    return false;
  }
  error(
      SemanticKind::Type, at,
      "cannot assign a value of type " + quoted(value) + " to a target of type " + quoted(target));
  return false;
}

// ---------------------------------------------------------------------------
// Control flow, print, apply

void Checker::check_condition(ast::Expr& e) {
  TypeRef t = check_value(e, "a condition");
  if (t && !is_bool(*t))
    error(SemanticKind::Type, e.span,
          "expected a boolean conditional expression but got an expression of type " + quoted(*t));
}

void Checker::check_for_range(ast::ForRange& f) {
  const char* names[] = {"lower", "upper"};
  ast::Expr* bounds[] = {f.lo.get(), f.hi.get()};
  for (int k = 0; k < 2; ++k) {
    TypeRef t = bounds[k] ? check_value(*bounds[k], "a loop bound") : nullptr;
    if (t && !is_int(*t))
      error(SemanticKind::Type, bounds[k]->span,
            std::string("expected ") + names[k] +
                " bound of for-loop range to be integral but got " + quoted(*t));
  }
  scopes_.push();
  f.var = new_variable(Variable::Kind::LoopVar, f.var_name, f.var_span,
                       make_scalar(ScalarKind::Int), false);
  scopes_.declare(f.var);
  check_block(f.body);
  scopes_.pop();
}

void Checker::check_for_set(ast::ForSet& f) {
  Variable* d = scopes_.lookup(f.domain);
  TypeRef type;
  if (!d) {
    undeclared("undeclared set", f.domain, f.domain_span);
  } else if (d->kind == Variable::Kind::Generic) {
    f.domain_var = d;
    type = generic_element_type(d);
  } else if (is_set_var(d)) {
    f.domain_var = d;
    type = element_type(d->type->element, IndexSet::set(d), true);
  } else if (d->type) {
    error(SemanticKind::Type, f.domain_span,
          "expected a set but '" + f.domain + "' is of type " + quoted(*d->type));
  } else {
    error(SemanticKind::Type, f.domain_span,
          "expected a set but '" + f.domain + "' is not a value");
  }
  scopes_.push();
  f.var = new_variable(Variable::Kind::LoopVar, f.var_name, f.var_span, type, false);
  scopes_.declare(f.var);
  check_block(f.body);
  scopes_.pop();
}

// An error statement's arguments follow print's rules: its message is what println prints.
void Checker::check_print(ast::Print& p) {
  const bool err = p.is_error();
  for (auto& a : p.args) {
    TypeRef t = a ? check_value(*a, err ? "an error argument" : "a print argument") : nullptr;
    if (t && !t->is_tensor())
      error(SemanticKind::Type, a->span,
            std::string(err ? "cannot show an expression of type " + quoted(*t) +
                                  " in an error message"
                            : "cannot print an expression of type " + quoted(*t)));
  }
}

void Checker::check_apply(ast::Apply& a) {
  Subst s;
  const Variable* through = nullptr;
  check_assembly(a.assembly, "", SourceSpan{}, &through, a.span, s, true);
}

}  // namespace simit::frontend::checker_detail
