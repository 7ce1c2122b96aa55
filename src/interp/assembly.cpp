// `map` and `apply` (LANGUAGE.md §8.5-8.7): the mapped function runs once per element with
// its result variables bound to the global results, which start at zero; assembly writes
// land in place through the precomputed block positions of the pattern.
#include <chrono>

#include "interp/frame.h"
#include "interp/interpreter.h"
#include "interp/map_context.h"
#include "interp/set_binding.h"
#include "interp/system_values.h"
#include "runtime/dense_linalg.h"
#include "runtime/system_ops.h"

namespace simit::interp {

// Times the outermost running map or apply into Interpreter::stats(); inner ones only nest.
class Interpreter::AssemblyTimer {
 public:
  explicit AssemblyTimer(Interpreter& in) : in_(in) {
    if (in_.assembly_depth_++ == 0) start_ = std::chrono::steady_clock::now();
  }
  ~AssemblyTimer() {
    if (--in_.assembly_depth_ != 0) return;
    in_.stats_.assembly_seconds +=
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
    ++in_.stats_.maps;
  }
  AssemblyTimer(const AssemblyTimer&) = delete;
  AssemblyTimer& operator=(const AssemblyTimer&) = delete;

 private:
  Interpreter& in_;
  std::chrono::steady_clock::time_point start_;
};

namespace ast = frontend::ast;
using frontend::IndexSet;
using frontend::SourceSpan;
using frontend::Type;

namespace {

bool is_system_matrix_type(const Type& t) {
  return t.kind == Type::Kind::Tensor && t.dims.size() == 2 &&
         t.dims[0].kind != IndexSet::Kind::Fixed && t.dims[1].kind != IndexSet::Kind::Fixed;
}

}  // namespace

std::vector<Value> Interpreter::eval_map(const ast::Map& m) {
  AssemblyTimer timer(*this);
  MapContext ctx;
  ctx.reduce = m.reduce;
  run_assembly(m.assembly, m.through_set, &ctx, m.span);
  std::vector<Value> out;
  for (size_t i = 0; i < ctx.values.size(); ++i) {
    out.push_back(ctx.is_matrix[i] && ctx.grid ? finish_grid_result(ctx, i)
                                               : std::move(ctx.values[i]));
    // Writes stored blocks of blocks level by level, as the dense block values are laid out.
    if (ctx.is_matrix[i] && out.back().matrix())
      runtime::unnest_blocks(*out.back().matrix(), ctx.blocks[i]);
    // --float32: every value of a result is a binary32 value (docs/arithmetic.md). Its sums
    // are already (each addition rounds); a value a map writes as it read it (a binary64
    // field's) is rounded here, unless the hook that ran the map vouches for every value.
    // The results are the map's own.
    if (options_.float32 && !ctx.results_binary32) {
      Value& r = out.back();
      if (r.kind() == Value::Kind::Matrix && r.matrix())
        runtime::round_to_float32(*r.matrix());
      else if (r.is_tensor())
        runtime::round_to_float32(r.tensor());
    }
    // A distributed run: a ghost's sum misses the other ranks' elements (interp/distribution.h).
    if (options_.distribution && m.type) {
      const bool multi = m.type->kind == frontend::Type::Kind::Multi;
      if (!multi || i < m.type->members.size())
        refresh_ghosts(out.back(), multi ? m.type->members[i].get() : m.type.get());
    }
  }
  return out;
}

void Interpreter::exec_apply(const ast::Apply& a) {
  AssemblyTimer timer(*this);
  MapContext ctx;
  run_assembly(a.assembly, nullptr, &ctx, a.span);
}

void Interpreter::run_assembly(const ast::Assembly& a, const ast::Variable* through,
                               MapContext* ctx, const SourceSpan& at) {
  if (!a.callee || !a.target_set) fail(at, "map of an unresolved function or set");
  const ast::FuncDecl& f = *a.callee;
  ctx->assembly = &a;
  ctx->at = at;
  ctx->target = var(*a.target_set).binding();
  if (!ctx->target)
    fail(at, "set '" + a.target_set->name + "' has no value (the host did not bind it)");
  if (through) {
    ctx->grid = var(*through).binding();
    if (!ctx->grid) fail(at, "grid '" + through->name + "' is not bound");
  }
  std::vector<Value> partial;
  for (const auto& arg : a.args) partial.push_back(eval_root(*arg));
  const std::vector<Value> generics = [&] {
    std::vector<Value> g;
    for (const IndexSet& b : a.bindings) {
      if (b.kind == IndexSet::Kind::Fixed)
        g.push_back(Value::of_int(b.size));
      else if (b.var)
        g.push_back(var(*b.var));
      else
        g.emplace_back();
    }
    return g;
  }();
  MapContext* saved = map_;
  const int saved_depth = map_depth_, base_depth = depth_;
  auto setup = [&](int element) -> Frame& {
    Frame& callee = next_frame(f, at, ctx);
    size_t k = 0;
    // The partial arguments are the same for every element: parameters refer to them
    // (an inout one gets its own copy).
    for (Value& p : partial) {
      const ast::Param& param = f.params[k++];
      if (param.inout)
        callee.slots[param.var->slot] = p;
      else
        callee.refs[param.var->slot] = &p;
    }
    if (k < f.params.size())
      callee.slots[f.params[k++].var->slot] = Value::of_element(ctx->target, element);
    if (a.pass_endpoints && k < f.params.size())
      callee.slots[f.params[k++].var->slot] = Value::of_tuple(ctx->target, element);
    if (ctx->grid && k < f.params.size())
      callee.slots[f.params[k++].var->slot] = Value::of_set(ctx->grid);
    for (size_t i = 0; i < f.generics.size(); ++i)
      callee.slots[f.generics[i].var->slot] = i < generics.size() ? generics[i] : Value();
    for (const ast::Param& p : f.params) {
      if (f.generics.empty()) break;  // deduction only binds generic parameters
      const Value& v = *callee.refs[p.var->slot];
      if (p.var->type && p.var->type->kind == Type::Kind::Tensor && v.is_tensor())
        deduce(*p.var->type, v.tensor().shape(), callee, at);
    }
    for (size_t i = 0; i < f.results.size(); ++i)
      callee.refs[f.results[i].var->slot] = &ctx->values[i];
    return callee;
  };
  AssemblyPlan& plan = plan_site(a, *ctx);
  map_ = ctx;
  map_depth_ = depth_ + 1;
  try {
    const bool offer = options_.sites && !trap_->armed();
    // The results exist (zero) even when the set is empty.
    ctx->values.resize(f.results.size());
    setup(0);
    ++depth_;
    for (const ast::Param& r : f.results) {
      const Type& t = *r.var->type;
      Shape block = t.block ? shape_of(*t.block, r.span) : Shape();
      ctx->blocks.push_back(block);
      ctx->is_matrix.push_back(is_system_matrix_type(t));
      ctx->stencil.emplace_back();
      Value& slot = ctx->values[ctx->blocks.size() - 1];
      if (!ctx->is_matrix.back()) {
        slot = zero_of(t, r.span);
        continue;
      }
      if (ctx->grid) {
        slot = Value::of_matrix(nullptr);
        continue;
      }
      auto set_of = [&](const IndexSet& d) -> runtime::Set& {
        const Value& v = *frame().refs[d.var->slot];
        const Value& s = d.kind == IndexSet::Kind::Set ? var(*d.var) : v;
        if (s.kind() != Value::Kind::Set)
          fail(r.span, "matrix dimension '" + d.var->name + "' is not bound to a set");
        return *s.binding()->set;
      };
      runtime::PatternPtr pattern =
          patterns_.assembled(*ctx->target->set, set_of(t.dims[0]), set_of(t.dims[1]));
      const runtime::BlockDims bd = runtime::block_dims(block);
      AssemblyPlan::Result& pr = plan.results[ctx->blocks.size() - 1];
      pr.block = block;
      if (offer && pr.hook_allocates && pr.pattern == pattern) {
        pr.is_matrix = true;
        slot = Value::of_matrix(nullptr);
        continue;
      }
      slot = Value::of_matrix(
          result_matrix(pr, pattern, bd.rows, bd.cols, component_of(t.component())));
    }
    --depth_;
    ++plan.runs;
    SiteCall call{plan, partial, ctx->values, *ctx->target->set, *this, at, false};
    if (offer && options_.sites->run_site(call)) {
      ctx->results_binary32 = call.results_binary32 && !ctx->grid;
      map_ = saved;
      map_depth_ = saved_depth;
      return;
    }
    // Declined: the results the hook was to make are made here.
    for (size_t i = 0; i < ctx->values.size(); ++i)
      if (ctx->is_matrix[i] && !ctx->grid && !ctx->values[i].matrix()) {
        const runtime::BlockDims bd = runtime::block_dims(ctx->blocks[i]);
        ctx->values[i] = Value::of_matrix(
            result_matrix(plan.results[i], plan.results[i].pattern, bd.rows, bd.cols,
                          component_of(f.results[i].var->type->component())));
      }
    // After the first element only the element and its endpoint tuple change: nothing
    // between elements touches the frame's references (calls run one level deeper).
    bool reuse = f.generics.empty();
    for (size_t i = 0; i < partial.size(); ++i) reuse = reuse && !f.params[i].inout;
    const size_t first = partial.size();
    const int element_slot = first < f.params.size() ? f.params[first].var->slot : -1;
    const int tuple_slot =
        a.pass_endpoints && first + 1 < f.params.size() ? f.params[first + 1].var->slot : -1;
    Frame* frame_of_element = nullptr;
    const int n = ctx->target->set->size();
    for (int e = 0; e < n; ++e) {
      ctx->element = e;
      if (reuse && frame_of_element) {
        frame_of_element->activation = ++activations_;
        if (element_slot >= 0)
          frame_of_element->slots[element_slot] = Value::of_element(ctx->target, e);
        if (tuple_slot >= 0) frame_of_element->slots[tuple_slot] = Value::of_tuple(ctx->target, e);
      } else {
        frame_of_element = &setup(e);
      }
      ++depth_;
      execute_body(f);
    }
    if (offer) options_.sites->site_done(call);
  } catch (RuntimeError& e) {
    e.note_element(f.name, element_note(*ctx));
    depth_ = base_depth;
    map_ = saved;
    map_depth_ = saved_depth;
    throw;
  } catch (...) {
    depth_ = base_depth;
    map_ = saved;
    map_depth_ = saved_depth;
    throw;
  }
  map_ = saved;
  map_depth_ = saved_depth;
}

// "mapping over element 5 of set 'tets' (endpoints 3, 9, 12, 40 of 'verts')": built only when
// an error leaves the map. Elements by their mesh numbers (a scene's renumbered mesh).
std::string Interpreter::element_note(const MapContext& ctx) const {
  const runtime::Set* set = ctx.target ? ctx.target->set : nullptr;
  const ast::Variable* target = ctx.assembly ? ctx.assembly->target_set : nullptr;
  const std::string name = target ? target->name : set ? set->name() : "?";
  std::string note = "mapping over element " +
                     std::to_string(set ? set->mesh_number(ctx.element) : ctx.element) +
                     " of set '" + name + "'";
  if (!set || set->is_grid() || ctx.element < 0 || ctx.element >= set->size() || set->arity() == 0)
    return note;
  const Type* type = target && target->type ? target->type.get() : nullptr;
  std::string list, open;
  for (int k = 0; k < set->arity(); ++k) {
    const ast::Variable* ep =
        type && static_cast<size_t>(k) < type->endpoints.size() ? type->endpoints[k].var : nullptr;
    const std::string of = ep ? ep->name : set->endpoint_set(k).name();
    if (!open.empty() && of != open) list += " of '" + open + "';";
    list += (list.empty() || of != open ? (list.empty() ? "" : " ") : ", ") +
            std::to_string(set->endpoint_set(k).mesh_number(set->endpoint(ctx.element, k)));
    open = of;
  }
  return note + " (endpoints " + list + " of '" + open + "')";
}

// The site's plan, made again when the target set or its topology changed.
AssemblyPlan& Interpreter::plan_site(const ast::Assembly& a, const MapContext& ctx) {
  AssemblyPlan& plan = plans_[&a];
  const runtime::Set& target = *ctx.target->set;
  if (plan.site != &a || plan.target != &target || plan.topology != target.topology_version()) {
    plan = AssemblyPlan{};
    plan.site = &a;
    plan.func = a.callee;
    plan.target = &target;
    plan.topology = target.topology_version();
    plan.reduce = ctx.reduce;
    plan.grid = ctx.grid != nullptr;
    plan.results.resize(a.callee->results.size());
  }
  return plan;
}

// A zero matrix over `pattern` for one result of a site: the site's previous matrix when
// nothing holds it any more (the program dropped it), otherwise a new one.
std::shared_ptr<runtime::SystemMatrix> Interpreter::result_matrix(
    AssemblyPlan::Result& r, const runtime::PatternPtr& pattern, int block_rows, int block_cols,
    ComponentKind kind) {
  r.is_matrix = true;
  r.pattern = pattern;
  auto& last = r.last;
  if (last && last.use_count() == 1 && last->shared_pattern() == pattern &&
      last->block_rows() == block_rows && last->block_cols() == block_cols &&
      last->kind() == kind) {
    last->set_zero();
    return last;
  }
  last = std::make_shared<runtime::SystemMatrix>(pattern, block_rows, block_cols, kind);
  return last;
}

bool Interpreter::is_map_result(const Value* v) const {
  if (!map_ || depth_ != map_depth_) return false;
  for (const Value& r : map_->values)
    if (&r == v) return true;
  return false;
}

namespace {

std::string element_text(const Value& v) {
  if (v.kind() != Value::Kind::Element) return "a non-element";
  const runtime::Set& s = *v.binding()->set;
  return "element " + std::to_string(s.mesh_number(v.index())) + " of " + s.describe();
}

}  // namespace

// `K(a, b) = M` inside a mapped function: the block position comes from the assembly index
// of the pattern (edge sets) or from the stencil offset (grids).
Place Interpreter::matrix_place(const ast::TensorRead& r, Value& m) {
  if (r.indices.size() != 2 || !r.indices[0] || !r.indices[1])
    fail(r.span, "a system matrix is written at (row element, column element)");
  MapContext& ctx = *map_;
  size_t res = 0;
  while (&ctx.values[res] != &m) ++res;
  if (const int32_t pos = member_block(r, m); pos >= 0) {
    Place p;
    p.whole = false;
    p.shape = ctx.blocks[res];
    p.accumulate = ctx.reduce;
    p.root = &m;
    p.matrix_position = pos;
    p.offset = static_cast<size_t>(pos) * p.shape.size();
    return p;
  }
  Value row = eval(*r.indices[0]), col = eval(*r.indices[1]);
  if (row.kind() != Value::Kind::Element || col.kind() != Value::Kind::Element)
    fail(r.span, "system matrices are indexed by elements");
  const Shape& block = ctx.blocks[res];
  const size_t bsize = block.size();
  Place p;
  p.whole = false;
  p.shape = block;
  p.accumulate = ctx.reduce;
  if (ctx.grid) {
    if (row.index() != ctx.element)
      fail(r.span,
           "a stencil map writes only the row of the point it visits, not " + element_text(row));
    int tag = col.offset_tag();
    if (tag < 0) {
      if (col.index() != ctx.element)
        fail(r.span, "write outside the stencil: column " + element_text(col));
      tag = ctx.offset_tag(std::vector<int>(ctx.grid->set->dimensions(), 0));
    }
    auto& per_offset = ctx.stencil[res];
    const int points = ctx.grid->set->points().size();
    while (per_offset.size() <= static_cast<size_t>(tag))
      per_offset.push_back(Value::of_tensor(
          Tensor(component_of(ctx.assembly->callee->results[res].var->type->component()),
                 Shape::blocked(std::vector<int>{points}, block))));
    p.root = &per_offset[tag];
    p.offset = static_cast<size_t>(row.index()) * bsize;
    return p;
  }
  const runtime::SystemMatrix& mat = *m.matrix();
  int32_t pos =
      mat.pattern().assembly_position(*ctx.target->set, ctx.element, row.index(), col.index());
  if (pos < 0)
    fail(r.span, "write to (" + element_text(row) + ", " + element_text(col) +
                     ") outside the sparsity pattern while mapping element " +
                     std::to_string(ctx.target->set->mesh_number(ctx.element)) + " of " +
                     ctx.target->set->describe());
  p.root = &m;
  p.offset = static_cast<size_t>(pos) * bsize;
  p.matrix_position = pos;
  return p;
}

// `f(p(0)) = t`, `K(v(i), v(j)) = B` in the mapped function itself: a write into one of the
// map's results at a member of the visited element goes straight to its block, without
// resolving a general place. False (nothing written) for any other target, which the
// general path then handles, with its checks and messages.
bool Interpreter::result_write(const ast::Expr& target, Value& value) {
  const auto* r = target.as<ast::TensorRead>();
  // `K(v(i), v(j))(a, d) = x`: one component of a block.
  const ast::TensorRead* component = nullptr;
  if (r && r->base->is<ast::TensorRead>()) {
    component = r;
    r = r->base->as<ast::TensorRead>();
  }
  // The frontend marked the writes into the function's system-tensor results.
  if (!r || r->assembles_result < 0 || map_->grid) return false;
  MapContext& ctx = *map_;
  const auto& base = static_cast<const ast::VarRef&>(*r->base);
  const size_t res = static_cast<size_t>(r->assembles_result);
  if (res >= ctx.values.size() || &var(*base.var) != &ctx.values[res]) return false;
  Value& root = ctx.values[res];
  Place p;
  p.whole = false;
  p.root = &root;
  p.accumulate = ctx.reduce;
  p.shape = ctx.blocks[res];
  if (root.kind() == Value::Kind::Matrix) {
    p.matrix_position = member_block(*r, root);
    if (p.matrix_position < 0) return false;
    p.offset = static_cast<size_t>(p.matrix_position) * p.shape.size();
    if (component && !block_component(*component, p)) return false;
  } else {
    if (component || !root.is_tensor() || r->indices.size() != 1 || !r->indices[0]) return false;
    const Shape& s = root.tensor().shape();
    const int m = s.order() == 1 ? member_of(*r->indices[0]) : -1;
    const int32_t e = m < 0 ? -1 : runtime::member_element(*ctx.target->set, ctx.element, m);
    if (e < 0 || e >= s.dim(0)) return false;
    p.offset = static_cast<size_t>(e) * p.shape.size();
  }
  write_place(p, std::move(value), target.span);
  return true;
}

// The block position of `K(x, y)` in matrix result `m` when x and y name members of the
// visited element (`K(v(i), v(j))`, `K(p, p)`): from the pattern's per-element table, with no
// search. -1 for anything else, which the general path evaluates and checks.
int32_t Interpreter::member_block(const ast::TensorRead& r, const Value& m) {
  const MapContext& ctx = *map_;
  if (ctx.grid || r.indices.size() != 2 || !r.indices[0] || !r.indices[1]) return -1;
  const runtime::MatrixPattern& pattern = m.matrix()->pattern();
  if (!pattern.assembled_through(*ctx.target->set)) return -1;
  const int rm = member_of(*r.indices[0]);
  const int cm = rm < 0 ? -1 : member_of(*r.indices[1]);
  if (cm < 0) return -1;
  const runtime::AssemblyIndex& a = pattern.assembly();
  const int rl = local_member(a.row_members, rm), cl = local_member(a.col_members, cm);
  return rl < 0 || cl < 0 ? -1 : a.position(ctx.element, rl, cl);
}

// Narrows a block place to the component `(a, d)` of an unblocked matrix block; false for
// anything else (the general path then evaluates the indices and reports errors).
bool Interpreter::block_component(const ast::TensorRead& r, Place& p) {
  const Shape& block = p.shape;
  if (block.levels() != 1 || block.order() != 2 || r.indices.size() != 2) return false;
  size_t at = 0;
  for (int k = 0; k < 2; ++k) {
    if (!r.indices[k]) return false;
    Value scratch;
    const Value& i = operand(*r.indices[k], scratch);
    if (i.kind() != Value::Kind::Int || i.as_int() < 0 || i.as_int() >= block.dim(k)) return false;
    at = at * static_cast<size_t>(block.dim(k)) + static_cast<size_t>(i.as_int());
  }
  p.offset += at;
  p.shape = Shape();
  return true;
}

// The member of the visited element an index of a matrix write names directly (0: the
// element parameter, k + 1: endpoint k read from its tuple); -1 for any other index, which
// the general path evaluates. Evaluates the tuple's index expression (calls in it were
// hoisted, so evaluating it again on the general path repeats no call).
int Interpreter::member_of(const ast::Expr& index) {
  const MapContext& ctx = *map_;
  if (const auto* t = index.as<ast::TupleRead>()) {
    const auto* base = t->base->as<ast::VarRef>();
    if (!base) return -1;
    const Value& tuple = var(*base->var);
    if (tuple.kind() != Value::Kind::Tuple || tuple.binding() != ctx.target ||
        tuple.index() != ctx.element)
      return -1;
    int k = t->member_index;
    if (t->index) {
      Value i = eval(*t->index);
      if (i.kind() != Value::Kind::Int) return -1;
      k = i.as_int();
    }
    return k >= 0 && k < ctx.target->set->arity() ? k + 1 : -1;
  }
  if (const auto* v = index.as<ast::VarRef>()) {
    const Value& e = var(*v->var);
    if (e.kind() == Value::Kind::Element && e.binding() == ctx.target && e.index() == ctx.element)
      return 0;
  }
  return -1;
}

int Interpreter::local_member(const std::vector<int>& members, int member) {
  for (size_t i = 0; i < members.size(); ++i)
    if (members[i] == member) return static_cast<int>(i);
  return -1;
}

// A write `r(x)` into a global vector result must name the visited element or an endpoint.
void Interpreter::check_vector_write(const ast::TensorRead& r, const Value& x) {
  if (map_->grid) return;
  const runtime::Set& t = *map_->target->set;
  const int e = map_->element;
  const runtime::Set* s = x.binding()->set;
  bool ok = s == &t && x.index() == e;
  for (int k = 0; !ok && k < t.arity(); ++k)
    ok = &t.endpoint_set(k) == s && t.endpoint(e, k) == x.index();
  if (!ok)
    fail(r.span, "write to " + element_text(x) + " outside the neighbourhood of element " +
                     std::to_string(t.mesh_number(e)) + " of " + t.describe());
}

Value Interpreter::finish_grid_result(MapContext& ctx, size_t res) {
  const runtime::Set& grid = *ctx.grid->set;
  const Shape& block = ctx.blocks[res];
  const runtime::BlockDims bd = runtime::block_dims(block);
  const ComponentKind kind =
      component_of(ctx.assembly->callee->results[res].var->type->component());
  runtime::PatternPtr pattern = patterns_.stencil(grid, ctx.offsets);
  auto m = std::make_shared<runtime::SystemMatrix>(pattern, bd.rows, bd.cols, kind);
  const size_t bsize = block.size();
  const auto& rp = pattern->row_ptr();
  for (size_t j = 0; j < ctx.stencil[res].size(); ++j) {
    const Tensor& src = ctx.stencil[res][j].tensor();
    for (int p = 0; p + 1 < static_cast<int>(rp.size()); ++p)
      store_tensor_part(*m, (rp[p] + j) * bsize, src, p * bsize, bsize);
  }
  return Value::of_matrix(std::move(m));
}

}  // namespace simit::interp
