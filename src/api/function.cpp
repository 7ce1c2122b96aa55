// Functions: bindings by name, checks at bind and init time, and runs through the engine.
#include <cstring>
#include <map>
#include <optional>

#include "api/engine.h"
#include "api/set_access.h"
#include "api/stop_on_sigint.h"
#include "binding_check.h"
#include "runtime/fault.h"
#include "simit/program.h"
#include "tensor_values.h"

namespace simit {

namespace ast = frontend::ast;
using frontend::IndexSet;
using frontend::Type;
using interp::Value;
using RtKind = runtime::ComponentKind;  // simit::ComponentKind is the host-facing one

namespace {

// One bindable name: an extern, a parameter or a result of the function.
struct Slot {
  enum class Role { Extern, Param, Result };
  Role role = Role::Extern;
  const ast::Variable* var = nullptr;
  int index = 0;  // parameter / result position
  runtime::Set* set = nullptr;
  std::optional<TensorSlot> tensor;
  bool bound() const { return set || tensor; }
  bool is_set() const { return var->type && var->type->kind == Type::Kind::Set; }
  std::string what() const {
    const char* role_name[] = {"extern", "parameter", "result"};
    return std::string(role_name[static_cast<int>(role)]) + " '" + var->name + "'";
  }
};

runtime::Shape shape_of(const Type& t) {
  if (t.kind != Type::Kind::Tensor) return runtime::Shape();
  std::vector<int> outer;
  for (const IndexSet& d : t.dims) outer.push_back(d.size);
  runtime::Shape block = t.block ? shape_of(*t.block) : runtime::Shape();
  return block.is_scalar() ? runtime::Shape::of(outer) : runtime::Shape::blocked(outer, block);
}

template <class T>
T component(const TensorSlot& s, size_t i) {
  if (s.kind == simit::ComponentKind::Float)
    return s.single ? static_cast<T>(static_cast<const float*>(s.data)[i])
                    : static_cast<T>(static_cast<const double*>(s.data)[i]);
  return static_cast<const T*>(s.data)[i];
}

runtime::Complex complex_component(const TensorSlot& s, size_t i) {
  return s.single ? runtime::Complex(static_cast<const std::complex<float>*>(s.data)[i])
                  : static_cast<const runtime::Complex*>(s.data)[i];
}

}  // namespace

namespace api {

// The host tensor's value as an interpreter value of type `t` (already checked to match).
Value to_value(const TensorSlot& s, const Type& t) {
  if (t.kind == Type::Kind::Scalar) {
    switch (api::runtime_kind(s.kind)) {
      case RtKind::Int: return Value::of_int(component<int32_t>(s, 0));
      case RtKind::Float: return Value::of_float(component<double>(s, 0));
      case RtKind::Bool: return Value::of_bool(component<bool>(s, 0));
      case RtKind::Complex: return Value::of_complex(complex_component(s, 0));
      case RtKind::String: break;
    }
    throw Error("string tensors cannot be bound");
  }
  runtime::Tensor out(api::runtime_kind(s.kind), shape_of(t));
  for (size_t i = 0; i < out.size(); ++i) {
    switch (api::runtime_kind(s.kind)) {
      case RtKind::Int: out.mutable_ints()[i] = component<int32_t>(s, i); break;
      case RtKind::Float: out.mutable_floats()[i] = component<double>(s, i); break;
      case RtKind::Bool: out.mutable_bools()[i] = component<bool>(s, i); break;
      case RtKind::Complex: out.mutable_complexes()[i] = complex_component(s, i); break;
      case RtKind::String: break;
    }
  }
  return Value::of_tensor(std::move(out));
}

// Writes an interpreter value back into the host tensor it came from.
void from_value(const Value& v, const TensorSlot& s) {
  if (!v.is_scalar() && !v.is_tensor()) return;
  runtime::Tensor t = v.to_tensor();
  for (size_t i = 0; i < t.size(); ++i) {
    switch (api::runtime_kind(s.kind)) {
      case RtKind::Int: static_cast<int32_t*>(s.data)[i] = t.ints()[i]; break;
      case RtKind::Float:
        if (s.single)
          static_cast<float*>(s.data)[i] = static_cast<float>(t.floats()[i]);
        else
          static_cast<double*>(s.data)[i] = t.floats()[i];
        break;
      case RtKind::Bool: static_cast<bool*>(s.data)[i] = t.bools()[i]; break;
      case RtKind::Complex:
        if (s.single)
          static_cast<std::complex<float>*>(s.data)[i] = std::complex<float>(t.complexes()[i]);
        else
          static_cast<runtime::Complex*>(s.data)[i] = t.complexes()[i];
        break;
      case RtKind::String: break;
    }
  }
}

}  // namespace api

using api::from_value;
using api::to_value;

struct Function::Impl {
  std::shared_ptr<const api::CompiledProgram> loaded;
  Options options;
  const ast::FuncDecl* func = nullptr;
  std::map<std::string, Slot> slots;  // every bindable name
  std::vector<std::string> needed;    // externs used and parameters, in order
  std::unique_ptr<api::Engine> engine;
  std::vector<std::pair<const runtime::Set*, uint64_t>> topology;  // at init
  std::vector<Value> results;
  RunStats stats;
  interp::Trap trap;  // Ctrl-C's switch (Options::stop_on_interrupt)

  Slot& slot(const std::string& name) {
    auto it = slots.find(name);
    if (it == slots.end())
      throw BindError({"'" + name + "' is not an extern of the program nor a parameter or " +
                       "result of '" + func->name + "'"});
    return it->second;
  }
  const runtime::Set* bound_set(const ast::Variable& v) const {
    auto it = slots.find(v.name);
    return it != slots.end() && it->second.var == &v ? it->second.set : nullptr;
  }
  std::vector<std::string> endpoint_problems(const Slot& s) const {
    return api::check_endpoints(*s.var, *s.set,
                                [&](const ast::Variable& v) { return bound_set(v); });
  }
  bool stale() const {
    if (!engine) return true;
    for (auto [set, version] : topology)
      if (set->topology_version() != version) return true;
    return false;
  }
  void init();
  void run();
};

Function::Function() = default;
Function::Function(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
Function::~Function() = default;
Function::Function(Function&&) noexcept = default;
Function& Function::operator=(Function&&) noexcept = default;

Function::Impl& Function::impl() const {
  if (!impl_) throw Error("use of an undefined Function (compile one from a Program)");
  return *impl_;
}

const std::string& Function::name() const { return impl().func->name; }

Function Program::compile(const std::string& name) const {
  if (!loaded_) throw Error("compile('" + name + "'): no program is loaded");
  if (std::string bad = executor_unavailable(options_.executor); !bad.empty()) throw Error(bad);
  const ast::Program& program = loaded_->program();
  const ast::FuncDecl* f = program.find_func(name);
  if (!f || f->is_extern) throw Error("the program has no function '" + name + "' to compile");
  auto impl = std::make_unique<Function::Impl>();
  impl->loaded = loaded_;
  impl->options = options_;
  impl->func = f;
  for (const ast::Variable* g : program.globals)
    if (g && g->kind == ast::Variable::Kind::Extern)
      impl->slots[g->name] = Slot{Slot::Role::Extern, g, 0, nullptr, std::nullopt};
  for (const ast::Variable* g : f->extern_uses) impl->needed.push_back(g->name);
  for (size_t i = 0; i < f->params.size(); ++i) {
    impl->slots[f->params[i].name] =
        Slot{Slot::Role::Param, f->params[i].var, static_cast<int>(i), nullptr, std::nullopt};
    impl->needed.push_back(f->params[i].name);
  }
  for (size_t i = 0; i < f->results.size(); ++i)
    impl->slots[f->results[i].name] =
        Slot{Slot::Role::Result, f->results[i].var, static_cast<int>(i), nullptr, std::nullopt};
  return Function(std::move(impl));
}

void Function::bind(const std::string& name, Set& set) {
  Impl& im = impl();
  Slot& s = im.slot(name);
  if (s.role != Slot::Role::Extern || !s.is_set())
    throw BindError({s.what() + " is " + frontend::to_string(*s.var->type) +
                     ", not a set extern, but a set (" + api::SetAccess::of(set).describe() +
                     ") was bound to it"});
  std::vector<std::string> problems =
      api::check_set(*s.var, api::SetAccess::of(set), im.options.float_size);
  runtime::Set* previous = s.set;
  s.set = &api::SetAccess::of(set);
  for (const std::string& p : im.endpoint_problems(s)) problems.push_back(p);
  if (!problems.empty()) {
    s.set = previous;
    throw BindError(std::move(problems));
  }
  im.engine.reset();  // rebinding needs init() again (run() does it by itself)
}

void Function::bind(const std::string& name, const TensorSlot& tensor) {
  Impl& im = impl();
  Slot& s = im.slot(name);
  if (s.is_set())
    throw BindError({s.what() + " is a set (" + frontend::to_string(*s.var->type) +
                     ") but a host tensor was bound to it"});
  if (!tensor.data) throw BindError({s.what() + ": the host tensor has no storage"});
  std::vector<std::string> problems =
      api::check_tensor(s.what(), *s.var->type, tensor, im.options.float_size);
  if (!problems.empty()) throw BindError(std::move(problems));
  s.tensor = tensor;
  im.engine.reset();
}

std::optional<FieldType> Function::tensor_type(const std::string& name) const {
  Impl& im = impl();
  const Slot& s = im.slot(name);
  if (s.is_set()) return std::nullopt;
  const auto t = api::field_type_for(*s.var->type, im.options.float_size);
  if (!t) return std::nullopt;
  return FieldType{api::host_kind(t->kind), t->dims, t->single};
}

std::vector<std::string> Function::unbound() const {
  std::vector<std::string> out;
  for (const std::string& n : impl().needed)
    if (!impl().slots.at(n).bound()) out.push_back(n);
  return out;
}

void Function::init() { impl().init(); }
void Function::run() { impl().run(); }

void Function::Impl::init() {
  std::vector<std::string> problems;
  for (const std::string& n : needed) {
    const Slot& s = slots.at(n);
    if (!s.bound())
      problems.push_back(s.what() + " is not bound (" + frontend::to_string(*s.var->type) + ")");
  }
  // Endpoint sets: checked again now that every set is bound (their binding order is free).
  for (const auto& [n, s] : slots)
    if (s.set)
      for (const std::string& p : endpoint_problems(s)) problems.push_back(p);
  if (!problems.empty()) {
    problems.insert(problems.begin(), "cannot initialise '" + func->name + "':");
    throw BindError(std::move(problems));
  }
  api::EngineOptions eo;
  eo.executor = options.executor;  // the user's choice, whole (checked by compile)
  eo.float32 = options.float_size == 4;
  eo.check_finite = options.check_finite;
  eo.out = options.out;
  if (options.stop_on_interrupt) eo.trap = &trap;
  engine = std::make_unique<api::Engine>(loaded, eo);
  topology.clear();
  try {
    // Vertex sets first: an edge set's binding refers to its endpoint sets' bindings.
    for (int pass = 0; pass < 2; ++pass)
      for (const std::string& n : needed) {
        const Slot& s = slots.at(n);
        if (s.set && (s.set->arity() == 0) == (pass == 0)) {
          engine->bind_set(*s.var, *s.set);
          topology.emplace_back(s.set, s.set->topology_version());
        }
      }
  } catch (const interp::RuntimeError& e) {
    engine.reset();
    throw BindError({"cannot initialise '" + func->name + "': " + e.message()});
  }
}

void Function::Impl::run() {
  if (stale()) init();
  std::vector<Value> args(func->params.size());
  for (const auto& [n, s] : slots) {
    if (!s.tensor) continue;
    if (s.role == Slot::Role::Extern) engine->set_global(*s.var, to_value(*s.tensor, *s.var->type));
    if (s.role == Slot::Role::Param) args[s.index] = to_value(*s.tensor, *s.var->type);
  }
  engine->reset_stats();
  // Counted on the way out too, so that a failed run's time is not lost.
  auto account = [&] {
    ++stats.runs;
    stats.assembly_seconds += engine->stats().assembly_seconds;
    stats.assemblies += engine->stats().maps;
  };
  try {
    std::optional<api::StopOnSigint> stop_on_sigint;
    if (options.stop_on_interrupt) {
      trap.take_interrupt();  // one that came after the previous run had finished
      stop_on_sigint.emplace(trap);
    }
    results = engine->call(*func, std::move(args));
  } catch (const interp::Interrupted& e) {
    account();
    trap.take_interrupt();  // the next run starts afresh
    throw Interrupted(e.render(), e.line());
  } catch (const interp::RuntimeError& e) {
    account();
    throw RuntimeError(e.render(), e.line());
  } catch (const runtime::Fault& e) {
    account();
    throw RuntimeError(std::string("runtime error: ") + e.what(), 0);
  }
  account();
  for (const auto& [n, s] : slots) {
    if (!s.tensor) continue;
    if (s.role == Slot::Role::Extern) from_value(engine->global(*s.var), *s.tensor);
    if (s.role == Slot::Role::Result) from_value(results.at(s.index), *s.tensor);
  }
}

DenseResult Function::result(const std::string& name) const {
  Impl& im = impl();
  const Slot& s = im.slot(name);
  if (s.role != Slot::Role::Result)
    throw Error("'" + name + "' is not a result of '" + im.func->name + "'");
  if (im.results.empty()) throw Error("'" + im.func->name + "' has not run yet");
  const Value& v = im.results.at(s.index);
  if (v.kind() == Value::Kind::Matrix)
    throw Error("result '" + name + "' is a system matrix; read it with matrix()");
  if (!v.is_scalar() && !v.is_tensor()) throw Error("result '" + name + "' is not a tensor");
  return DenseResult(std::make_shared<const runtime::Tensor>(v.to_tensor()));
}

RunStats Function::stats() const { return impl().stats; }
void Function::reset_stats() { impl().stats = RunStats{}; }

const ExecutorChoice& Function::executor() const {
  const Impl& im = impl();
  return im.engine ? im.engine->options().executor : im.options.executor;
}

SystemMatrixView Function::matrix(const std::string& name) const {
  Impl& im = impl();
  const Slot& s = im.slot(name);
  if (s.role != Slot::Role::Result)
    throw Error("'" + name + "' is not a result of '" + im.func->name + "'");
  if (im.results.empty()) throw Error("'" + im.func->name + "' has not run yet");
  const Value& v = im.results.at(s.index);
  if (v.kind() != Value::Kind::Matrix || !v.matrix())
    throw Error("result '" + name + "' is not a system matrix");
  return SystemMatrixView(v.matrix());
}

}  // namespace simit
