// Type checker: expressions (§6) other than calls, maps and reads — literals, names,
// places, unary and binary operators, comparisons and transposes.
#include "frontend/ast_walk.h"
#include "frontend/checker_impl.h"
#include "frontend/op_typing.h"

namespace simit::frontend::checker_detail {

using ast::Variable;

ast::Variable* Checker::ivar_named(const ast::Expr& e) const {
  const auto* r = e.as<ast::VarRef>();
  if (!r) return nullptr;
  Variable* v = scopes_.lookup(r->name);
  return v && v->kind == Variable::Kind::IndexVar ? v : nullptr;
}

bool Checker::mentions_ivar(const ast::Expr& e) const {
  if (ivar_named(e)) return true;
  bool found = false;
  ast::for_each_child(e, [&](const ast::Expr& c) { found = found || mentions_ivar(c); });
  return found;
}

TypeRef Checker::check_expr(ast::Expr& e) {
  TypeRef t = dispatch_expr(e);
  e.type = t;
  return t;
}

TypeRef Checker::dispatch_expr(ast::Expr& e) {
  switch (e.kind) {
    case ast::NodeKind::IntLit: return make_scalar(ScalarKind::Int);
    case ast::NodeKind::FloatLit: return make_scalar(ScalarKind::Float);
    case ast::NodeKind::BoolLit: return make_scalar(ScalarKind::Bool);
    case ast::NodeKind::StringLit: return make_scalar(ScalarKind::String);
    case ast::NodeKind::ComplexLit: return make_scalar(ScalarKind::Complex);
    case ast::NodeKind::DenseLit: return check_dense(*e.as<ast::DenseLit>());
    case ast::NodeKind::VarRef: return check_var_ref(*e.as<ast::VarRef>(), true);
    case ast::NodeKind::Call: return check_call(*e.as<ast::Call>());
    case ast::NodeKind::TensorRead: {
      auto& r = *e.as<ast::TensorRead>();
      TypeRef base = r.base ? check_expr(*r.base) : nullptr;
      return base ? type_tensor_read(r, base) : nullptr;
    }
    case ast::NodeKind::TupleRead: {
      auto& t = *e.as<ast::TupleRead>();
      TypeRef base = t.base ? check_expr(*t.base) : nullptr;
      return base ? type_tuple_read(t, base) : nullptr;
    }
    case ast::NodeKind::FieldRead: {
      auto& f = *e.as<ast::FieldRead>();
      TypeRef base = f.base ? check_expr(*f.base) : nullptr;
      return base ? type_field_read(f, base) : nullptr;
    }
    case ast::NodeKind::SetRead: return check_set_read(*e.as<ast::SetRead>());
    case ast::NodeKind::Unary: return check_unary(*e.as<ast::Unary>());
    case ast::NodeKind::Binary: return check_binary(*e.as<ast::Binary>());
    case ast::NodeKind::Compare: return check_compare(*e.as<ast::Compare>());
    case ast::NodeKind::Transpose: return check_transpose(*e.as<ast::Transpose>());
    case ast::NodeKind::Map: return check_map(*e.as<ast::Map>());
    default: SIMIT_ASSERT(false, "not an expression node");
  }
  return nullptr;
}

TypeRef Checker::check_value(ast::Expr& e, const char* what) {
  TypeRef t = check_expr(e);
  if (!t) return nullptr;
  if (t->kind == Type::Kind::Void) {
    error(SemanticKind::Type, e.span, std::string("cannot use a void value as ") + what);
    return nullptr;
  }
  if (t->kind == Type::Kind::Multi) {
    error(SemanticKind::Type, e.span, std::string("cannot use multiple values as ") + what);
    return nullptr;
  }
  return t;
}

// Places are checked like reads, except that naming a variable there is not a read of it.
TypeRef Checker::check_place(ast::Expr& e) {
  TypeRef t;
  switch (e.kind) {
    case ast::NodeKind::VarRef: {
      auto& r = *e.as<ast::VarRef>();
      Variable* v = scopes_.lookup(r.name);
      if (v && (v->kind == Variable::Kind::IndexVar || v->kind == Variable::Kind::Generic)) {
        r.var = v;
        error(SemanticKind::NotWritable, e.span, "assignment target is not writable");
        return nullptr;
      }
      t = check_var_ref(r, false);
      break;
    }
    case ast::NodeKind::TensorRead: {
      auto& r = *e.as<ast::TensorRead>();
      TypeRef base = r.base ? check_place(*r.base) : nullptr;
      t = base ? type_tensor_read(r, base) : nullptr;
      break;
    }
    case ast::NodeKind::FieldRead: {
      auto& f = *e.as<ast::FieldRead>();
      TypeRef base = f.base ? check_place(*f.base) : nullptr;
      t = base ? type_field_read(f, base) : nullptr;
      break;
    }
    case ast::NodeKind::TupleRead: {
      auto& tr = *e.as<ast::TupleRead>();
      TypeRef base = tr.base ? check_place(*tr.base) : nullptr;
      t = base ? type_tuple_read(tr, base) : nullptr;
      break;
    }
    default: return check_expr(e);
  }
  e.type = t;
  return t;
}

TypeRef Checker::check_var_ref(ast::VarRef& r, bool read) {
  Variable* v = scopes_.lookup(r.name);
  if (!v) {
    undeclared("undeclared variable or constant", r.name, r.span);
    return nullptr;
  }
  r.var = v;
  r.writable = v->writable;
  if (v->kind == Variable::Kind::IndexVar) {
    error(SemanticKind::None, r.span,
          "index variable '" + r.name +
              "' can only be used as an index of a tensor read in an index-notation assignment");
    return nullptr;
  }
  if (v->kind == Variable::Kind::Generic) {
    if (v->ranged) return make_scalar(ScalarKind::Int);
    error(SemanticKind::Type, r.span, "generic parameter '" + r.name + "' is not a value");
    return nullptr;
  }
  if (read && v->kind == Variable::Kind::Result && info_ && !info_->misuses_result) {
    info_->misuses_result = true;
    info_->misuse_span = r.span;
    info_->misused_result = r.name;
  }
  return v->type;
}

TypeRef Checker::check_dense(ast::DenseLit& d) {
  if (!d.shape_error.empty()) {
    bool kind_error = d.shape_error.find("type") != std::string::npos;
    error(kind_error ? SemanticKind::Type : SemanticKind::Dimension, d.span, d.shape_error);
    return nullptr;
  }
  std::vector<IndexSet> dims;
  for (int n : d.shape) {
    if (n < 1) return nullptr;  // the parser never builds empty literals
    dims.push_back(IndexSet::fixed(n));
  }
  if (dims.empty()) return nullptr;
  bool row = dims.size() == 1 && !d.column;
  return make_tensor(std::move(dims), make_scalar(d.component), row);
}

// Operator typing prints operand types; elements of a generic set have no name to print.
bool Checker::operands_ok(ast::Expr& at, const std::vector<const Type*>& operands) {
  for (const Type* t : operands) {
    if (t->kind == Type::Kind::Element && !t->element) {
      error(SemanticKind::Type, at.span,
            "expected a numeric tensor operand but got an " + type_name(*t));
      return false;
    }
  }
  return true;
}

static void report(Diagnostics& diags, const Typing& r, SourceSpan at) {
  diags.semantic(r.kind, at, r.error.empty() ? "invalid operand types" : r.error);
}

TypeRef Checker::check_unary(ast::Unary& u) {
  TypeRef t = u.operand ? check_value(*u.operand, "an operand") : nullptr;
  if (!t || !operands_ok(u, {t.get()})) return nullptr;
  Typing r = type_unary(u.op, *t);
  if (!r.ok()) report(*diags_, r, u.span);
  return r.type;
}

TypeRef Checker::check_binary(ast::Binary& b) {
  if (in_index_ && (b.op == ast::Binary::Op::Div || b.op == ast::Binary::Op::LeftDiv)) {
    error(SemanticKind::None, b.span, "division is not allowed in an index-notation assignment");
    return nullptr;
  }
  TypeRef l = b.lhs ? check_value(*b.lhs, "an operand") : nullptr;
  TypeRef r = l && b.rhs ? check_value(*b.rhs, "an operand") : nullptr;
  if (!l || !r || !operands_ok(b, {l.get(), r.get()})) return nullptr;
  ast::Binary::Op op = b.op;
  // In index notation `*` multiplies components (§7.2), not matrices.
  if (in_index_ && op == ast::Binary::Op::Mul && (mentions_ivar(*b.lhs) || mentions_ivar(*b.rhs)))
    op = ast::Binary::Op::ElemMul;
  Typing t = type_binary(op, *l, *r);
  if (!t.ok()) report(*diags_, t, b.span);
  return t.type;
}

TypeRef Checker::check_compare(ast::Compare& c) {
  std::vector<TypeRef> types;
  for (auto& o : c.operands) {
    TypeRef t = o ? check_value(*o, "an operand") : nullptr;
    // Debugger conditions such as `t == 17` name an element by its index.
    if (t && debug_expr_ && t->kind == Type::Kind::Element) t = make_scalar(ScalarKind::Int);
    if (!t || !operands_ok(c, {t.get()})) return nullptr;
    types.push_back(t);
  }
  for (size_t i = 0; i < c.ops.size() && i + 1 < types.size(); ++i) {
    Typing t = type_compare(c.ops[i], *types[i], *types[i + 1]);
    if (!t.ok()) {
      report(*diags_, t, c.span);
      return nullptr;
    }
  }
  return make_scalar(ScalarKind::Bool);
}

TypeRef Checker::check_transpose(ast::Transpose& t) {
  TypeRef o = t.operand ? check_value(*t.operand, "an operand") : nullptr;
  if (!o || !operands_ok(t, {o.get()})) return nullptr;
  Typing r = type_transpose(*o);
  if (!r.ok()) report(*diags_, r, t.span);
  return r.type;
}

}  // namespace simit::frontend::checker_detail
