// Inspection of a paused run: frames, their variables and map contexts, and the evaluation
// of debugger expressions in a chosen frame.
#include "frontend/ast_walk.h"
#include "interp/frame.h"
#include "interp/interpreter.h"
#include "interp/map_context.h"

namespace simit::interp {

namespace ast = frontend::ast;

namespace {

bool is_global(const ast::Variable& v) {
  return v.kind == ast::Variable::Kind::Extern || v.kind == ast::Variable::Kind::GlobalConst;
}

// Why `e` cannot be evaluated in a frame of `func` with `slots` slots: a call that would run
// statements, or a variable of another function. Empty when it can.
std::string refusal(const ast::Expr& e, const ast::FuncDecl* func, size_t slots) {
  if (const auto* c = e.as<ast::Call>(); c && c->intrinsic == frontend::Intrinsic::None)
    return "calls of user functions ('" + c->callee + "') cannot be evaluated by the debugger";
  if (e.is<ast::Map>()) return "maps cannot be evaluated by the debugger";
  if (const auto* r = e.as<ast::VarRef>(); r && r->var && !is_global(*r->var)) {
    const ast::Variable& v = *r->var;
    if (v.func != func || v.slot < 0 || static_cast<size_t>(v.slot) >= slots)
      return "'" + v.name + "' is not a variable of this frame";
  }
  std::string why;
  ast::for_each_child(e, [&](const ast::Expr& c) {
    if (why.empty()) why = refusal(c, func, slots);
  });
  return why;
}

}  // namespace

FrameView Interpreter::frame_view(int level) const {
  FrameView v;
  if (level < 0 || level >= depth_) return v;
  const Frame& f = *frames_[depth_ - level];
  v.func = f.func;
  v.depth = depth_ - level - 1;
  v.call_site = f.call_site;
  if (level > 0) v.position = frames_[depth_ - level + 1]->call_site;
  v.activation = f.activation;
  if (!f.map) return v;
  const MapContext& ctx = *f.map;
  MapView m;
  m.assembly = ctx.assembly;
  m.at = ctx.at;
  m.is_apply = ctx.assembly && ctx.assembly->callee && ctx.assembly->callee->results.empty();
  m.set = ctx.target ? ctx.target->set : nullptr;
  m.element = ctx.element;
  if (m.set && !m.set->is_grid() && m.element >= 0 && m.element < m.set->size()) {
    const ast::Variable* target = ctx.assembly ? ctx.assembly->target_set : nullptr;
    const frontend::Type* type = target && target->type ? target->type.get() : nullptr;
    for (int k = 0; k < m.set->arity(); ++k) {
      MapView::Endpoint ep;
      if (type && static_cast<size_t>(k) < type->endpoints.size())
        ep.set_var = type->endpoints[k].var;
      ep.set = &m.set->endpoint_set(k);
      ep.index = m.set->endpoint(m.element, k);
      m.endpoints.push_back(ep);
    }
  }
  v.map = std::move(m);
  return v;
}

const Value* Interpreter::frame_value(int level, const ast::Variable& var) const {
  const Value* value = nullptr;
  if (is_global(var)) {
    if (var.slot >= 0 && static_cast<size_t>(var.slot) < globals_.size())
      value = &globals_[var.slot];
  } else if (level >= 0 && level < depth_) {
    const Frame& f = *frames_[depth_ - level];
    if (var.func == f.func && var.slot >= 0 && static_cast<size_t>(var.slot) < f.refs.size())
      value = f.refs[var.slot];
  }
  return value && !value->empty() ? value : nullptr;
}

Value Interpreter::evaluate(const ast::Expr& expr, int level) const {
  // Nothing here outlives the call: the depth and the option are put back on every exit,
  // and evaluating without calls touches no argument stack, hoisting state or frame.
  // The hook receives a const interpreter; this is the one place that works through it.
  auto& self = const_cast<Interpreter&>(*this);
  if (level < 0 || (depth_ > 0 && level >= depth_) || (depth_ == 0 && level > 0))
    fail(expr.span, "no frame #" + std::to_string(level));
  const Frame& f = *frames_[depth_ - level];
  if (std::string why = refusal(expr, depth_ > 0 ? f.func : nullptr, f.refs.size()); !why.empty())
    fail(expr.span, why);
  struct Restore {
    Interpreter& in;
    int depth;
    bool check_finite;
    ~Restore() {
      in.depth_ = depth;
      in.options_.check_finite = check_finite;
    }
  } restore{self, depth_, options_.check_finite};
  self.depth_ = depth_ - level;
  self.options_.check_finite = false;
  return self.eval(expr);
}

}  // namespace simit::interp
