// The tracer's writes (jit/trace/tracer.h): bindings of variables, component writes,
// stores into fields, writes into the mapped function's results, and matrix arguments.
#include <algorithm>

#include "jit/trace/tracer.h"

namespace simit::jit::trace_detail {

void Tracer::bind(const ast::Variable& v, Sym value, const SourceSpan& at) {
  Frame& f = frame();
  if (auto m = f.merged.find(&v); m != f.merged.end()) {
    if (value.kind != Sym::Kind::Tensor || value.size() != m->second.size())
      give_up(at, AbortReason::ShapeChange);
    // Every component is read before any is written: `t = t'` reads t's own locals.
    value = settle(std::move(value), at);
    for (size_t i = 0; i < value.size(); ++i) set_local(m->second[i], value.c[i], at);
    Sym& cur = f.vars[&v];
    cur.dims = value.dims;
    cur.block = value.block;
    return;
  }
  if (auto b = f.bound_at.find(&v);
      b != f.bound_at.end() && b->second < static_cast<int>(blocks_.size()))
    give_up(at, AbortReason::UnexpectedBranchAssignment, v.name);
  f.vars[&v] = value.kind == Sym::Kind::Tensor ? settle(std::move(value), at) : std::move(value);
  f.bound_at[&v] = static_cast<int>(blocks_.size());
}

void Tracer::assign(const ast::Expr& target, Sym value, const SourceSpan& at) {
  if (const auto* v = target.as<ast::VarRef>()) {
    auto it = frame().vars.find(v->var);
    if (it != frame().vars.end() && it->second.kind == Sym::Kind::Result)
      give_up(at, AbortReason::WholeResultAssignment);
    // `v = 0.0` on a tensor broadcasts; a variable keeps its declared shape.
    if (v->var->type) value = as_declared(std::move(value), *v->var->type, at);
    return bind(*v->var, std::move(value), at);
  }
  if (const auto* f = target.as<ast::FieldRead>())
    return store_field(*f, nullptr, std::move(value), at);
  const auto* r = target.as<ast::TensorRead>();
  if (!r) give_up(at, AbortReason::AssignmentTarget);
  if (r->index_notation) give_up(at, AbortReason::IndexNotation);
  // Writes into the function's system-tensor results.
  // `K(x, y)(a, d) = s`: one component of a block (the pass marks the whole target).
  if (const auto* inner = r->base->as<ast::TensorRead>(); inner && r->assembles_result >= 0)
    return assign_result(*inner, r, std::move(value), at);
  if (r->assembles_result >= 0) return assign_result(*r, nullptr, std::move(value), at);
  std::vector<int64_t> idx;
  for (const auto& i : r->indices) {
    if (!i) give_up(at, AbortReason::SliceAssignment);
    idx.push_back(const_int(*i));
  }
  if (const auto* f = r->base->as<ast::FieldRead>())
    return store_field(*f, &idx, std::move(value), at);
  // `B(i, j)(a, b) = x`: a component of a block of a blocked local.
  const ast::TensorRead* outer = r;
  std::vector<int64_t> sub;
  if (const auto* in = r->base->as<ast::TensorRead>()) {
    outer = in;
    sub = std::move(idx);
    idx.clear();
    for (const auto& i : in->indices) {
      if (!i) give_up(at, AbortReason::SliceAssignment);
      idx.push_back(const_int(*i));
    }
  }
  const auto* base = outer->base->as<ast::VarRef>();
  if (!base) give_up(at, AbortReason::AssignmentTarget);
  assign_part(*base->var, idx, outer != r ? &sub : nullptr, std::move(value), at);
}

// A write of a component of a local, or of a block or a block's component when it is blocked
// (a scalar fills the block, as in the interpreter).
void Tracer::assign_part(const ast::Variable& v, const std::vector<int64_t>& idx,
                         const std::vector<int64_t>* sub, Sym value, const SourceSpan& at) {
  auto it = frame().vars.find(&v);
  Sym cur = it != frame().vars.end() ? it->second : zero_of(*v.type, at);
  if (cur.kind != Sym::Kind::Tensor) give_up(at, AbortReason::ComponentWriteNonTensor);
  if (sub && !cur.blocked()) give_up(at, AbortReason::ComponentWriteComponent);
  if (idx.size() != cur.dims.size() || (sub && sub->size() != cur.block.size()))
    give_up(at, AbortReason::IndexCount);
  size_t first = offset_of(cur.dims, idx, at), count = 1;
  if (cur.blocked()) {
    first *= cur.block_size();
    count = cur.block_size();
    if (sub) {
      first += offset_of(cur.block, *sub, at);
      count = 1;
    }
  }
  if (value.kind != Sym::Kind::Tensor || value.ty != cur.ty)
    give_up(at, AbortReason::ComponentWriteType);
  if (!value.scalar() && (value.size() != count || value.blocked()))
    give_up(at, AbortReason::BlockWriteShape);
  // Computed once, and every component read before any is written (`B(0, 0) = B(0, 0)'`).
  if (count > 1) value = settle(std::move(value), at);
  auto part = [&](size_t k) { return value.scalar() ? value.c[0] : value.c[k]; };
  if (auto m = frame().merged.find(&v); m != frame().merged.end()) {
    for (size_t k = 0; k < count; ++k) set_local(m->second[first + k], part(k), at);
    return;
  }
  for (size_t k = 0; k < count; ++k) cur.c[first + k] = part(k);
  bind(v, std::move(cur), at);
}

void Tracer::store_field(const ast::FieldRead& f, const std::vector<int64_t>* idx, Sym value,
                         const SourceSpan& at) {
  if (f.of_set) give_up(at, AbortReason::SetFieldWrite);
  Sym base = eval(*f.base);
  if (base.kind != Sym::Kind::Element || base.member != 0)
    give_up(at, AbortReason::FieldWriteOtherElement);
  const int slot = field_array(0, f.field, f.span);
  ArraySlot& a = trace_.arrays[slot];
  a.written = true;
  trace_.writes_fields = true;
  if (value.kind != Sym::Kind::Tensor || value.ty != a.ty || value.blocked())
    give_up(at, AbortReason::FieldWriteType);
  std::vector<int> dims = dims_of(*f.type, f.span);
  size_t first = 0, count = static_cast<size_t>(a.components);
  if (idx) {
    first = offset_of(dims, *idx, at);
    count = 1;
  }
  if (!value.scalar() && value.size() != count) give_up(at, AbortReason::FieldWriteShape);
  value = settle(std::move(value), at);
  for (size_t k = 0; k < count; ++k) {
    Stmt s;
    s.kind = StmtKind::Store;
    s.slot = slot;
    s.comp = static_cast<int>(first + k);
    s.index = member_index(0);
    s.value = value.scalar() ? value.c[0] : value.c[k];
    s.span = at;
    emit(std::move(s));
  }
  forget_loads(slot);
}

void Tracer::assign_result(const ast::TensorRead& r, const ast::TensorRead* component, Sym value,
                           const SourceSpan& at) {
  const auto* base = r.base->as<ast::VarRef>();
  auto it = base ? frame().vars.find(base->var) : frame().vars.end();
  if (it == frame().vars.end() || it->second.kind != Sym::Kind::Result || frames_.size() != 1)
    give_up(at, AbortReason::ResultWriteOutside);
  const int res = it->second.slot;
  const int slot = array({ArraySlot::Kind::Result, 0, res, Ty::F64, false, true, 0, "", {}});
  ArraySlot& a = trace_.arrays[slot];
  if (value.kind != Sym::Kind::Tensor || value.ty != Ty::F64)
    give_up(at, AbortReason::ResultWriteNonFloat);
  if (value.blocked()) give_up(at, AbortReason::ResultWriteBlocked);
  std::vector<int64_t> sub;
  if (component)
    for (const auto& i : component->indices) {
      if (!i) give_up(at, AbortReason::ResultBlockSlice);
      sub.push_back(const_int(*i));
    }
  std::vector<int> members;
  for (const auto& i : r.indices) {
    if (!i) give_up(at, AbortReason::ResultWriteSlice);
    Sym m = eval(*i);
    if (m.kind != Sym::Kind::Element) give_up(at, AbortReason::ResultWriteNotAtMember);
    members.push_back(m.member);
  }
  const runtime::MatrixPattern* pattern = in_.patterns[res];
  int pair = -1;
  ExprRef index;
  if (pattern) {
    if (members.size() != 2) give_up(at, AbortReason::MatrixWriteOneIndex);
    const runtime::AssemblyIndex& ai = pattern->assembly();
    auto local = [&](const std::vector<int>& ms, int m) {
      auto p = std::find(ms.begin(), ms.end(), m);
      if (p == ms.end()) give_up(at, AbortReason::MatrixWriteOutsidePattern);
      return static_cast<int>(p - ms.begin());
    };
    pair = local(ai.row_members, members[0]) * static_cast<int>(ai.col_members.size()) +
           local(ai.col_members, members[1]);
  } else {
    if (members.size() != 1) give_up(at, AbortReason::VectorWriteTwoIndices);
    index = member_index(members[0]);
  }
  // The block's shape comes from the result's type.
  const Type& rt = *base->var->type;
  const std::vector<int> block = rt.block ? dims_of(*rt.block, at) : std::vector<int>{};
  size_t bsize = 1;
  for (int d : block) bsize *= static_cast<size_t>(d);
  a.components = static_cast<int>(bsize);
  size_t first = 0, count = bsize;
  if (component) {
    first = offset_of(block, sub, at);
    count = 1;
  }
  if (!value.scalar() && value.size() != count) give_up(at, AbortReason::ResultWriteShape);
  for (size_t k = 0; k < count; ++k) {
    Stmt s;
    s.kind = StmtKind::Assemble;
    s.slot = slot;
    s.comp = static_cast<int>(first + k);
    s.pair = pair;
    s.index = index;
    s.value = value.scalar() ? value.c[0] : value.c[k];
    s.span = at;
    emit(std::move(s));
  }
}

// A global matrix argument, read by blocks (read_matrix_block).
Sym Tracer::matrix_arg(int k, const ast::Param& p, const interp::Value& v) {
  const runtime::SystemMatrix* m = v.matrix().get();
  if (!m || !m->is_float()) give_up(p.span, AbortReason::MatrixArgumentNotFloat);
  // The interpreter sums the repeated blocks of a stencil pattern where it reads one.
  if (!m->pattern().canonical()) give_up(p.span, AbortReason::MatrixArgumentRepeatsBlocks);
  ArraySlot a;
  a.kind = ArraySlot::Kind::Matrix;
  a.index = k;
  a.components = m->block_size();
  a.name = p.name;
  Sym s;
  s.kind = Sym::Kind::Matrix;
  s.slot = array(std::move(a));
  return s;
}

}  // namespace simit::jit::trace_detail
