// Index-notation assignments (LANGUAGE.md §7.2), evaluated by their definition: for every
// value of the free index variables, the sum over every value of the reduction variables
// of the right-hand side, which is then an ordinary scalar (or block) expression.
#include <algorithm>

#include "interp/frame.h"
#include "interp/interpreter.h"
#include "interp/operators.h"

namespace simit::interp {

namespace ast = frontend::ast;

// The index variables of one assignment, each listed once, with the size it ranges over.
struct Interpreter::IndexVars {
  std::vector<const ast::Variable*> free, reduction;
  std::vector<int> free_sizes, reduction_sizes;
};

namespace {

const ast::Variable* ivar_of(const ast::Expr* e) {
  const auto* r = e ? e->as<ast::VarRef>() : nullptr;
  return r && r->var && r->var->kind == ast::Variable::Kind::IndexVar ? r->var : nullptr;
}

// The next combination of `idx` below `sizes` (row-major); false after the last one.
bool advance(std::vector<int>& idx, const std::vector<int>& sizes) {
  for (size_t k = idx.size(); k-- > 0;) {
    if (++idx[k] < sizes[k]) return true;
    idx[k] = 0;
  }
  return false;
}

bool any_empty(const std::vector<int>& sizes) {
  return std::any_of(sizes.begin(), sizes.end(), [](int n) { return n == 0; });
}

}  // namespace

// The shape of `r` with its indices applied, recording the size every ivar index ranges
// over on the way (nested reads such as `K(i, j)(k, l)` included). All occurrences of one
// variable must index dimensions of one size.
Shape Interpreter::ivar_ranges(const ast::TensorRead& r,
                               std::vector<std::pair<const ast::Variable*, int>>& sizes) {
  Shape s;
  const ast::Expr& base = *r.base;
  if (const auto* inner = base.as<ast::TensorRead>(); inner && inner->index_notation)
    s = ivar_ranges(*inner, sizes);
  else if (const auto* v = base.as<ast::VarRef>())
    s = read_var(*v->var, base).shape();
  else
    s = eval(base).shape();
  for (size_t k = 0; k < r.indices.size() && static_cast<int>(k) < s.order(); ++k) {
    const ast::Variable* v = ivar_of(r.indices[k].get());
    if (!v) continue;
    const int size = s.dim(static_cast<int>(k));
    auto known =
        std::find_if(sizes.begin(), sizes.end(), [&](const auto& p) { return p.first == v; });
    if (known == sizes.end())
      sizes.emplace_back(v, size);
    else if (known->second != size)
      fail(r.indices[k]->span, "index variable '" + v->name + "' ranges over dimensions of sizes " +
                                   std::to_string(known->second) + " and " + std::to_string(size));
  }
  return s.block();
}

// The ranges of the loops the frontend planned (frontend/index_ranges.h), from the shapes
// the ranging reads have now.
Interpreter::IndexVars Interpreter::index_vars(const ast::Assign& a) {
  std::vector<std::pair<const ast::Variable*, int>> sizes;
  for (const ast::TensorRead* r : a.ranging_reads) ivar_ranges(*r, sizes);
  auto size_of = [&](const ast::Variable* v) {
    auto it = std::find_if(sizes.begin(), sizes.end(), [&](const auto& p) { return p.first == v; });
    if (it == sizes.end()) fail(a.span, "index variable '" + v->name + "' indexes no dimension");
    return it->second;
  };
  IndexVars vars;
  vars.free = a.loop_free;
  vars.reduction = a.loop_reduction;
  for (const auto* v : vars.free) vars.free_sizes.push_back(size_of(v));
  for (const auto* v : vars.reduction) vars.reduction_sizes.push_back(size_of(v));
  return vars;
}

void Interpreter::set_ivars(const std::vector<const ast::Variable*>& vars,
                            const std::vector<int>& values) {
  for (size_t k = 0; k < vars.size(); ++k) var(*vars[k]) = Value::of_int(values[k]);
}

// The right side summed over every value of the reduction variables (the free ones are set).
Value Interpreter::reduce(const ast::Assign& a, const IndexVars& vars) {
  Value sum = zero_of(*a.value->type, a.value->span);
  if (any_empty(vars.reduction_sizes)) return sum;
  std::vector<int> idx(vars.reduction.size(), 0);
  do {
    set_ivars(vars.reduction, idx);
    Value term = eval(*a.value);
    if (sum.kind() == Value::Kind::Float && term.kind() == Value::Kind::Float)
      sum.set_float(sum.as_float() + term.as_float());
    else
      sum = binary_op(ast::Binary::Op::Add, sum, false, term, false);
    finish(sum, *a.value);
  } while (advance(idx, vars.reduction_sizes));
  return sum;
}

void Interpreter::exec_index_assign(const ast::Assign& a) {
  // Calls without index variables run once, before the components are computed.
  HoistScope hoisted(*this, *a.value);
  const IndexVars vars = index_vars(a);
  const ast::Expr& target = *a.targets.at(0);
  if (!target.is<ast::TensorRead>()) {  // a full reduction into a plain variable
    store(a, 0, reduce(a, vars));
    return;
  }
  const auto* base = target.as<ast::TensorRead>()->base->as<ast::VarRef>();
  if (!base) unsupported(target.span, "index-notation targets other than variables");
  Value& dst = read_var(*base->var, *base);
  // The target is replaced: components that the free variables do not reach become zero,
  // and the right side reads the old value throughout.
  Value result = Value::zero(dst.component_kind(), dst.shape());
  if (!any_empty(vars.free_sizes)) {
    std::vector<int> idx(vars.free.size(), 0);
    do {
      set_ivars(vars.free, idx);
      Value v = reduce(a, vars);
      write_place(resolve_place(target, &result), std::move(v), target.span);
    } while (advance(idx, vars.free_sizes));
  }
  dst = std::move(result);
}

}  // namespace simit::interp
