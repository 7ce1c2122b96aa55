// The tracer's state (jit/trace/tracer.h): field arrays, cached loads, the trace of a whole
// site (run), and the entry point trace_site (jit/trace_site.h).
#include "jit/trace/tracer.h"

#include <algorithm>

#include "jit/tunables.h"

namespace simit::jit {
namespace trace_detail {

int Tracer::field_array(int member, const std::string& name, const SourceSpan& at) {
  const runtime::Set& s = member_set(member);
  const int f = s.field_index(name);
  if (f < 0) give_up(at, AbortReason::FieldNotBound, name);
  const runtime::FieldType& ft = s.field(f).type();
  ArraySlot a;
  a.kind = ArraySlot::Kind::Field;
  a.member = member;
  a.index = f;
  switch (ft.kind) {
    case runtime::ComponentKind::Float: a.ty = Ty::F64; break;
    case runtime::ComponentKind::Int: a.ty = Ty::I32; break;
    case runtime::ComponentKind::Bool: a.ty = Ty::Bool; break;
    default: give_up(at, AbortReason::FieldComponentType);
  }
  a.single = ft.single;
  a.components = static_cast<int>(ft.components());
  a.name = s.name() + "." + name;
  return array(std::move(a));
}

ExprRef Tracer::load(int slot, int member, int comp, const SourceSpan& at) {
  const auto key = std::make_tuple(slot, member, comp);
  if (auto it = loads_.find(key); it != loads_.end()) {
    if (std::find(blocks_.begin(), blocks_.end(), it->second.block) != blocks_.end())
      return read_local(it->second.local);
  }
  Expr e;
  e.kind = ExprKind::Load;
  e.ty = trace_.arrays[slot].ty;
  e.slot = slot;
  e.comp = comp;
  e.ops = {member_index(member)};
  e.span = at;
  const int l = new_local(e.ty, false);
  set_local(l, make(std::move(e)), at);
  loads_[key] = {l, blocks_.back()};
  return read_local(l);
}

// The components of array `slot` at a member as a tensor: each loaded once (cached per
// block); a float tensor of more than kTileAbove components by one loop into a scratch array.
Sym Tracer::load_tensor(int slot, int member, std::vector<int> dims, const SourceSpan& at) {
  const ArraySlot& a = trace_.arrays[slot];
  const size_t n = static_cast<size_t>(a.components);
  std::vector<ExprRef> c;
  if (a.ty != Ty::F64 || n <= kTileAbove) {
    for (int k = 0; k < a.components; ++k) c.push_back(load(slot, member, k, at));
    return tensor(a.ty, std::move(dims), std::move(c));
  }
  const auto key = std::make_tuple(slot, member, -1);
  auto it = loads_.find(key);
  if (it == loads_.end() ||
      std::find(blocks_.begin(), blocks_.end(), it->second.block) == blocks_.end()) {
    const int array = new_scratch(n, false);
    for_loop(a.components, at, [&](const ExprRef& k) {
      Expr e;
      e.kind = ExprKind::Load;
      e.ty = Ty::F64;
      e.slot = slot;
      e.ops = {member_index(member), k};
      e.span = at;
      put(array, k, make(std::move(e)), at);
    });
    it = loads_.insert_or_assign(key, CachedLoad{array, blocks_.back()}).first;
  }
  for (size_t k = 0; k < n; ++k)
    c.push_back(read_scratch(it->second.local, iconst(static_cast<int64_t>(k)), at));
  return tensor(Ty::F64, std::move(dims), std::move(c));
}

TracedSite Tracer::run() {
  TracedSite out;
  const ast::Assembly& site = *in_.site;
  const ast::FuncDecl& f = *site.callee;
  trace_.name = f.name;
  if (site.func_span.valid()) trace_.name += ":" + std::to_string(site.func_span.start().line);
  trace_.arity = in_.target->arity();
  trace_.reduce = in_.reduce;
  trace_.float32 = in_.float32;
  ZeroFold* const folding = build_.fold();  // null when traced without folding
  try {
    if (!f.generics.empty()) give_up(site.func_span, AbortReason::GenericMappedFunction);
    if (in_.target->is_grid()) give_up(site.func_span, AbortReason::GridMap);
    Frame top;
    const auto& partial = *in_.partial_args;
    size_t k = 0;
    for (; k < partial.size(); ++k) {
      const ast::Param& p = f.params[k];
      if (p.inout) give_up(p.span, AbortReason::InoutPartialArgument);
      const interp::Value& v = partial[k];
      const Type& t = *p.var->type;
      Sym s;
      if (t.kind == Type::Kind::Tensor && t.is_global() &&
          v.kind() == interp::Value::Kind::Matrix) {
        s = matrix_arg(static_cast<int>(k), p, v);
      } else if (t.kind == Type::Kind::Tensor && t.is_global()) {
        if (!v.is_tensor() || v.tensor().kind() != runtime::ComponentKind::Float ||
            t.dims.size() != 1)
          give_up(p.span, AbortReason::GlobalArgumentNotFloatVector);
        ArraySlot a;
        a.kind = ArraySlot::Kind::Vector;
        a.index = static_cast<int>(k);
        a.components = static_cast<int>(v.tensor().shape().block_size());
        a.name = p.name;
        s.kind = Sym::Kind::Vector;
        s.slot = array(std::move(a));
      } else {
        s = const_of(v, p.span);
        for (size_t i = 0; i < s.c.size(); ++i)
          s.c[i] = scalar_arg(s.ty, {static_cast<int>(k), nullptr, static_cast<int>(i)});
      }
      top.vars[p.var] = std::move(s);
    }
    if (k < f.params.size()) {
      Sym e;
      e.kind = Sym::Kind::Element;
      e.member = 0;
      e.inout = f.params[k].inout;
      top.vars[f.params[k++].var] = e;
    }
    if (site.pass_endpoints && k < f.params.size()) {
      Sym t;
      t.kind = Sym::Kind::Tuple;
      top.vars[f.params[k++].var] = t;
    }
    if (k != f.params.size()) give_up(site.func_span, AbortReason::UnexpectedParameters);
    trace_.pairs.assign(f.results.size(), 0);
    for (size_t i = 0; i < f.results.size(); ++i) {
      Sym r;
      r.kind = Sym::Kind::Result;
      r.slot = static_cast<int>(i);
      top.vars[f.results[i].var] = r;
      if (in_.patterns[i]) {
        trace_.pairs[i] = static_cast<int>(in_.patterns[i]->assembly().pairs());
        array({ArraySlot::Kind::Table,
               0,
               static_cast<int>(i),
               Ty::I32,
               false,
               false,
               trace_.pairs[i],
               f.results[i].name + ".table",
               {}});
        array({ArraySlot::Kind::Marks,
               0,
               static_cast<int>(i),
               Ty::Bool,
               false,
               true,
               1,
               f.results[i].name + ".marks",
               {}});
      }
      array({ArraySlot::Kind::Result,
             0,
             static_cast<int>(i),
             Ty::F64,
             false,
             true,
             1,
             f.results[i].name,
             {}});
    }
    frames_.push_back(std::move(top));
    exec_block(f.body);
    // A failed check makes the interpreter run the site again, which must not see the
    // fields this trace has already written.
    if (error_at_.valid() && trace_.writes_fields)
      give_up(error_at_, AbortReason::ErrorWithInoutFields);
    if (folding)
      if (auto check = folding->close(trace_.errors, site.func_span))
        trace_.body.push_back(std::move(*check));
  } catch (const GiveUp& g) {
    out.reason = g.reason;
    return out;
  } catch (const FoldConflict& c) {
    fold_failed_ = true;
    out.reason = c.reason;
    return out;
  }
  // A call that fails its checks is run again by the interpreter, which a trace that writes
  // fields cannot allow.
  if (folding && folding->used() && trace_.writes_fields) fold_failed_ = true;
  out.scalar_sources = sources_;
  trace_.local_mutable = mutable_;
  out.trace = std::move(trace_);
  return out;
}

}  // namespace trace_detail

TracedSite trace_site(const SiteShape& shape) {
  trace_detail::Tracer folded(shape, kFoldZeros);
  TracedSite t = folded.run();
  if (!folded.fold_failed()) return t;
  return trace_detail::Tracer(shape, false).run();
}

}  // namespace simit::jit
