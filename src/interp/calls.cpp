// Calls of user functions: arguments, inout parameters, generic bindings, results.
#include "interp/frame.h"
#include "interp/interpreter.h"

namespace simit::interp {

namespace ast = frontend::ast;
using frontend::IndexSet;
using frontend::SourceSpan;
using frontend::Type;

bool Interpreter::has_inout(const ast::FuncDecl& f) {
  for (const ast::Param& p : f.params)
    if (p.inout) return true;
  return false;
}

bool Interpreter::is_local(const ast::Variable& v) {
  using K = ast::Variable::Kind;
  return v.kind == K::Param || v.kind == K::Result || v.kind == K::Local || v.kind == K::LoopVar;
}

Value Interpreter::eval_call(const ast::Call& c) {
  if (c.intrinsic != frontend::Intrinsic::None) {
    Value v = call_intrinsic(c);
    finish(v, c);
    return v;
  }
  if (hoisted_.size() > hoist_base_) [[unlikely]] {
    Value v;
    if (take_hoisted(c, v)) return v;
  }
  return eval_user_call(c);
}

Value Interpreter::eval_user_call(const ast::Call& c) {
  Frame& callee = run_call(c);
  if (c.func->results.empty()) return {};
  return std::move(callee.slots[c.func->results[0].var->slot]);
}

std::vector<Value> Interpreter::eval_multi(const ast::Expr& e) {
  if (const auto* m = e.as<ast::Map>()) return eval_map(*m);
  const auto* c = e.as<ast::Call>();
  if (!c) fail(e.span, "expression does not produce several values");
  if (c->intrinsic != frontend::Intrinsic::None) {
    if (e.type && e.type->kind == Type::Kind::Multi) return call_decomposition(*c);
    return {eval_call(*c)};
  }
  Frame& callee = run_call(*c);
  std::vector<Value> results;
  results.reserve(c->func->results.size());
  for (const ast::Param& r : c->func->results)
    results.push_back(std::move(callee.slots[r.var->slot]));
  return results;
}

// Evaluates the arguments left to right, runs the callee and writes inout components back.
// The callee's frame stays intact until the next call at the same depth, so the caller
// can take the results out of it.
Interpreter::Frame& Interpreter::run_call(const ast::Call& c) {
  if (!c.func) fail(c.span, "call of an unresolved function '" + c.callee + "'");
  const ast::FuncDecl& f = *c.func;
  if (f.is_extern) fail(c.span, "external function '" + f.name + "' has no implementation bound");
  const size_t arg_base = arg_stack_.size(), inout_base = inout_stack_.size();
  const bool by_reference = !has_inout(f);
  for (size_t i = 0; i < c.args.size(); ++i) {
    if (f.params[i].inout) {
      push_inout_arg(*c.args[i], f.params[i].var->slot);
    } else if (const auto* r = c.args[i]->as<ast::VarRef>();
               r && by_reference && is_local(*r->var)) {
      // A read-only parameter sees the caller's variable itself: nothing can change that
      // variable while the callee runs (no inout parameter aliases it), so no copy is made.
      arg_stack_.push_back(Arg{Value(), &read_var(*r->var, *r)});
    } else {
      arg_stack_.push_back(Arg{eval(*c.args[i]), nullptr});
    }
  }
  Frame& callee = enter(f, arg_base, inout_base, &c);
  execute_body(f);
  write_back_inout(inout_base, callee, c.span);
  return callee;
}

void Interpreter::push_inout_arg(const ast::Expr& arg, int slot) {
  if (const auto* r = arg.as<ast::VarRef>()) {
    inout_stack_.push_back(InoutArg{&read_var(*r->var, arg), {}, false, slot});
    arg_stack_.emplace_back();
    return;
  }
  if (arg.is<ast::TupleRead>()) {
    // An endpoint passed on as an element: elements are references, nothing to write back.
    arg_stack_.push_back(Arg{eval(arg), nullptr});
    inout_stack_.push_back(InoutArg{nullptr, {}, false, slot});
    return;
  }
  Place p = resolve_place(arg);
  arg_stack_.push_back(Arg{read_place(p), nullptr});
  inout_stack_.push_back(InoutArg{nullptr, p, true, slot});
}

void Interpreter::write_back_inout(size_t inout_base, Frame& callee, const SourceSpan& at) {
  for (size_t k = inout_base; k < inout_stack_.size(); ++k) {
    InoutArg& a = inout_stack_[k];
    if (a.write_back) write_place(a.place, std::move(callee.slots[a.slot]), at);
  }
  inout_stack_.resize(inout_base);
}

Interpreter::Frame& Interpreter::enter(const ast::FuncDecl& f, size_t arg_base, size_t inout_base,
                                       const ast::Call* c) {
  constexpr int kMaxDepth = 10000;  // recursion is rejected statically; this is a backstop
  if (depth_ + 1 >= kMaxDepth) fail(c ? c->span : f.span, "call depth limit exceeded");
  Frame& callee = next_frame(f, c ? c->span : SourceSpan{}, nullptr);
  size_t inout = inout_base;
  for (size_t i = 0; i < f.params.size(); ++i) {
    const int slot = f.params[i].var->slot;
    if (f.params[i].inout) {
      const InoutArg& a = inout_stack_[inout++];
      if (a.whole) {
        callee.refs[slot] = a.whole;
        continue;
      }
    }
    Arg& a = arg_stack_[arg_base + i];
    if (a.ref)
      callee.refs[slot] = a.ref;
    else
      callee.slots[slot] = std::move(a.value);
  }
  arg_stack_.resize(arg_base);
  bind_generics(f, callee, c);
  ++depth_;
  // Results start at zero on every call (§4.5.2, Q21).
  for (const ast::Param& r : f.results) callee.slots[r.var->slot] = zero_of(*r.var->type, r.span);
  return callee;
}

// Generic parameters take the sizes of the actual arguments; those that no argument
// mentions come from the call's explicit or deduced bindings.
void Interpreter::bind_generics(const ast::FuncDecl& f, Frame& callee, const ast::Call* c) {
  if (f.generics.empty()) return;
  const SourceSpan at = c ? c->span : f.name_span;
  for (const ast::GenericParam& g : f.generics) callee.slots[g.var->slot] = Value();
  for (const ast::Param& p : f.params) {
    const Value& v = *callee.refs[p.var->slot];
    if (p.var->type && p.var->type->kind == Type::Kind::Tensor && v.is_tensor())
      deduce(*p.var->type, v.tensor().shape(), callee, at);
  }
  for (size_t i = 0; c && i < c->bindings.size() && i < f.generics.size(); ++i) {
    Value& slot = callee.slots[f.generics[i].var->slot];
    const IndexSet& b = c->bindings[i];
    if (!slot.empty()) continue;
    if (b.kind == IndexSet::Kind::Fixed) slot = Value::of_int(b.size);
    if (b.kind == IndexSet::Kind::Generic && b.var) slot = *frame().refs[b.var->slot];
  }
  for (const ast::GenericParam& g : f.generics)
    if (callee.slots[g.var->slot].empty())
      fail(at, "cannot bind generic parameter '" + g.name + "' of '" + f.name + "' to a size");
}

void Interpreter::deduce(const Type& param, const Shape& arg, Frame& callee, const SourceSpan& at) {
  if (param.kind != Type::Kind::Tensor || arg.is_scalar()) return;
  for (size_t k = 0; k < param.dims.size() && static_cast<int>(k) < arg.order(); ++k) {
    const IndexSet& d = param.dims[k];
    if (d.kind != IndexSet::Kind::Generic || !d.var || d.var->func != callee.func) continue;
    Value& slot = callee.slots[d.var->slot];
    int size = arg.dim(static_cast<int>(k));
    if (slot.empty())
      slot = Value::of_int(size);
    else if (slot.kind() == Value::Kind::Int && slot.as_int() != size)
      fail(at, "generic parameter '" + d.var->name + "' is bound to " +
                   std::to_string(slot.as_int()) + " but an argument has size " +
                   std::to_string(size));
  }
  if (param.block) deduce(*param.block, arg.block(), callee, at);
}

void Interpreter::execute_body(const ast::FuncDecl& f) {
  // Hoisted results of the caller's expression are not this body's to take.
  const size_t saved_base = hoist_base_;
  hoist_base_ = hoisted_.size();
  try {
    exec_block(f.body);
  } catch (RuntimeError& e) {
    e.add_frame(f.name, frame().call_site);
    --depth_;
    hoist_base_ = saved_base;
    throw;
  }
  --depth_;
  hoist_base_ = saved_base;
}

}  // namespace simit::interp
