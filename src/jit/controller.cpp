// The trace controller (jit/controller.h): hot counting, keys, the kernel cache, calls.
#include "jit/controller.h"

#include <chrono>
#include <cstdio>
#include <ctime>
#include <sstream>

#include "interp/interpreter.h"
#include "interp/runtime_error.h"
#include "jit/pruned_matrix.h"

namespace simit::jit {

namespace ast = frontend::ast;
using interp::Value;

struct TraceController::Entry {
  TracedSite traced;
  std::unique_ptr<Kernel> kernel;
  TraceStats stats;
};

struct TraceController::SiteState {
  int failures = 0;
  std::string gave_up;  // set once the site stays interpreted for good
  std::map<std::string, std::unique_ptr<Entry>> kernels;
  std::string site;
};

struct TraceController::LoopEntry {
  TracedSystem traced;
  std::unique_ptr<Kernel> kernel;
  // Per matrix the loop multiplies (by the variable): its non-zero blocks, rebuilt per call.
  std::map<const ast::Variable*, PrunedMatrix> pruned;
  int64_t kept = 0, total = 0;  // blocks streamed and blocks in the patterns, over all calls
  double prune_cpu_ms = 0.0;
  std::vector<int64_t> sizes;       // the lengths it was traced for
  std::vector<bool> writes_scalar;  // per scalar local
  TraceStats stats;
};

struct TraceController::LoopState {
  long runs = 0;
  int failures = 0;
  std::string gave_up;
  std::vector<std::unique_ptr<LoopEntry>> entries;
};

namespace {

double thread_cpu_ms() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return 1e3 * static_cast<double>(t.tv_sec) + 1e-6 * static_cast<double>(t.tv_nsec);
}

// The lengths a system trace's sizes name, as the interpreter's values hold them now (-1
// where a value is missing or of another kind).
std::vector<int64_t> current_sizes(const SystemBinding& b, interp::Interpreter& in) {
  std::vector<int64_t> out;
  for (const SystemBinding::Size& s : b.sizes) {
    const Value& v = in.variable(*s.var);
    if (s.rows)
      out.push_back(v.kind() == Value::Kind::Matrix && v.matrix() ? v.matrix()->rows() : -1);
    else
      out.push_back(v.is_tensor() ? static_cast<int64_t>(v.tensor().size()) : -1);
  }
  return out;
}

// What a kernel is specialised for: the target's identity and topology, the patterns of the
// matrix results, the shapes of the partial arguments, the storage of the fields and the
// arithmetic modes. Values (a partial argument's number, an extern) are read at each call.
std::string key_of(const interp::SiteCall& call, const JitOptions& o) {
  std::ostringstream k;
  const runtime::Set& t = call.target;
  k << "set " << t.name() << "#" << t.id() << " v" << t.topology_version() << " arity "
    << t.arity();
  for (int m = 0; m <= t.arity(); ++m) {
    const runtime::Set& s = runtime::member_set(t, m);
    k << " [" << s.id();
    for (int f = 0; f < s.field_count(); ++f) k << (s.field(f).type().single ? "s" : "d");
    k << "]";
  }
  for (const auto& r : call.plan.results) k << " r" << (r.pattern ? r.pattern.get() : nullptr);
  for (const Value& v : call.partial_args)
    k << " a" << static_cast<int>(v.kind()) << ":" << v.shape().str();
  if (call.plan.reduce) k << " reduce";
  if (o.float32) k << " float32";
  return k.str();
}

double component(const Value& v, int i) {
  switch (v.kind()) {
    case Value::Kind::Float: return v.as_float();
    case Value::Kind::Int: return v.as_int();
    case Value::Kind::Bool: return v.as_bool() ? 1.0 : 0.0;
    case Value::Kind::Tensor: {
      const runtime::Tensor& t = v.tensor();
      switch (t.kind()) {
        case runtime::ComponentKind::Float: return t.floats()[i];
        case runtime::ComponentKind::Int: return t.ints()[i];
        case runtime::ComponentKind::Bool: return t.bools()[i] ? 1.0 : 0.0;
        default: return 0.0;
      }
    }
    default: return 0.0;
  }
}

void zero_results(interp::SiteCall& call) {
  for (Value& r : call.results) {
    if (r.kind() == Value::Kind::Matrix && r.matrix()) r.matrix()->set_zero();
    if (r.is_tensor()) {
      runtime::Tensor& t = r.tensor();
      if (t.kind() == runtime::ComponentKind::Float) t.fill(0, t.size(), 0.0);
    }
  }
}

}  // namespace

TraceController::TraceController(JitOptions options) : options_(options) {
  backend_ = make_cpu_backend(backend_error_);
}

TraceController::~TraceController() = default;

TraceController::Entry* TraceController::entry_for(interp::SiteCall& call) {
  auto& slot = sites_[call.plan.site];
  if (!slot) {
    slot = std::make_unique<SiteState>();
    slot->site = call.plan.func->name;
    if (call.at.valid()) slot->site += " (line " + std::to_string(call.at.start().line) + ")";
  }
  SiteState& s = *slot;
  const std::string key = key_of(call, options_);
  if (auto it = s.kernels.find(key); it != s.kernels.end()) return it->second.get();
  if (!s.gave_up.empty()) return nullptr;
  auto e = std::make_unique<Entry>();
  e->stats.site = s.site;
  e->stats.key = key;
  auto give_up = [&](std::string why) {
    e->stats.status = std::move(why);
    if (++s.failures >= kMaxFailures) s.gave_up = e->stats.status;
  };
  if (!backend_) {
    give_up("no code generator: " + backend_error_);
  } else if (options_.check_finite) {
    give_up("interpreted: --check-finite pinpoints the statement in the interpreter");
  } else {
    SiteShape shape;
    shape.site = call.plan.site;
    shape.target = &call.target;
    shape.reduce = call.plan.reduce;
    shape.float32 = options_.float32;
    for (const auto& r : call.plan.results)
      shape.patterns.push_back(r.is_matrix ? r.pattern.get() : nullptr);
    shape.partial_args = &call.partial_args;
    const interp::Interpreter& in = call.interpreter;
    shape.global = [&in](const ast::Variable& v) -> const Value* { return &in.global(v); };
    e->traced = trace_site(shape);
    if (!e->traced.trace) {
      // The trace depends on the site, not on the key: no retries.
      e->stats.status = "interpreted: " + e->traced.reason;
      s.failures = kMaxFailures;
      s.gave_up = e->stats.status;
    } else if (std::string bad = verify(*e->traced.trace); !bad.empty()) {
      give_up("interpreted: loop IR failed verification: " + bad);
    } else {
      const Trace& t = *e->traced.trace;
      e->stats.ir_nodes = node_count(t);
      std::string error;
      e->kernel = backend_->compile(t, options_.dump_llvm, error);
      if (!e->kernel) {
        give_up("interpreted: " + error);
      } else {
        e->stats.status = "compiled";
        e->stats.compile_ms = e->kernel->compile_ms;
        if (options_.dump && options_.dump_loop_ir) print(*options_.dump, t);
        if (options_.dump && options_.dump_llvm) *options_.dump << e->kernel->llvm_ir;
      }
    }
  }
  Entry* out = e.get();
  s.kernels[key] = std::move(e);
  return out;
}

bool TraceController::run_site(interp::SiteCall& call) {
  if (call.plan.runs <= options_.threshold) return false;
  Entry* e = entry_for(call);
  if (!e || !e->kernel) return false;
  const auto start = std::chrono::steady_clock::now();
  const double cpu = thread_cpu_ms();
  const bool done = run_kernel(*e, call);
  e->stats.cpu_ms += thread_cpu_ms() - cpu;
  e->stats.run_ms +=
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  ++e->stats.calls;
  return done;
}

bool TraceController::run_kernel(Entry& e, interp::SiteCall& call) {
  const Trace& t = *e.traced.trace;
  std::vector<void*> arrays(t.arrays.size(), nullptr);
  // Writable arrays first: taking one for writing may copy it (copy-on-write), and the
  // pointers read afterwards then see the copy.
  for (int pass = 0; pass < 2; ++pass)
    for (size_t i = 0; i < t.arrays.size(); ++i) {
      const ArraySlot& a = t.arrays[i];
      if (a.written != (pass == 0)) continue;
      switch (a.kind) {
        case ArraySlot::Kind::Field: {
          auto& set = const_cast<runtime::Set&>(runtime::member_set(call.target, a.member));
          runtime::Field& f = set.field(a.index);
          arrays[i] = a.written ? static_cast<void*>(f.bytes())
                                : const_cast<std::byte*>(std::as_const(f).bytes());
          break;
        }
        case ArraySlot::Kind::Vector:
          arrays[i] = const_cast<double*>(call.partial_args[a.index].tensor().floats());
          break;
        case ArraySlot::Kind::Result: {
          Value& r = call.results[a.index];
          if (r.kind() == Value::Kind::Matrix)
            arrays[i] = r.matrix()->values();
          else if (r.is_tensor())
            arrays[i] = r.tensor().mutable_floats();
          else
            return false;
          break;
        }
        case ArraySlot::Kind::Table:
          arrays[i] =
              const_cast<int32_t*>(call.plan.results[a.index].pattern->assembly().table.data());
          break;
      }
    }
  std::vector<double> scalars;
  for (const ScalarSource& s : e.traced.scalar_sources)
    scalars.push_back(component(
        s.partial >= 0 ? call.partial_args[s.partial] : call.interpreter.global(*s.global),
        s.component));
  const int32_t* endpoints = call.target.endpoints();
  const int n = call.target.size();
  interp::Trap& trap = call.interpreter.trap();
  for (int begin = 0; begin < n; begin += kChunkElements) {
    const int end = std::min(n, begin + kChunkElements);
    int32_t failed = -1;
    const int32_t rc = e.kernel->fn(arrays.data(), scalars.data(), endpoints, begin, end, &failed);
    if (rc != 0) {
      const ErrorSite& err = t.errors[static_cast<size_t>(rc - 1)];
      if (!t.writes_fields) {
        // Nothing but the results changed: the interpreter runs the site again from zero
        // and reports the error in its own words, with its call stack.
        zero_results(call);
        return false;
      }
      throw interp::RuntimeError(err.span, err.message + " (element " + std::to_string(failed) +
                                               " of " + call.target.describe() + ")");
    }
    if (end < n && trap.interrupt_pending()) {
      trap.take_interrupt();
      throw interp::Interrupted(call.at, "interrupted");
    }
  }
  return true;
}

TraceController::LoopEntry* TraceController::loop_entry_for(const ast::While& loop,
                                                            interp::Interpreter& in) {
  auto& slot = loops_[&loop];
  if (!slot) slot = std::make_unique<LoopState>();
  LoopState& s = *slot;
  for (auto& e : s.entries)
    if (e->kernel && current_sizes(e->traced.binding, in) == e->sizes) return e.get();
  if (!s.gave_up.empty()) return nullptr;
  auto e = std::make_unique<LoopEntry>();
  e->stats.site = "while (line " + std::to_string(loop.span.start().line) + ")";
  auto fail = [&](std::string why, bool final) {
    e->stats.status = "interpreted: " + std::move(why);
    if (final || ++s.failures >= kMaxFailures) s.gave_up = e->stats.status;
  };
  if (!backend_) {
    fail("no code generator: " + backend_error_, true);
  } else if (options_.check_finite || options_.float32) {
    fail(options_.check_finite ? "--check-finite runs system statements in the interpreter"
                               : "float32 runs system statements in the interpreter",
         true);
  } else {
    e->traced = trace_system(loop, in);
    if (!e->traced.trace) {
      fail(e->traced.reason, true);
    } else {
      SystemTrace& t = *e->traced.trace;
      const int removed = fuse_passes(t);
      e->sizes = current_sizes(e->traced.binding, in);
      std::ostringstream key;
      for (size_t i = 0; i < t.sizes.size(); ++i) key << (i ? ", " : "") << t.sizes[i];
      key << "; " << removed << " loops fused away";
      e->stats.key = key.str();
      e->writes_scalar.assign(static_cast<size_t>(t.scalars), false);
      for (const VectorOp& op : t.body)
        for (const Stmt& st : op.body)
          if (st.kind == StmtKind::SetLocal && st.slot < t.scalars)
            e->writes_scalar[st.slot] = true;
      std::string error;
      e->kernel = backend_->compile(t, options_.dump_llvm, error);
      if (!e->kernel) {
        fail(error, false);
      } else {
        e->stats.status = "compiled";
        e->stats.compile_ms = e->kernel->compile_ms;
        if (options_.dump && options_.dump_loop_ir) print(*options_.dump, t);
        if (options_.dump && options_.dump_llvm) *options_.dump << e->kernel->llvm_ir;
      }
    }
  }
  LoopEntry* out = e.get();
  s.entries.push_back(std::move(e));
  return out && out->kernel ? out : nullptr;
}

bool TraceController::run_statement(const ast::Stmt& stmt, interp::Interpreter& in) {
  const auto* loop = stmt.as<ast::While>();
  if (!loop) return false;
  auto& state = loops_[loop];
  if (!state) state = std::make_unique<LoopState>();
  if (++state->runs <= options_.threshold) return false;
  LoopEntry* e = loop_entry_for(*loop, in);
  if (!e) return false;
  const auto start = std::chrono::steady_clock::now();
  const double cpu = thread_cpu_ms();
  const SystemBinding& b = e->traced.binding;
  const SystemTrace& t = *e->traced.trace;
  for (const auto& [var, like] : b.created)
    if (in.variable(*var).empty()) {
      const runtime::Tensor& shape = in.variable(*like).tensor();
      in.variable(*var) = Value::of_tensor(runtime::Tensor(shape.kind(), shape.shape()));
    }
  std::vector<void*> arrays(b.arrays.size(), nullptr);
  for (int pass = 0; pass < 2; ++pass)
    for (size_t i = 0; i < b.arrays.size(); ++i) {
      if (t.arrays[i].written != (pass == 0)) continue;
      Value& v = in.variable(*b.arrays[i].var);
      using Part = SystemBinding::Array::Part;
      switch (b.arrays[i].part) {
        case Part::Vector:
          arrays[i] = t.arrays[i].written ? static_cast<void*>(v.tensor().mutable_floats())
                                          : const_cast<double*>(v.tensor().floats());
          break;
        case Part::RowPtr: {
          // The matrix is constant while the loop runs: its zero blocks are dropped once.
          const double before = thread_cpu_ms();
          PrunedMatrix& p = e->pruned[b.arrays[i].var];
          p.assign(*v.matrix());
          e->kept += p.kept;
          e->total += p.total;
          e->prune_cpu_ms += thread_cpu_ms() - before;
          arrays[i] = p.row_ptr.data();
          break;
        }
        case Part::Cols: arrays[i] = e->pruned[b.arrays[i].var].cols.data(); break;
        case Part::Values: arrays[i] = e->pruned[b.arrays[i].var].values.data(); break;
      }
    }
  std::vector<double> scalars(b.scalars.size(), 0.0);
  for (size_t i = 0; i < b.scalars.size(); ++i) {
    const Value& v = in.variable(*b.scalars[i]);
    if (!v.empty()) scalars[i] = component(v, 0);
  }
  e->kernel->system(arrays.data(), scalars.data(), e->sizes.data());
  for (size_t i = 0; i < b.scalars.size(); ++i) {
    if (!e->writes_scalar[i]) continue;
    switch (b.scalar_types[i]) {
      case Ty::F64: in.variable(*b.scalars[i]) = Value::of_float(scalars[i]); break;
      case Ty::I32:
        in.variable(*b.scalars[i]) = Value::of_int(static_cast<int32_t>(scalars[i]));
        break;
      case Ty::Bool: in.variable(*b.scalars[i]) = Value::of_bool(scalars[i] != 0.0); break;
    }
  }
  e->stats.cpu_ms += thread_cpu_ms() - cpu;
  e->stats.run_ms +=
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  ++e->stats.calls;
  if (e->total > 0) {
    char note[160];
    std::snprintf(note, sizeof note, "; products stream %.1f%% of the blocks (zero blocks dropped in %.2f cpu ms)",
                  100.0 * static_cast<double>(e->kept) / static_cast<double>(e->total), e->prune_cpu_ms);
    e->stats.note = note;
  }
  return true;
}

std::vector<TraceStats> TraceController::stats() const {
  std::vector<TraceStats> out;
  for (const auto& [site, s] : sites_)
    for (const auto& [key, e] : s->kernels) out.push_back(e->stats);
  for (const auto& [loop, s] : loops_)
    for (const auto& e : s->entries) out.push_back(e->stats);
  return out;
}

void TraceController::print_stats(std::ostream& os) const {
  os << "jit traces:\n";
  char line[256];
  std::snprintf(line, sizeof line, "  %-28s %10s %8s %10s %10s %8s  %s\n", "site", "compile ms",
                "calls", "run ms", "cpu ms", "ir nodes", "status");
  os << line;
  for (const TraceStats& s : stats()) {
    std::snprintf(line, sizeof line, "  %-28s %10.1f %8ld %10.2f %10.2f %8zu  ", s.site.c_str(),
                  s.compile_ms, s.calls, s.run_ms, s.cpu_ms, s.ir_nodes);
    os << line << s.status << "\n      key: " << s.key << s.note << "\n";
  }
}

}  // namespace simit::jit
