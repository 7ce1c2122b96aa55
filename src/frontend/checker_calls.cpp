// Type checker: calls of intrinsics and user functions, generic binding (§4.5.3-4.5.4),
// and assembly with `map` and `apply` (§8.5-8.7).
#include "frontend/checker_impl.h"
#include "frontend/op_typing.h"

namespace simit::frontend::checker_detail {

using ast::Variable;

TypeRef Checker::check_call(ast::Call& c) {
  auto it = funcs_.find(c.callee);
  // A function named like an intrinsic (an error check_func reports) takes the name's calls
  // after it: checked against the intrinsic, they would add knock-on errors.
  auto id = find_intrinsic(c.callee);
  if (id && it == funcs_.end()) return check_intrinsic_call(c, *id);
  if (it == funcs_.end()) {
    undeclared("undeclared function", c.callee, c.callee_span.valid() ? c.callee_span : c.span);
    return nullptr;
  }
  const ast::FuncDecl& f = *it->second;
  c.func = &f;
  std::vector<IndexSet> explicit_args;
  if (!resolve_generic_args(c.generic_args, explicit_args)) return nullptr;
  if (explicit_args.size() > f.generics.size()) {
    error(SemanticKind::Arity, c.span,
          "passed " + std::to_string(explicit_args.size()) + " generic arguments but function '" +
              f.name + "' has " + std::to_string(f.generics.size()) + " generic parameters");
    return nullptr;
  }
  ArgList args;
  if (!check_args(c.args, args)) return nullptr;
  if (args.types.size() != f.params.size()) {
    error(SemanticKind::Arity, c.span,
          "passed in " + std::to_string(args.types.size()) + " arguments but function '" + f.name +
              "' expects " + std::to_string(f.params.size()));
    return nullptr;
  }
  if (!infos_[&f].signature_ok) return nullptr;
  Subst s;
  if (!bind_generics(f, explicit_args, args, c.span, s, c.bindings)) return nullptr;
  if (!check_arg_types(f, args, s, c.span, false)) return nullptr;
  return result_type(f, s, c.span);
}

TypeRef Checker::check_intrinsic_call(ast::Call& c, Intrinsic id) {
  c.intrinsic = id;
  std::vector<IndexSet> explicit_args;
  if (!resolve_generic_args(c.generic_args, explicit_args)) return nullptr;
  ArgList args;
  if (!check_args(c.args, args)) return nullptr;
  std::vector<const Type*> types;
  for (const auto& t : args.types) types.push_back(t.get());
  if (!operands_ok(c, types)) return nullptr;
  c.bindings.clear();
  Typing r = type_intrinsic_call(id, types, explicit_args, c.bindings);
  if (!r.ok())
    diags_->semantic(r.kind, c.span, r.error.empty() ? "invalid intrinsic call" : r.error);
  return r.type;
}

bool Checker::check_args(std::vector<ast::ExprPtr>& args, ArgList& out) {
  bool ok = true;
  for (auto& a : args) {
    if (!a) {
      ok = false;
      continue;
    }
    if (in_index_ && mentions_ivar(*a)) {
      error(SemanticKind::None, a->span,
            "index variables cannot be used in call arguments of an index-notation assignment");
      ok = false;
      continue;
    }
    TypeRef t = check_expr(*a);
    if (t && t->kind == Type::Kind::Void) {
      error(SemanticKind::Type, a->span, "must pass a non-void value as argument");
      t = nullptr;
    } else if (t && t->kind == Type::Kind::Multi) {
      error(SemanticKind::Type, a->span, "cannot pass multiple values as a single argument");
      t = nullptr;
    }
    if (!t) {
      ok = false;
      continue;
    }
    const auto* ref = a->as<ast::VarRef>();
    out.types.push_back(t);
    out.exprs.push_back(a.get());
    out.set_vars.push_back(ref && is_set_var(ref->var) ? ref->var : nullptr);
  }
  return ok;
}

bool Checker::resolve_generic_args(std::vector<ast::IndexSetExpr>& args,
                                   std::vector<IndexSet>& out) {
  for (auto& d : args) {
    if (!resolve_dim(d, true)) return false;
    out.push_back(d.resolved);
  }
  return true;
}

// Binds the callee's generic parameters (explicit arguments first, then by unification,
// first binding wins) and its set parameters (to the sets their arguments name).
bool Checker::bind_generics(const ast::FuncDecl& f, const std::vector<IndexSet>& explicit_args,
                            const ArgList& args, SourceSpan at, Subst& s,
                            std::vector<IndexSet>& bindings) {
  for (size_t i = 0; i < explicit_args.size() && i < f.generics.size(); ++i) {
    const Variable* g = f.generics[i].var;
    if (g->ranged && !is_int_dim(explicit_args[i])) {
      error(SemanticKind::Type, at,
            "generic parameter '" + g->name + "' of '" + f.name +
                "' is ranged and can only be bound to an integer size");
      return false;
    }
    s[g] = explicit_args[i];
  }
  for (size_t i = 0; i < f.params.size() && i < args.types.size(); ++i)
    if (is_set_var(f.params[i].var) && args.set_vars[i])
      s.emplace(f.params[i].var, IndexSet::set(args.set_vars[i]));
  for (size_t i = 0; i < f.params.size() && i < args.types.size(); ++i)
    unify(*f.params[i].var->type, *args.types[i], f, s);
  bindings.clear();
  for (const auto& g : f.generics) {
    auto it = s.find(g.var);
    if (it == s.end()) {
      if (report_order_mismatch(f, args, s, at)) return false;
      error(SemanticKind::GenericUnresolved, at,
            "unable to resolve type parameter '" + g.name + "' for call to function '" + f.name +
                "'");
      return false;
    }
    bindings.push_back(it->second);
  }
  return true;
}

// A tensor argument whose shape cannot match its parameter leaves generics unbound; that
// is an argument type mismatch (§11.4), not an unresolvable parameter.
bool Checker::report_order_mismatch(const ast::FuncDecl& f, const ArgList& args, const Subst& s,
                                    SourceSpan at) {
  for (size_t i = 0; i < f.params.size() && i < args.types.size(); ++i) {
    const Type& p = *f.params[i].var->type;
    const Type& a = *args.types[i];
    if (p.kind == Type::Kind::Tensor && a.kind == Type::Kind::Tensor && p.order() != a.order()) {
      error(SemanticKind::Type, args.exprs[i] ? args.exprs[i]->span : at,
            "expected argument of type " + quoted(*substitute(f.params[i].var->type, s)) +
                " but got an argument of type " + quoted(a));
      return true;
    }
  }
  return false;
}

void Checker::unify(const Type& param, const Type& arg, const ast::FuncDecl& f, Subst& s) {
  auto bindable = [&](const IndexSet& d) {
    return d.kind == IndexSet::Kind::Generic && d.var && d.var->func == &f &&
           d.var->kind == Variable::Kind::Generic && !s.count(d.var);
  };
  switch (param.kind) {
    case Type::Kind::Tensor:
      if (arg.kind != Type::Kind::Tensor || arg.dims.size() != param.dims.size()) return;
      for (size_t i = 0; i < param.dims.size(); ++i) {
        const IndexSet& d = param.dims[i];
        if (!bindable(d) || (d.var->ranged && !is_int_dim(arg.dims[i]))) continue;
        s[d.var] = arg.dims[i];
      }
      if (param.block && arg.block) unify(*param.block, *arg.block, f, s);
      return;
    case Type::Kind::Element:
      if (param.has_source && bindable(param.source) && !param.source.var->ranged &&
          arg.kind == Type::Kind::Element && arg.has_source)
        s[param.source.var] = arg.source;
      return;
    case Type::Kind::Tuple:
      if (arg.kind != Type::Kind::Tuple) return;
      for (size_t k = 0; k < param.members.size() && k < arg.members.size(); ++k)
        if (param.members[k] && arg.members[k]) unify(*param.members[k], *arg.members[k], f, s);
      return;
    default: return;
  }
}

static std::string mismatch(const Type& expected, const Type& got) {
  if (expected.kind == Type::Kind::Element && got.kind == Type::Kind::Element &&
      expected.element == got.element && expected.has_source && got.has_source) {
    return "expected an element of set '" + index_set_name(expected.source) +
           "' but got an element of set '" + index_set_name(got.source) + "'";
  }
  return "";
}

bool Checker::check_arg_types(const ast::FuncDecl& f, const ArgList& args, const Subst& s,
                              SourceSpan at, bool is_map) {
  for (size_t i = 0; i < f.params.size() && i < args.types.size(); ++i) {
    const Variable* p = f.params[i].var;
    TypeRef expected = substitute(p->type, s);
    const Type& got = *args.types[i];
    SourceSpan span = args.exprs[i] ? args.exprs[i]->span : at;
    if (!same_type(*expected, got)) {
      std::string detail = mismatch(*expected, got);
      std::string msg = is_map ? "map operation passes argument of type " + quoted(got) +
                                     " to assembly function '" + f.name +
                                     "' but function expects argument of type " + quoted(*expected)
                               : "expected argument of type " + quoted(*expected) +
                                     " but got an argument of type " + quoted(got);
      error(SemanticKind::Type, span, detail.empty() ? msg : msg + " (" + detail + ")");
      return false;
    }
    if (p->inout && args.exprs[i] && !args.exprs[i]->writable) {
      error(SemanticKind::NotWritable, span, "inout argument must be writable");
      return false;
    }
  }
  return true;
}

// The value of a call: its results after substitution. Only tensor and opaque results
// reach a caller (§4.5.2).
TypeRef Checker::result_type(const ast::FuncDecl& f, const Subst& s, SourceSpan at) {
  std::vector<TypeRef> results;
  for (const auto& r : f.results) {
    TypeRef t = substitute(r.var->type, s);
    if (!is_tensor_or_opaque(*t)) {
      error(SemanticKind::Type, at,
            "cannot use function '" + f.name + "': its result '" + r.name + "' has type " +
                quoted(*t) + ", which cannot be returned to a caller");
      return nullptr;
    }
    results.push_back(t);
  }
  if (results.empty()) return make_void();
  if (results.size() == 1) return results[0];
  return make_multi(std::move(results));
}

// ---------------------------------------------------------------------------
// map and apply

const ast::Variable* Checker::lookup_set(const std::string& name, SourceSpan span, bool is_target) {
  Variable* v = scopes_.lookup(name);
  if (!v) {
    undeclared("undeclared set", name, span);
    return nullptr;
  }
  if (v->kind == Variable::Kind::Generic) {
    error(SemanticKind::Type, span,
          is_target ? "map operation cannot be applied to a generic set"
                    : "expected a set but '" + name + "' is a generic parameter");
    return nullptr;
  }
  if (is_set_var(v)) return v;
  if (v->type)
    error(SemanticKind::Type, span,
          "expected a set but '" + name + "' is of type " + quoted(*v->type));
  else if (v->kind == Variable::Kind::IndexVar)
    error(SemanticKind::Type, span, "expected a set but '" + name + "' is an index variable");
  return nullptr;
}

TypeRef Checker::check_map(ast::Map& m) {
  Subst s;
  const Variable* through = nullptr;
  if (!check_assembly(m.assembly, m.through, m.through_span, &through, m.span, s, false))
    return nullptr;
  m.through_set = through;
  const ast::FuncDecl& f = *m.assembly.callee;
  if (!check_map_results(m, f, s)) return nullptr;
  return result_type(f, s, m.span);
}

static bool has_set_dims(const Type& t) {
  if (t.kind != Type::Kind::Tensor) return false;
  for (const auto& d : t.dims)
    if (d.kind == IndexSet::Kind::Fixed || (d.kind == IndexSet::Kind::Generic && d.var->ranged))
      return false;
  return true;
}

// Results of a mapped function are global tensors assembled from indexed writes
// (§8.5.4): they need set dimensions, and the function may not read them or assign
// them whole (Q10, Q19).
bool Checker::check_map_results(const ast::Map& m, const ast::FuncDecl& f, const Subst& s) {
  for (const auto& r : f.results) {
    TypeRef t = substitute(r.var->type, s);
    if (!has_set_dims(*t)) {
      error(SemanticKind::Type, m.span,
            "result '" + r.name + "' of mapped function '" + f.name + "' has type " + quoted(*t) +
                "; map results must have set dimensions");
      return false;
    }
  }
  const FuncInfo& info = infos_[&f];
  if (info.misuses_result && info.body_ok) {
    // Reported where the function misuses its result: that is what must change.
    error(SemanticKind::None, info.misuse_span,
          "function '" + f.name + "' cannot be mapped: it reads or assigns whole its result '" +
              info.misused_result + "', which only indexed writes may assemble");
    return false;
  }
  return true;
}

bool Checker::check_assembly(ast::Assembly& a, const std::string& through, SourceSpan through_span,
                             const Variable** through_var, SourceSpan at, Subst& s, bool is_apply) {
  auto it = funcs_.find(a.func);
  if (it == funcs_.end()) {
    if (find_intrinsic(a.func))
      error(SemanticKind::Type, a.func_span, "cannot map the intrinsic function '" + a.func + "'");
    else
      undeclared("undeclared function", a.func, a.func_span);
    return false;
  }
  const ast::FuncDecl& f = *it->second;
  a.callee = &f;
  if (is_apply && !f.results.empty()) {
    error(SemanticKind::None, at, "cannot apply a non-void function");
    return false;
  }
  a.target_set = lookup_set(a.target, a.target_span, true);
  if (!a.target_set) return false;
  const Variable* grid = nullptr;
  if (!through.empty()) {
    grid = lookup_set(through, through_span, false);
    if (!grid) return false;
    if (grid->type->grid_dims == 0) {
      error(SemanticKind::Type, through_span,
            "map operation can only be applied through grid edge sets");
      return false;
    }
    if (grid->type->endpoints.empty() || grid->type->endpoints[0].var != a.target_set) {
      error(SemanticKind::Type, through_span,
            "map operation can only be applied through grid edge set with target '" + a.target +
                "' as an endpoint");
      return false;
    }
    *through_var = grid;
  }
  std::vector<IndexSet> explicit_args;
  if (!resolve_generic_args(a.generic_args, explicit_args)) return false;
  if (explicit_args.size() > f.generics.size()) {
    error(SemanticKind::Arity, at, "too many generic arguments for function '" + f.name + "'");
    return false;
  }
  ArgList args;
  if (!assembly_args(a, f, grid, at, args) || !infos_[&f].signature_ok) return false;
  if (!bind_generics(f, explicit_args, args, at, s, a.bindings)) return false;
  return check_arg_types(f, args, s, at, true);
}

bool Checker::check_partial_args(ast::Assembly& a, ArgList& args) {
  for (auto& p : a.args) {
    TypeRef t = p ? check_expr(*p) : nullptr;
    if (!t) return false;
    if (!is_single_value(*t) || !is_tensor_or_opaque(*t)) {
      error(SemanticKind::Type, p->span,
            "expected argument to be a tensor or opaque but got an argument of type " + quoted(*t));
      return false;
    }
    args.types.push_back(t);
    args.exprs.push_back(p.get());
    args.set_vars.push_back(nullptr);
  }
  return true;
}

// §8.5.2: partial arguments, the element, the endpoint tuple when the function wants it,
// and the grid of a `through` map.
bool Checker::assembly_args(ast::Assembly& a, const ast::FuncDecl& f, const Variable* grid,
                            SourceSpan at, ArgList& args) {
  if (!check_partial_args(a, args)) return false;
  const Type& set = *a.target_set->type;
  IndexSet self = IndexSet::set(a.target_set);
  args.types.push_back(element_type(set.element, self, true));
  args.exprs.push_back(nullptr);
  args.set_vars.push_back(nullptr);
  size_t implicit = args.types.size() + (grid ? 1 : 0);
  a.pass_endpoints = set.grid_dims == 0 && !set.endpoints.empty() && f.params.size() > implicit;
  if (a.pass_endpoints) {
    std::vector<TypeRef> members;
    for (const auto& e : set.endpoints) {
      const ast::ElementDecl* d = e.var && e.var->type ? e.var->type->element : nullptr;
      members.push_back(element_type(d, e, true));
    }
    args.types.push_back(tuple_type(std::move(members), {}));
    args.exprs.push_back(nullptr);
    args.set_vars.push_back(nullptr);
  }
  if (grid) {
    args.types.push_back(grid->type);
    args.exprs.push_back(nullptr);
    args.set_vars.push_back(grid);
  }
  if (args.types.size() != f.params.size()) {
    error(SemanticKind::Arity, at,
          "map operation passes " + std::to_string(args.types.size()) +
              " arguments to assembly function but function '" + f.name + "' expects " +
              std::to_string(f.params.size()));
    return false;
  }
  return true;
}

}  // namespace simit::frontend::checker_detail
