// The interpreter's core: construction, entry calls, variables and types at run time.
#include "interp/interpreter.h"
#include "interp/set_binding.h"

#include <cmath>

#include "interp/frame.h"
#include "interp/operators.h"
#include "runtime/fault.h"
#include "runtime/residency.h"

namespace simit::interp {

using frontend::IndexSet;
using frontend::ScalarKind;
using frontend::SourceSpan;
using frontend::Type;
namespace ast = frontend::ast;

ComponentKind component_of(ScalarKind k) {
  switch (k) {
    case ScalarKind::Int: return ComponentKind::Int;
    case ScalarKind::Float: return ComponentKind::Float;
    case ScalarKind::Bool: return ComponentKind::Bool;
    case ScalarKind::Complex: return ComponentKind::Complex;
    case ScalarKind::String: return ComponentKind::String;
  }
  return ComponentKind::Float;
}

Interpreter::Interpreter(const ast::Program& program, Options options)
    : program_(program), options_(options) {
  post_process_ = options_.float32 || options_.check_finite;
  if (options_.trap)
    trap_ = options_.trap;
  else if (options_.hook)
    own_trap_.install(options_.hook);
  globals_.resize(program.globals.size());
  frames_.push_back(std::make_unique<Frame>());
  for (const auto& decl : program.decls) {
    const auto* c = decl->as<ast::ConstDecl>();
    if (!c || !c->decl || !c->decl->var) continue;
    exec_var_decl(*c->decl);
  }
}

Interpreter::~Interpreter() = default;

std::vector<Value> Interpreter::call(const ast::FuncDecl& func, std::vector<Value> args) {
  if (args.size() != func.params.size())
    fail(func.name_span, "'" + func.name + "' expects " + std::to_string(func.params.size()) +
                             " arguments but got " + std::to_string(args.size()));
  for (size_t i = 0; i < args.size(); ++i) check_argument(func.params[i], args[i]);
  const int base_depth = depth_;
  const size_t arg_base = arg_stack_.size(), inout_base = inout_stack_.size();
  try {
    for (size_t i = 0; i < args.size(); ++i) {
      if (func.params[i].inout)
        inout_stack_.push_back(InoutArg{nullptr, {}, false, func.params[i].var->slot});
      arg_stack_.push_back(Arg{std::move(args[i]), nullptr});
    }
    Frame& callee = enter(func, arg_base, inout_base, nullptr);
    inout_stack_.resize(inout_base);
    execute_body(func);
    std::vector<Value> results;
    for (const ast::Param& r : func.results)
      results.push_back(std::move(callee.slots[r.var->slot]));
    bring_arrays_home(base_depth, true);
    return results;
  } catch (...) {
    // What the call wrote before it failed is the host's to see too.
    try {
      bring_arrays_home(base_depth, false);
    } catch (const std::exception&) {
      // The call's own error is the one to report.
    }
    // Leave the interpreter usable for the next call.
    depth_ = base_depth;
    arg_stack_.resize(arg_base);
    inout_stack_.resize(inout_base);
    hoisted_.clear();
    hoist_base_ = 0;
    throw;
  }
}

// The host that called reads what the call left through pointers of its own (a scene's
// stepper, the API's and Python's views), which bring nothing back: every array whose newest
// contents an executor keeps in its memory comes home now (runtime/residency.h). After a
// call that returned, its frames' locals go first: nothing reads them again, and arrays that
// only they held are dropped rather than copied.
void Interpreter::bring_arrays_home(int base_depth, bool release_locals) {
  if (options_.host_uses_accessors || !runtime::residency::any_elsewhere()) return;
  if (release_locals) {
    for (size_t d = static_cast<size_t>(base_depth) + 1; d < frames_.size(); ++d)
      for (Value& v : frames_[d]->slots) v = Value();
    // A site's last matrix that nothing else holds is kept only to be zeroed and reused.
    for (auto& [site, plan] : plans_)
      for (AssemblyPlan::Result& r : plan.results)
        if (r.last && r.last.use_count() == 1) runtime::residency::settle(r.last->raw_values());
    if (options_.sites) options_.sites->drop_reusable();
  }
  runtime::residency::bring_back_all();
}

namespace {

// Whether a value of `shape` with `kind` components fits `t` (generic dimensions fit any
// size; the call binds them).
bool fits(const Type& t, ComponentKind kind, const Shape& shape) {
  if (t.kind == Type::Kind::Scalar) return shape.is_scalar() && component_of(t.scalar) == kind;
  if (t.kind != Type::Kind::Tensor || shape.is_scalar()) return false;
  if (static_cast<int>(t.dims.size()) != shape.order()) return false;
  for (size_t k = 0; k < t.dims.size(); ++k)
    if (t.dims[k].kind == IndexSet::Kind::Fixed && t.dims[k].size != shape.dim(static_cast<int>(k)))
      return false;
  return t.block && fits(*t.block, kind, shape.block());
}

}  // namespace

void Interpreter::check_argument(const ast::Param& p, const Value& v) const {
  const Type& t = *p.var->type;
  if (!t.is_tensor() || v.kind() == Value::Kind::Matrix) return;
  if (v.empty() || !fits(t, v.component_kind(), v.shape()))
    fail(p.span, "the value passed for '" + p.name + "' does not have its type '" +
                     frontend::to_string(t) + "'");
}

Value Interpreter::evaluate_constant(const ast::Expr& expr) { return eval(expr); }

void Interpreter::set_global(const ast::Variable& v, Value value) {
  globals_.at(v.slot) = std::move(value);
}

const Value& Interpreter::global(const ast::Variable& v) const { return globals_.at(v.slot); }

const Value* Interpreter::local(const ast::Variable& v) const {
  const Frame& f = frame();
  if (v.func != f.func || v.slot < 0 || static_cast<size_t>(v.slot) >= f.refs.size())
    return nullptr;
  const Value* value = f.refs[v.slot];
  return value->empty() ? nullptr : value;
}

Interpreter::Frame& Interpreter::next_frame(const ast::FuncDecl& f, const SourceSpan& call_site,
                                            MapContext* map) {
  if (frames_.size() <= static_cast<size_t>(depth_ + 1))
    frames_.push_back(std::make_unique<Frame>());
  Frame& callee = *frames_[depth_ + 1];
  callee.func = &f;
  callee.call_site = call_site;
  callee.map = map;
  callee.activation = ++activations_;
  const size_t n = static_cast<size_t>(f.frame_size);
  if (callee.slots.size() < n) {
    callee.slots.resize(n);
    callee.refs.resize(n);
  }
  // A call starts with empty variables: values of the previous activation at this depth
  // are released now (a map's matrix can then be reused, assembly_plan.h). The elements of
  // a map overwrite their small locals instead, one element after the other.
  if (!map)
    for (size_t i = 0; i < n; ++i) callee.slots[i] = Value();
  for (size_t i = 0; i < n; ++i) callee.refs[i] = &callee.slots[i];
  return callee;
}

void Interpreter::fail_unset(const ast::Variable& v, const ast::Expr& at) const {
  if (v.kind == ast::Variable::Kind::Extern)
    fail(at.span, "extern '" + v.name + "' has no value (the host did not bind it)");
  if (v.kind == ast::Variable::Kind::Generic)
    fail(at.span, "generic parameter '" + v.name + "' is bound to a set, not to a size");
  fail(at.span, "'" + v.name + "' is read before it has a value");
}

int Interpreter::dim_size(const IndexSet& d, const SourceSpan& at) {
  switch (d.kind) {
    case IndexSet::Kind::Fixed: return d.size;
    case IndexSet::Kind::Generic: {
      const Value& v = *frame().refs[d.var->slot];
      if (v.kind() == Value::Kind::Int) return v.as_int();
      if (v.kind() == Value::Kind::Set) return v.binding()->set->size();
      break;
    }
    case IndexSet::Kind::Set: return set_size(*d.var, at);
  }
  unsupported(at, "tensors with set dimensions");
}

Shape Interpreter::shape_of(const Type& t, const SourceSpan& at) {
  if (t.kind == Type::Kind::Scalar) return Shape();
  if (t.kind != Type::Kind::Tensor) unsupported(at, "values of element, set, tuple or opaque type");
  // The common case, a small unblocked vector or matrix of fixed size.
  if (!t.dims.empty() && t.dims.size() <= 2 && (!t.block || t.block->kind == Type::Kind::Scalar) &&
      t.dims[0].kind == IndexSet::Kind::Fixed &&
      (t.dims.size() == 1 || t.dims[1].kind == IndexSet::Kind::Fixed))
    return t.dims.size() == 1 ? Shape{t.dims[0].size} : Shape{t.dims[0].size, t.dims[1].size};
  int dims[Shape::kMaxRank];
  int n = 0;
  for (const IndexSet& d : t.dims) {
    if (n == Shape::kMaxRank) fail(at, "tensor has too many dimensions");
    dims[n++] = dim_size(d, at);
  }
  Shape block = t.block ? shape_of(*t.block, at) : Shape();
  try {
    return Shape::blocked(dims, n, block);
  } catch (const runtime::Fault& f) {
    fail(at, f.what());
  }
}

Value Interpreter::zero_of(const Type& t, const SourceSpan& at) {
  auto set_dim = [&](const IndexSet& d) {
    if (d.kind == IndexSet::Kind::Set) return true;
    return d.kind == IndexSet::Kind::Generic &&
           frame().refs[d.var->slot]->kind() == Value::Kind::Set;
  };
  if (t.kind == Type::Kind::Tensor && t.dims.size() == 2 && set_dim(t.dims[0]) &&
      set_dim(t.dims[1])) {
    // A system matrix nothing was assembled into: an empty pattern (every component zero).
    const int rows = dim_size(t.dims[0], at), cols = dim_size(t.dims[1], at);
    Shape block = t.block ? shape_of(*t.block, at) : Shape();
    auto pattern =
        runtime::MatrixPattern::from_csr(rows, cols, std::vector<int32_t>(rows + 1, 0), {});
    try {
      const runtime::BlockDims bd = runtime::block_dims(block);
      return Value::of_matrix(std::make_shared<runtime::SystemMatrix>(pattern, bd.rows, bd.cols,
                                                                      component_of(t.component())));
    } catch (const runtime::Fault& f) {
      fail(at, f.what());
    }
  }
  if (t.kind == Type::Kind::Opaque || t.kind == Type::Kind::Element ||
      t.kind == Type::Kind::Tuple || t.kind == Type::Kind::Set)
    return {};
  Shape shape = shape_of(t, at);
  try {
    return Value::zero(component_of(t.component()), shape);
  } catch (const runtime::Fault& f) {  // out of memory
    fail(at, f.what());
  }
}

void Interpreter::fail(const SourceSpan& at, std::string message) const {
  throw RuntimeError(at, std::move(message));
}

void Interpreter::unsupported(const SourceSpan& at, const char* what) const {
  fail(at, std::string(what) + " are not supported by the interpreter yet");
}

void Interpreter::check_result(Value& v, const ast::Expr& at) {
  if (options_.float32) round_to_float32(v);
  if (options_.check_finite && !is_finite(v)) {
    if (v.kind() == Value::Kind::Float)
      fail(at.span, std::isnan(v.as_float()) ? "the operation produced NaN"
                                             : "the operation produced an infinity");
    fail(at.span, "the operation produced a NaN or an infinity");
  }
}

void Interpreter::finish(Value& v, const ast::Expr& at) {
  if (post_process_) [[unlikely]]
    check_result(v, at);
}

}  // namespace simit::interp
