// Type checker: index-notation assignments with `ivar`s (§7.2) — free and reduction
// variables, the dimensions each index variable ranges over, and the operations allowed.
#include <algorithm>

#include "frontend/checker_impl.h"

namespace simit::frontend::checker_detail {

using ast::Variable;

// Every occurrence of an index variable must range over equal dimensions.
void Checker::record_ivar(const Variable* v, const IndexSet& dim, SourceSpan at) {
  auto it = std::find_if(ivar_dims_.begin(), ivar_dims_.end(),
                         [&](const auto& p) { return p.first == v; });
  if (it == ivar_dims_.end()) {
    ivar_dims_.emplace_back(v, dim);
  } else if (it->second != dim) {
    error(SemanticKind::Dimension, at,
          "index variable '" + v->name + "' ranges over '" + index_set_name(it->second) +
              "' and '" + index_set_name(dim) + "'");
  }
  if (ivar_sink_ && std::find(ivar_sink_->begin(), ivar_sink_->end(), v) == ivar_sink_->end())
    ivar_sink_->push_back(v);
}

void Checker::check_index_assign(ast::Assign& a) {
  if (a.targets.size() != 1 || !a.targets[0] || !a.value) {
    error(SemanticKind::None, a.span, "an index-notation assignment must have exactly one target");
    return;
  }
  std::vector<const Variable*> left, right;
  a.reduction_vars.clear();
  in_index_ = true;
  ivars_ok_ = true;
  ivar_dims_.clear();
  // The right side first: a new full-reduction target must not be visible in it.
  ivar_sink_ = &right;
  TypeRef value = check_value(*a.value, "the value of an assignment");
  ivar_sink_ = &left;
  ast::Expr& t = *a.targets[0];
  auto* ref = t.as<ast::VarRef>();
  if (ref && !scopes_.lookup(ref->name)) {
    declare_implicit(a, 0, value);
  } else if (value) {
    TypeRef target = check_place(t);
    if (target && !target->is_tensor()) {
      error(SemanticKind::Type, t.span, "cannot assign to a target of type " + quoted(*target));
    } else if (target && !t.writable) {
      not_writable(t);
    } else if (target) {
      check_assignable(a.value->span, *target, *value);
    }
  }
  ivar_sink_ = nullptr;
  in_index_ = false;
  ivars_ok_ = false;
  a.index_notation = true;
  a.free_vars = left;
  for (const Variable* v : right)
    if (std::find(left.begin(), left.end(), v) == left.end()) a.reduction_vars.push_back(v);
}

}  // namespace simit::frontend::checker_detail
