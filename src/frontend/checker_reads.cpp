// Type checker: reads (§6.3) — tensor reads and slices with their index checks and element
// source inference, field reads of elements and sets, tuple reads, and grid set reads.
#include "frontend/checker_impl.h"

namespace simit::frontend::checker_detail {

using ast::Variable;

// ---------------------------------------------------------------------------
// Tensor reads (§6.3.3, §6.3.4)

TypeRef Checker::type_tensor_read(ast::TensorRead& r, const TypeRef& base) {
  if (!is_single_value(*base)) {
    error(SemanticKind::Type, r.span,
          "cannot read from a " + std::string(base->kind == Type::Kind::Void
                                                  ? "void value"
                                                  : "call with multiple results"));
    return nullptr;
  }
  if (base->kind != Type::Kind::Tensor) {
    error(SemanticKind::Type, r.span,
          "expected left operand of tensor access to be a tensor but got " + quoted(*base));
    return nullptr;
  }
  if (r.indices.size() != base->dims.size()) {
    error(SemanticKind::Arity, r.span,
          "tensor access expected " + std::to_string(base->dims.size()) + " indices but got " +
              std::to_string(r.indices.size()));
    return nullptr;
  }
  bool has_slice = false, has_ivar = false, ok = true;
  for (size_t i = 0; i < r.indices.size() && ok; ++i) {
    if (!r.indices[i]) {
      has_slice = true;
      continue;
    }
    bool is_ivar = false;
    ok = check_index(r, i, base->dims[i], &is_ivar) != nullptr;
    has_ivar |= is_ivar;
  }
  if (!ok) return nullptr;
  if (has_slice && has_ivar) {
    error(SemanticKind::None, r.span, "Cannot mix index expression and slice");
    return nullptr;
  }
  r.index_notation = has_ivar;
  r.writable = r.base->writable && !has_slice;
  return has_slice ? slice_type(r, *base) : base->block;
}

TypeRef Checker::check_index(ast::TensorRead& r, size_t i, const IndexSet& dim, bool* is_ivar) {
  ast::Expr& index = *r.indices[i];
  if (ivars_ok_) {
    if (Variable* iv = ivar_named(index)) {
      index.as<ast::VarRef>()->var = iv;
      index.type = make_scalar(ScalarKind::Int);
      *is_ivar = true;
      record_ivar(iv, dim, index.span);
      return index.type;
    }
  }
  // Index variables nested inside an index expression are not indices (§7.2).
  bool saved = ivars_ok_;
  ivars_ok_ = false;
  TypeRef t = check_value(index, "an index");
  ivars_ok_ = saved;
  if (!t || !check_set_index(r, index, *t, dim)) return nullptr;
  return t;
}

static std::string index_error(const std::string& expected, const Type& t) {
  if (t.kind == Type::Kind::Element)
    return "expected " + expected + " as index but got an element of type " + quoted(t);
  return "expected " + expected + " as index but got an index of type " + quoted(t);
}

bool Checker::check_set_index(ast::TensorRead& r, ast::Expr& index, const Type& t,
                              const IndexSet& dim) {
  if (is_int_dim(dim)) {
    if (is_int(t)) return true;
    error(SemanticKind::Type, index.span,
          "expected an integral index but got an index of type " + quoted(t));
    return false;
  }
  // A debugger expression may name an element by its index: `print verts.x(3)`.
  if (debug_expr_ && is_int(t)) return true;
  std::string set_desc = dim.kind == IndexSet::Kind::Set
                             ? "an element of set '" + index_set_name(dim) + "'"
                             : "an element of '" + index_set_name(dim) + "'";
  if (t.kind != Type::Kind::Element) {
    error(SemanticKind::Type, index.span, index_error(set_desc, t));
    return false;
  }
  if (dim.kind == IndexSet::Kind::Set) {
    const ast::ElementDecl* want = dim.var && dim.var->type ? dim.var->type->element : nullptr;
    if (t.element != want) {
      error(SemanticKind::Type, index.span,
            "expected an element of type '" + std::string(want ? want->name : "?") +
                "' as index but got an element of type " + quoted(t));
      return false;
    }
  }
  if (t.has_source && t.source != dim) {
    error(SemanticKind::Dimension, index.span,
          "expected " + set_desc + " as index but got an element inferred to be of set '" +
              index_set_name(t.source) + "'");
    return false;
  }
  if (!t.has_source) infer_source(r, index, dim);
  return true;
}

// §8.5.6: an element parameter (or tuple parameter component) used directly as an index
// of a named tensor with a set dimension comes from that set; the first use wins.
void Checker::infer_source(ast::TensorRead& r, ast::Expr& index, const IndexSet& dim) {
  if (!r.base || !r.base->is<ast::VarRef>()) return;
  if (auto* ref = index.as<ast::VarRef>()) {
    Variable* v = const_cast<Variable*>(ref->var);
    if (!v || v->kind != Variable::Kind::Param || !v->type ||
        v->type->kind != Type::Kind::Element || v->type->has_source)
      return;
    v->type = with_source(v->type, dim);
    index.type = v->type;
    return;
  }
  auto* tr = index.as<ast::TupleRead>();
  if (!tr || !tr->base || !tr->base->is<ast::VarRef>()) return;
  // The tree holds resolved variables as const; the checker owns and may refine them.
  Variable* v = const_cast<Variable*>(tr->base->as<ast::VarRef>()->var);
  if (!v || v->kind != Variable::Kind::Param || !v->type || v->type->kind != Type::Kind::Tuple)
    return;
  auto t = std::make_shared<Type>(*v->type);
  for (size_t k = 0; k < t->members.size(); ++k) {
    bool target = tr->index ? true : static_cast<int>(k) == tr->member_index;
    if (target && t->members[k] && !t->members[k]->has_source)
      t->members[k] = with_source(t->members[k], dim);
  }
  v->type = t;
  tr->base->type = t;
  if (index.type && index.type->kind == Type::Kind::Element)
    index.type = with_source(index.type, dim);
}

TypeRef Checker::slice_type(const ast::TensorRead& r, const Type& base) {
  std::vector<IndexSet> kept;
  for (size_t i = 0; i < r.indices.size(); ++i)
    if (!r.indices[i]) kept.push_back(base.dims[i]);
  if (kept.size() != 1) return make_tensor(std::move(kept), base.block);
  if (base.dims.size() == 1) return make_tensor(std::move(kept), base.block, base.row);
  // One kept dimension: a column when the second-to-last index is the slice.
  bool column = !r.indices[r.indices.size() - 2];
  return make_tensor(std::move(kept), base.block, !column);
}

// ---------------------------------------------------------------------------
// Field, tuple and set reads

static int find_field(const ast::ElementDecl& e, const std::string& name) {
  for (size_t i = 0; i < e.fields.size(); ++i)
    if (e.fields[i].name == name) return static_cast<int>(i);
  return -1;
}

TypeRef Checker::type_field_read(ast::FieldRead& f, const TypeRef& base) {
  if (!is_single_value(*base)) {
    error(SemanticKind::Type, f.span,
          base->kind == Type::Kind::Void ? "cannot access fields of a void value"
                                         : "cannot access fields of multiple values");
    return nullptr;
  }
  bool is_set = base->kind == Type::Kind::Set;
  if (!(is_set || base->kind == Type::Kind::Element) || !base->element) {
    error(
        SemanticKind::Type, f.span,
        "expected left operand of field access to be a set or an element but got " + quoted(*base));
    return nullptr;
  }
  int idx = find_field(*base->element, f.field);
  if (idx < 0) {
    undeclared("undefined field", base->element->name + "." + f.field,
               f.field_span.valid() ? f.field_span : f.span);
    return nullptr;
  }
  f.field_index = idx;
  f.writable = f.base->writable;
  TypeRef ft = base->element->fields[idx].type;
  if (!ft || !is_set) return ft;
  const auto* ref = f.base->as<ast::VarRef>();
  if (ft->order() > 1 || !ref || !ref->var) {
    error(SemanticKind::Type, f.span, "can only access scalar or vector set fields");
    return nullptr;
  }
  f.of_set = true;
  bool row = ft->order() == 1 && ft->row;
  return make_tensor({IndexSet::set(ref->var)}, ft, row);
}

TypeRef Checker::type_tuple_read(ast::TupleRead& t, const TypeRef& base) {
  if (base->kind != Type::Kind::Tuple || base->members.empty()) {
    error(SemanticKind::Type, t.span, "expected a tuple but got " + quoted(*base));
    return nullptr;
  }
  t.writable = t.base->writable;
  if (!t.index) {
    for (size_t k = 0; k < base->names.size() && k < base->members.size(); ++k) {
      if (base->names[k] == t.member) {
        t.member_index = static_cast<int>(k);
        return base->members[k];
      }
    }
    error(SemanticKind::Undeclared, t.span, "undefined tuple element '" + t.member + "'");
    return nullptr;
  }
  if (!base->names.empty()) {
    error(SemanticKind::Type, t.span, "elements of a named tuple are read by name");
    return nullptr;
  }
  TypeRef it = check_value(*t.index, "a tuple index");
  if (!it) return nullptr;
  if (!is_int(*it)) {
    error(SemanticKind::Type, t.index->span, "tuple access expects an integral index");
    return nullptr;
  }
  if (auto* lit = t.index->as<ast::IntLit>()) {
    if (lit->value >= 0 && lit->value < static_cast<long long>(base->members.size()))
      return base->members[lit->value];
  }
  for (const auto& m : base->members)
    if (!same_type(*m, *base->members[0]) || m->has_source != base->members[0]->has_source)
      return element_type(base->members[0]->element, IndexSet::fixed(0), false);
  return base->members[0];
}

int Checker::grid_dims_of(const Variable* point_set) const {
  auto over = [&](const Variable* v) {
    return v && v->type && v->type->kind == Type::Kind::Set && v->type->grid_dims > 0 &&
           !v->type->endpoints.empty() && v->type->endpoints[0].var == point_set;
  };
  if (func_)
    for (const auto& p : func_->params)
      if (over(p.var)) return p.var->type->grid_dims;
  for (const Variable* g : program_.globals)
    if (over(g)) return g->type->grid_dims;
  return 0;
}

// Grid offsets are integer constants (§8.7): literals with optional signs.
static bool is_int_constant(const ast::Expr& e) {
  if (e.is<ast::IntLit>()) return true;
  const auto* u = e.as<ast::Unary>();
  return u && u->op != ast::Unary::Op::Not && u->operand && is_int_constant(*u->operand);
}

bool Checker::check_grid_indices(ast::SetRead& s, size_t expected, bool link) {
  size_t got = s.first.size() + s.second.size();
  bool halves = !link || (s.has_semicolon && s.first.size() == s.second.size());
  if (got != expected || !halves) {
    error(SemanticKind::Arity, s.span,
          std::string(link ? "grid edge set access expects 2 * dimensions = "
                           : "grid access expects ") +
              std::to_string(expected) + " indices but got " + std::to_string(got));
    return false;
  }
  for (auto* list : {&s.first, &s.second}) {
    for (auto& i : *list) {
      TypeRef t = i ? check_value(*i, "a grid index") : nullptr;
      if (!t) return false;
      if (!is_int(*t)) {
        error(SemanticKind::Type, i->span, "underlying set access expects an integral index");
        return false;
      }
      if (!is_int_constant(*i)) {
        error(SemanticKind::None, i->span, "grid offsets must be integer literals");
        return false;
      }
    }
  }
  return true;
}

TypeRef Checker::check_set_read(ast::SetRead& s) {
  TypeRef base = s.base ? check_expr(*s.base) : nullptr;
  if (!base) return nullptr;
  const auto* ref = s.base->as<ast::VarRef>();
  if (base->kind != Type::Kind::Set || !ref || !ref->var) {
    error(SemanticKind::Type, s.span, "expected a set but got " + quoted(*base));
    return nullptr;
  }
  s.writable = s.base->writable;
  IndexSet self = IndexSet::set(ref->var);
  if (base->grid_dims > 0) {
    if (!check_grid_indices(s, 2 * static_cast<size_t>(base->grid_dims), true)) return nullptr;
    return element_type(base->element, self, true);
  }
  if (!base->endpoints.empty() || s.has_semicolon) {
    error(SemanticKind::Type, s.span, "underlying point set cannot have non-zero cardinality");
    return nullptr;
  }
  int dims = grid_dims_of(ref->var);
  if (dims == 0) {
    error(SemanticKind::Type, s.span, "set '" + ref->name + "' is not the point set of a grid");
    return nullptr;
  }
  if (!check_grid_indices(s, static_cast<size_t>(dims), false)) return nullptr;
  return element_type(base->element, self, true);
}

}  // namespace simit::frontend::checker_detail
