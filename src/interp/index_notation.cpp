// Index-notation assignments (LANGUAGE.md §7.2), evaluated by their definition: for every
// value of the free index variables, the sum over every value of the reduction variables
// of the right-hand side, which is then an ordinary scalar (or block) expression. A sum over
// a set's elements follows the blocked order of docs/arithmetic.md ("Sums").
#include <algorithm>

#include "interp/frame.h"
#include "interp/interpreter.h"
#include "interp/operators.h"
#include "runtime/blocked_sum.h"

namespace simit::interp {

namespace ast = frontend::ast;

// The index variables of one assignment, each listed once, with the size it ranges over.
// The reduction variables are split: those that range over a set (or a generic parameter)
// sum in the blocked order, outermost first; the dense ones run row-major inside them.
struct Interpreter::IndexVars {
  std::vector<const ast::Variable*> free, over_sets, dense;
  std::vector<int> free_sizes, over_set_sizes, dense_sizes;
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

// Whether an index of `r` (or of a read nested in its base) indexes a dimension of `v`
// that is a set or a generic parameter: what makes a vector global for the inner product
// (interp/linalg.cpp), so that `u(i) * v(i)` and `u' * v` sum alike. The checker makes all
// occurrences of one variable range over the same index set.
bool ranges_over_set(const ast::TensorRead& r, const ast::Variable* v) {
  const ast::Expr& base = *r.base;
  if (const auto* inner = base.as<ast::TensorRead>();
      inner && inner->index_notation && ranges_over_set(*inner, v))
    return true;
  const frontend::Type* t = base.type.get();
  if (!t || t->kind != frontend::Type::Kind::Tensor) return false;
  for (size_t k = 0; k < r.indices.size() && k < t->dims.size(); ++k)
    if (ivar_of(r.indices[k].get()) == v && t->dims[k].kind != frontend::IndexSet::Kind::Fixed)
      return true;
  return false;
}

// One lane (or partial) of a blocked sum of values: fold_lanes adds these with `+`, which
// adds as the interpreter's `+` does (`add` is the caller's addition).
template <class Add>
struct Partial {
  Value value;
  const Add* add;
};

template <class Add>
Partial<Add> operator+(Partial<Add> l, const Partial<Add>& r) {
  (*l.add)(l.value, r.value);
  return l;
}

}  // namespace

// The shape of `r` with its indices applied, recording the size every ivar index ranges
// over on the way (nested reads such as `K(i, j)(k, l)` included). All occurrences of one
// variable must index dimensions of one size.
Shape Interpreter::ivar_ranges(const ast::TensorRead& r,
                               std::vector<std::pair<const ast::Variable*, int>>& sizes) {
  const ast::Expr& base = *r.base;
  std::vector<int> dims;  // the dimensions r's indices index
  Shape block;            // what r reads
  auto of_value = [&](const Value& v) {
    if (v.kind() == Value::Kind::Matrix) {
      // A system matrix has no dense shape: its blocks range over the row and column sets
      // (the read's type is the block's).
      dims = {v.matrix()->rows(), v.matrix()->cols()};
      if (r.type && r.type->kind == frontend::Type::Kind::Tensor) block = shape_of(*r.type, r.span);
      return;
    }
    dims = v.shape().outer_dims();
    block = v.shape().block();
  };
  if (const auto* inner = base.as<ast::TensorRead>(); inner && inner->index_notation) {
    const Shape s = ivar_ranges(*inner, sizes);
    dims = s.outer_dims();
    block = s.block();
  } else if (const auto* v = base.as<ast::VarRef>()) {
    of_value(read_var(*v->var, base));
  } else {
    of_value(eval(base));
  }
  for (size_t k = 0; k < r.indices.size() && k < dims.size(); ++k) {
    const ast::Variable* v = ivar_of(r.indices[k].get());
    if (!v) continue;
    const int size = dims[k];
    auto known =
        std::find_if(sizes.begin(), sizes.end(), [&](const auto& p) { return p.first == v; });
    if (known == sizes.end())
      sizes.emplace_back(v, size);
    else if (known->second != size)
      fail(r.indices[k]->span, "index variable '" + v->name + "' ranges over dimensions of sizes " +
                                   std::to_string(known->second) + " and " + std::to_string(size));
  }
  return block;
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
  for (const auto* v : vars.free) vars.free_sizes.push_back(size_of(v));
  for (const auto* v : a.loop_reduction) {
    const bool over_set =
        std::any_of(a.ranging_reads.begin(), a.ranging_reads.end(),
                    [&](const ast::TensorRead* r) { return ranges_over_set(*r, v); });
    (over_set ? vars.over_sets : vars.dense).push_back(v);
    (over_set ? vars.over_set_sizes : vars.dense_sizes).push_back(size_of(v));
  }
  return vars;
}

void Interpreter::set_ivars(const std::vector<const ast::Variable*>& vars,
                            const std::vector<int>& values) {
  for (size_t k = 0; k < vars.size(); ++k) var(*vars[k]) = Value::of_int(values[k]);
}

// The right side summed over every value of the reduction variables (the free ones are set).
// Each reduction variable over a set sums its values' sums in the blocked order
// (runtime/blocked_sum.h), the first of them outermost, so that `s = u(i) * v(i)` gives the
// bits of `u' * v`; for every combination of their values the dense reduction variables
// (a block's components) run row-major from +0.0. Every addition is one `+` of the
// interpreter, with its float32 rounding and finiteness check.
Value Interpreter::reduce(const ast::Assign& a, const IndexVars& vars) {
  if (options_.distribution && !vars.over_sets.empty())
    not_distributed(a.value->span, "a sum over a set in index notation");
  const Value zero = zero_of(*a.value->type, a.value->span);
  if (any_empty(vars.over_set_sizes) || any_empty(vars.dense_sizes)) return zero;
  auto add = [&](Value& sum, const Value& term) {
    if (sum.kind() == Value::Kind::Float && term.kind() == Value::Kind::Float)
      sum.set_float(sum.as_float() + term.as_float());
    else
      sum = binary_op(ast::Binary::Op::Add, sum, false, term, false);
    finish(sum, *a.value);
  };
  auto dense_sum = [&] {
    Value sum = zero;
    std::vector<int> idx(vars.dense.size(), 0);
    do {
      set_ivars(vars.dense, idx);
      add(sum, eval(*a.value));
    } while (advance(idx, vars.dense_sizes));
    return sum;
  };
  using Lane = Partial<decltype(add)>;
  // The blocked sum over set variable `level` of the sums below it.
  auto over_set = [&](auto& self, size_t level) -> Value {
    if (level == vars.over_sets.size()) return dense_sum();
    const ast::Variable& v = *vars.over_sets[level];
    const size_t elements = static_cast<size_t>(vars.over_set_sizes[level]);
    Value total = zero;
    for (size_t chunk = 0; chunk < runtime::sum_chunks(elements); ++chunk) {
      const size_t begin = chunk * runtime::kSumChunk;
      const size_t end = std::min(elements, begin + runtime::kSumChunk);
      std::vector<Lane> lanes(runtime::kSumLanes, Lane{zero, &add});
      for (size_t e = begin; e < end; ++e) {
        var(v) = Value::of_int(static_cast<int>(e));
        add(lanes[(e - begin) % runtime::kSumLanes].value, self(self, level + 1));
      }
      add(total, runtime::fold_lanes(lanes.data()).value);
    }
    return total;
  };
  return over_set(over_set, 0);
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
