// The trace controller (jit/controller.h): hot counting, keys, the kernel cache, calls.
#include "jit/controller.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <functional>
#include <sstream>

#include "interp/interpreter.h"
#include "interp/runtime_error.h"
#include "interp/set_binding.h"
#include "jit/decompose_call.h"
#include "jit/matrix_sum.h"
#include "jit/pruned_matrix.h"
#include "jit/specialise.h"
#include "jit/write_guard.h"
#include "runtime/system_ops.h"

namespace simit::jit {

namespace ast = frontend::ast;
using interp::Value;

struct TraceController::Entry {
  TracedSite traced;
  std::unique_ptr<Kernel> kernel;
  MapWrites writes = MapWrites::Shared;
  TraceStats stats;
  // Per result: its specialised pattern (jit/specialise.h), the last matrix made on it
  // (reused, zeroed, when the program has dropped it), the pattern the guard dropped (reused
  // when the blocks recorded again are the same), and while a call records its blocks, a
  // byte per block of the full pattern. `off`: full patterns for good.
  struct Special {
    std::optional<SpecialisedPattern> pattern, dropped;
    std::shared_ptr<runtime::SystemMatrix> last;
    std::vector<uint8_t> marks;
    bool off = false;
  };
  std::vector<Special> special;
  // What decides the blocks written (computed on first use), and their state when the
  // blocks were recorded (jit/write_guard.h).
  std::optional<WriteDeciders> deciders;
  WriteGuard guard;
  int64_t guard_calls = 0, guard_failures = 0;
  double guard_ms = 0.0;
  bool failed_last = false;  // the guard failed on the previous call
  std::string full_why;      // why the results stay on full patterns, for --jit-stats
  std::vector<std::vector<int32_t>> positions;  // per Positions array slot, this call's
};

struct TraceController::SiteState {
  int failures = 0;
  std::string gave_up;  // set once the site stays interpreted for good
  std::map<std::string, std::unique_ptr<Entry>> kernels;
  std::string site;
};

struct TraceController::LoopEntry {
  std::vector<const ast::Stmt*> run;  // the statements it runs (a while loop alone, or a run)
  TracedSystem traced;
  std::unique_ptr<Kernel> kernel;
  // Per matrix the loop multiplies (by the variable): its non-zero blocks, rebuilt per call.
  std::map<const ast::Variable*, PrunedMatrix> pruned;
  int64_t kept = 0, total = 0;  // blocks streamed and blocks in the patterns, over all calls
  double prune_cpu_ms = 0.0;
  std::vector<int64_t> sizes;                // the lengths it was traced for
  std::vector<bool> writes_scalar;           // per scalar local
  long handed_back = 0;                      // calls that reached an error statement
  std::vector<std::vector<double>> scratch;  // per array slot: a scratch vector's storage
  TraceStats stats;
};

struct TraceController::LoopState {
  size_t length = 0;  // a run: how many of its statements are traced (a prefix, after a failure)
  long runs = 0;
  int failures = 0;
  std::string gave_up;
  std::vector<std::unique_ptr<LoopEntry>> entries;
};

struct TraceController::Pending {
  const void* at = nullptr;  // the site or statement
  std::string name;          // the trace's site
  // Site: per result its values, per written field (array slot) its bytes, as compiled.
  std::vector<std::vector<double>> results;
  // Per result: a matrix the kernel assembled on its specialised pattern (else empty), which
  // replaces the interpreter's once they agree, so that what follows runs on what a
  // compiled run would give it (a direct solve reads the pattern).
  std::vector<Value> specialised;
  std::vector<std::pair<int, std::vector<std::byte>>> fields;
  const Trace* trace = nullptr;
  // Loop: per written variable its value as compiled; per written field ("S.f") its values.
  std::vector<std::pair<const ast::Variable*, Value>> variables;
  struct RunField {
    const runtime::Field* field;
    std::string name;
    std::vector<double> values;
  };
  std::vector<RunField> run_fields;
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
    if (s.field >= 0) {
      const bool bound = v.kind() == Value::Kind::Set && v.binding() && v.binding()->set;
      out.push_back(bound ? static_cast<int64_t>(v.binding()->set->size()) *
                                std::as_const(*v.binding()->set)
                                    .field(v.binding()->fields[s.field])
                                    .components()
                          : -1);
    } else if (s.rows)
      out.push_back(v.kind() == Value::Kind::Matrix && v.matrix() ? v.matrix()->rows() : -1);
    else
      out.push_back(v.is_tensor() ? static_cast<int64_t>(v.tensor().size()) : -1);
  }
  // A kernel reads each field in the storage it was traced for (binary32 or binary64).
  for (const SystemBinding::Array& a : b.arrays) {
    if (a.part != SystemBinding::Array::Part::Field) continue;
    const Value& v = in.variable(*a.var);
    const bool bound = v.kind() == Value::Kind::Set && v.binding() && v.binding()->set;
    out.push_back(
        bound ? std::as_const(*v.binding()->set).field(v.binding()->fields[a.field]).type().single
              : -1);
  }
  return out;
}

// Marks the program scalars (locals below `scalars`) a block sets, in branches too.
void note_scalar_writes(const std::vector<Stmt>& body, int scalars, std::vector<bool>& writes) {
  for (const Stmt& st : body) {
    if (st.kind == StmtKind::SetLocal && st.slot < scalars) writes[st.slot] = true;
    note_scalar_writes(st.body, scalars, writes);
    note_scalar_writes(st.orelse, scalars, writes);
  }
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

// "mapping over element 5 of set 'tets' (endpoints 3, 9, 12, 40 of 'verts')", as the
// interpreter writes it.
std::string element_note(const interp::SiteCall& call, int element) {
  const runtime::Set& t = call.target;
  const ast::Variable* target = call.plan.site->target_set;
  std::string note = "mapping over element " + std::to_string(element) + " of set '" +
                     (target ? target->name : t.name()) + "'";
  if (element < 0 || element >= t.size() || t.arity() == 0) return note;
  std::string list;
  for (int k = 0; k < t.arity(); ++k)
    list += (k ? ", " : "") + std::to_string(t.endpoint(element, k));
  const bool one_set = t.homogeneous();
  return note + " (endpoints " + list + (one_set ? " of '" + t.endpoint_set(0).name() + "'" : "") +
         ")";
}

// Where each block a trace reads from a global matrix argument lies in its pattern, per
// element (-1 outside it). False where the interpreter must read it: a pattern that repeats
// blocks (they are summed) or a member outside the matrix's rows or columns (an error).
bool find_positions(const ArraySlot& a, const interp::SiteCall& call, std::vector<int32_t>& out) {
  const Value& v = call.partial_args[a.index];
  if (v.kind() != Value::Kind::Matrix || !v.matrix()) return false;
  const runtime::MatrixPattern& p = v.matrix()->pattern();
  if (!p.canonical()) return false;
  const runtime::Set& t = call.target;
  out.resize(static_cast<size_t>(t.size()) * a.reads.size());
  size_t k = 0;
  for (int e = 0; e < t.size(); ++e)
    for (const auto& [rm, cm] : a.reads) {
      const int32_t row = runtime::member_element(t, e, rm),
                    col = runtime::member_element(t, e, cm);
      if (row < 0 || row >= p.rows() || col < 0 || col >= p.cols()) return false;
      out[k++] = p.find(row, col);
    }
  return true;
}

void zero_results(interp::SiteCall& call) {
  for (Value& r : call.results) {
    if (r.kind() == Value::Kind::Matrix && r.matrix()) r.matrix()->set_zero();  // null: made later
    if (r.is_tensor()) {
      runtime::Tensor& t = r.tensor();
      if (t.kind() == runtime::ComponentKind::Float) t.fill(0, t.size(), 0.0);
    }
  }
}

}  // namespace

TraceController::TraceController(JitOptions options) : options_(options) {
  HostCalls host;
  host.decompose = reinterpret_cast<void*>(&simit_jit_decompose);
  target_ = make_cpu_target(host, options_.cache_dir, target_error_);
  executor_ = options_.shuffle_seed ? make_shuffled_executor(options_.shuffle_seed)
                                    : make_serial_executor();
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
  e->stats.line = call.at.valid() ? static_cast<int>(call.at.start().line) : 0;
  e->stats.key = key;
  auto give_up = [&](std::string why) {
    e->stats.status = std::move(why);
    if (++s.failures >= kMaxFailures) s.gave_up = e->stats.status;
  };
  if (!target_) {
    give_up("no code generator: " + target_error_);
  } else {
    SiteShape shape;
    shape.site = call.plan.site;
    shape.target = &call.target;
    shape.reduce = call.plan.reduce;
    shape.float32 = options_.float32;
    shape.check_finite = options_.check_finite;
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
      e->kernel = target_->compile(t, options_.dump_llvm, error);
      if (!e->kernel) {
        give_up("interpreted: " + error);
      } else {
        e->stats.status = "compiled";
        e->writes = writes_of(t);
        if (e->kernel->lanes > 1)
          e->stats.note = "; " + std::to_string(e->kernel->lanes) + " elements at once";
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
  if (options_.check) return check_site(*e, call);
  const auto start = std::chrono::steady_clock::now();
  const double cpu = thread_cpu_ms();
  const bool done = run_kernel(*e, call);
  e->stats.cpu_ms += thread_cpu_ms() - cpu;
  e->stats.run_ms +=
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  ++e->stats.calls;
  return done;
}

// The matrix results: on the specialised pattern where there is one, otherwise on the full
// one (made here when the interpreter left it to the hook). Returns the tables to use.
std::vector<const int32_t*> TraceController::prepare_results(Entry& e, interp::SiteCall& call) {
  e.special.resize(call.results.size());
  std::vector<const int32_t*> tables(call.results.size(), nullptr);
  for (size_t i = 0; i < call.results.size(); ++i) {
    interp::AssemblyPlan::Result& r = call.plan.results[i];
    if (!r.is_matrix || !r.pattern) continue;
    Entry::Special& s = e.special[i];
    const runtime::BlockDims bd = runtime::block_dims(r.block);
    const bool special = s.pattern && s.pattern->full == r.pattern;
    const runtime::PatternPtr& pattern = special ? s.pattern->pattern : r.pattern;
    if (special || !call.results[i].matrix()) {
      if (s.last && s.last.use_count() == 1 && s.last->shared_pattern() == pattern) {
        s.last->set_zero();
      } else {
        s.last = std::make_shared<runtime::SystemMatrix>(pattern, bd.rows, bd.cols,
                                                         runtime::ComponentKind::Float);
      }
      call.results[i] = Value::of_matrix(s.last);
    }
    tables[i] = special ? s.pattern->table.data() : r.pattern->assembly().table.data();
  }
  return tables;
}

// Before a call: the guard of the specialised results (drops them when the inputs that
// decide the writes changed), and the results whose blocks this call records.
void TraceController::guard_results(Entry& e, interp::SiteCall& call,
                                    const std::vector<double>& scalars) {
  const Trace& t = *e.traced.trace;
  if (t.writes_fields || options_.float32) return;
  if (!e.deciders) {
    e.deciders = write_deciders(t);
    if (!e.deciders->unguardable.empty()) e.full_why = e.deciders->unguardable;
    // Endpoints of one set read the same field through slots of their own: compare it once.
    std::vector<int> fields;
    std::vector<const runtime::Field*> seen;
    for (int slot : e.deciders->fields) {
      const ArraySlot& a = t.arrays[static_cast<size_t>(slot)];
      const runtime::Field* f = &runtime::member_set(call.target, a.member).field(a.index);
      if (std::find(seen.begin(), seen.end(), f) != seen.end()) continue;
      seen.push_back(f);
      fields.push_back(slot);
    }
    e.deciders->fields = std::move(fields);
  }
  if (!e.deciders->unguardable.empty()) return;
  e.special.resize(call.results.size());
  bool specialised = false;
  for (const Entry::Special& s : e.special) specialised = specialised || s.pattern;
  if (specialised) {
    const auto start = std::chrono::steady_clock::now();
    const bool holds = e.guard.holds(*e.deciders, t, call.target, scalars);
    e.guard_ms +=
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    ++e.guard_calls;
    if (!holds) drop_specialised(e, call);
    e.failed_last = !holds;
  }
  bool record = false;
  for (size_t i = 0; i < call.results.size(); ++i) {
    const interp::AssemblyPlan::Result& r = call.plan.results[i];
    Entry::Special& s = e.special[i];
    if (!r.is_matrix || !r.pattern || s.off || !r.pattern->has_assembly_index() ||
        (s.pattern && s.pattern->full == r.pattern))
      continue;
    s.marks.assign(static_cast<size_t>(r.pattern->nnz()), 0);
    record = true;
  }
  if (record) e.guard.record(*e.deciders, t, call.target, scalars);
}

// The guard failed: this call and the next assemble on the full patterns, and record their
// blocks; failing on two calls in a row means the deciding inputs change with every call,
// and the results stay on full patterns.
void TraceController::drop_specialised(Entry& e, interp::SiteCall& call) {
  ++e.guard_failures;
  for (size_t i = 0; i < e.special.size(); ++i) {
    Entry::Special& s = e.special[i];
    if (!s.pattern) continue;
    s.dropped = std::move(s.pattern);
    s.pattern.reset();
    s.last.reset();
    s.off = e.failed_last;
    call.plan.results[i].hook_allocates = false;
  }
  if (e.failed_last) e.full_why = "the inputs that decide the writes changed on two calls in a row";
}

// After a call that recorded its blocks: specialise each result whose unwritten blocks are
// worth leaving out.
void TraceController::specialise_results(Entry& e, interp::SiteCall& call) {
  for (size_t i = 0; i < e.special.size(); ++i) {
    Entry::Special& s = e.special[i];
    if (s.marks.empty()) continue;
    interp::AssemblyPlan::Result& r = call.plan.results[i];
    std::optional<SpecialisedPattern> p =
        specialise(r.pattern, s.marks, kSpecialiseAtMost,
                   fused_sums(call.interpreter).keep_diagonal.count(call.plan.site) > 0);
    s.marks.clear();
    if (!p) {
      s.off = true;  // nearly every block is written: nothing to gain
      if (e.full_why.empty()) e.full_why = "nearly every block is written";
      continue;
    }
    // The same blocks as before the guard failed: the same pattern, so that what was derived
    // from it (sums over the union, the solver's copies) stays valid.
    if (s.dropped && same_blocks(*s.dropped, *p)) p = std::move(s.dropped);
    s.dropped.reset();
    s.pattern = std::move(p);
    r.hook_allocates = true;
    r.last.reset();  // the full matrix lives on only while the program holds this call's result
  }
}

bool TraceController::run_kernel(Entry& e, interp::SiteCall& call) {
  const Trace& t = *e.traced.trace;
  std::vector<double> scalars;
  for (const ScalarSource& s : e.traced.scalar_sources)
    scalars.push_back(component(
        s.partial >= 0 ? call.partial_args[s.partial] : call.interpreter.global(*s.global),
        s.component));
  guard_results(e, call, scalars);
  const std::vector<const int32_t*> tables = prepare_results(e, call);
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
        case ArraySlot::Kind::Table: arrays[i] = const_cast<int32_t*>(tables[a.index]); break;
        case ArraySlot::Kind::Marks: {
          const size_t r = static_cast<size_t>(a.index);
          arrays[i] = r < e.special.size() && !e.special[r].marks.empty()
                          ? e.special[r].marks.data()
                          : nullptr;
          break;
        }
        case ArraySlot::Kind::Matrix: {
          const Value& m = call.partial_args[a.index];
          if (m.kind() != Value::Kind::Matrix || !m.matrix()) return false;
          arrays[i] = const_cast<double*>(m.matrix()->values());
          break;
        }
        case ArraySlot::Kind::Positions:
          e.positions.resize(t.arrays.size());
          if (!find_positions(a, call, e.positions[i])) return false;
          arrays[i] = e.positions[i].data();
          break;
      }
    }
  const MapArgs args{arrays.data(), scalars.data(), call.target.endpoints()};
  interp::Trap& trap = call.interpreter.trap();
  const MapOutcome out =
      executor_->run_map(*e.kernel, args, call.target.size(), kChunkElements, e.writes,
                         [&trap] { return trap.interrupt_pending(); });
  if (out.code != 0) {
    const ErrorSite& err = t.errors[static_cast<size_t>(out.code - 1)];
    for (Entry::Special& s : e.special) s.marks.clear();  // this call records nothing
    if (!t.writes_fields) {
      // Nothing but the results changed: the interpreter runs the site again from zero
      // and reports the error in its own words, with its call stack (on full patterns).
      for (size_t i = 0; i < call.results.size(); ++i)
        if (call.plan.results[i].is_matrix && call.results[i].matrix() &&
            call.results[i].matrix()->shared_pattern() != call.plan.results[i].pattern)
          call.results[i] = Value::of_matrix(nullptr);
      zero_results(call);
      return false;
    }
    // Located as the interpreter locates it: the mapped function's frame names the element.
    interp::RuntimeError error(err.span, err.message);
    for (const auto& [callee, at] : err.frames) error.add_frame(callee, at);
    error.add_frame(call.plan.func->name, call.at);
    error.note_element(call.plan.func->name, element_note(call, out.element));
    throw error;
  }
  if (out.interrupted) {
    trap.take_interrupt();
    throw interp::Interrupted(call.at, "interrupted");
  }
  specialise_results(e, call);
  return true;
}

// The kernel of a while loop alone or of a run of statements, for the lengths its variables
// have now: found, or traced and compiled. A run whose statement j > 1 cannot be traced is
// traced again without it and the statements after it (s.length shrinks).
TraceController::LoopEntry* TraceController::system_entry_for(LoopState& s,
                                                              std::vector<const ast::Stmt*> run,
                                                              interp::Interpreter& in) {
  for (auto& e : s.entries)
    if (e->kernel && current_sizes(e->traced.binding, in) == e->sizes) return e.get();
  if (!s.gave_up.empty()) return nullptr;
  auto e = std::make_unique<LoopEntry>();
  auto fail = [&](std::string why, bool final) {
    e->stats.status = "interpreted: " + std::move(why);
    if (final || ++s.failures >= kMaxFailures) s.gave_up = e->stats.status;
  };
  if (!target_) {
    fail("no code generator: " + target_error_, true);
  } else if (options_.check_finite) {
    fail("--check-finite runs system statements in the interpreter", true);
  } else {
    e->traced = trace_system(run, in, options_.float32);
    // A prefix ends with a system-level statement, as runs do (--check-jit compares after
    // it), and has two statements or more.
    auto prefix = [&](size_t n) {
      while (n > 0 && !run[n - 1]->system_level) --n;
      return n;
    };
    while (!e->traced.trace && run.size() > 2 && prefix(e->traced.failed_at) >= 2) {
      run.resize(prefix(e->traced.failed_at));
      s.length = run.size();
      e->traced = trace_system(run, in, options_.float32);
    }
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
      for (const auto* ops : {&t.before, &t.body, &t.after})
        for (const VectorOp& op : *ops) note_scalar_writes(op.body, t.scalars, e->writes_scalar);
      std::string error;
      if (std::string bad = verify(t); !bad.empty()) {
        fail("loop IR failed verification: " + bad, true);
      } else if (e->kernel = target_->compile(t, options_.dump_llvm, error); !e->kernel) {
        fail(error, false);
      } else {
        e->stats.status = "compiled";
        e->stats.compile_ms = e->kernel->compile_ms;
        e->stats.ir_nodes = node_count(t);
        if (options_.dump && options_.dump_loop_ir) print(*options_.dump, t);
        if (options_.dump && options_.dump_llvm) *options_.dump << e->kernel->llvm_ir;
      }
    }
  }
  const ast::Stmt& first = *run.front();
  const std::string line = std::to_string(first.span.start().line);
  e->stats.site = run.size() > 1           ? "statements (lines " + run_lines(run) + ")"
                  : first.is<ast::While>() ? "while (line " + line + ")"
                                           : "statement (line " + line + ")";
  e->stats.line = static_cast<int>(first.span.start().line);
  e->run = std::move(run);
  LoopEntry* out = e.get();
  s.entries.push_back(std::move(e));
  return out && out->kernel ? out : nullptr;
}

bool TraceController::run_statement(const ast::Stmt& stmt, interp::Interpreter& in) {
  if (const auto sum = fused_sums(in).at.find(&stmt); sum != fused_sums(in).at.end())
    return run_fused_sum(stmt, sum->second, in);
  const auto* loop = stmt.as<ast::While>();
  if (!loop) return run_alone(stmt, in);
  auto& state = loops_[loop];
  if (!state) {
    state = std::make_unique<LoopState>();
    note_loop(*loop);
  }
  if (checking_run_) return false;
  if (++state->runs <= options_.threshold) return false;
  LoopEntry* e = system_entry_for(*state, {loop}, in);
  if (!e) return false;
  if (options_.check) {
    check_system(*e, in);
    return false;
  }
  return run_loop_kernel(*e, in);
}

bool TraceController::in_loop_to_compile(const ast::Block& block) const {
  const auto loop = loop_of_body_.find(&block);
  return loop != loop_of_body_.end() && may_compile(*loop->second);
}

bool TraceController::may_compile(const ast::While& loop) const {
  const auto state = loops_.find(&loop);
  return state == loops_.end() || state->second->gave_up.empty();
}

void TraceController::note_loop(const ast::While& loop) {
  loop_of_body_[&loop.body] = &loop;
  std::function<void(const ast::Block&)> walk = [&](const ast::Block& b) {
    for (const auto& s : b) {
      loop_of_stmt_.emplace(s.get(), &loop);
      if (const auto* i = s->as<ast::If>()) {
        for (const ast::Block& branch : i->branches) walk(branch);
        walk(i->else_branch);
      } else if (const auto* w = s->as<ast::While>()) {
        walk(w->body);
      }
    }
  };
  walk(loop.body);
}

// A system statement that is no part of a run (`verts.x = verts.x + h * verts.v`): a run of
// one, unless it lies in a loop that may itself still compile. One that does not compile is
// left out of the stats (the interpreter runs most system statements, matrix sums among them).
bool TraceController::run_alone(const ast::Stmt& stmt, interp::Interpreter& in) {
  if (!target_ || options_.check_finite || checking_run_) return false;
  if (auto loop = loop_of_stmt_.find(&stmt);
      loop != loop_of_stmt_.end() && may_compile(*loop->second))
    return false;
  auto& state = alone_[&stmt];
  if (!state) {
    state = std::make_unique<LoopState>();
    state->length = 1;
  }
  if (++state->runs <= options_.threshold) return false;
  LoopEntry* e = system_entry_for(*state, {&stmt}, in);
  if (!e) return false;
  if (options_.check) {
    check_system(*e, in);
    return false;
  }
  return run_loop_kernel(*e, in);
}

size_t TraceController::run_statements(const ast::Block& block, size_t first, size_t count,
                                       interp::Interpreter& in) {
  // Where no system statement compiles, the loops alone say why (a run would say it again
  // for each of its statements).
  if (!target_ || options_.check_finite) return 0;
  auto& state = runs_[block[first].get()];
  if (!state) {
    state = std::make_unique<LoopState>();
    // A matrix statement (a sum of matrices, a direct solve) is the interpreter's: the run
    // ends before it, and one that starts with it (length 0) is not offered (the interpreter
    // runs it and offers the statements after it).
    for (size_t i = first; i < first + count; ++i)
      if (matrix_statement(*block[i])) {
        count = i - first;
        break;
      }
    state->length = count;
    for (size_t i = first; i < first + count; ++i)
      if (const auto* loop = block[i]->as<ast::While>()) note_loop(*loop);
  }
  if (state->length == 0 || checking_run_ || in_loop_to_compile(block)) return 0;
  if (++state->runs <= options_.threshold) return 0;
  std::vector<const ast::Stmt*> run;
  for (size_t i = first; i < first + std::min(count, state->length); ++i)
    run.push_back(block[i].get());
  LoopEntry* e = system_entry_for(*state, std::move(run), in);
  if (!e) return 0;
  if (options_.check ? check_system(*e, in) : run_loop_kernel(*e, in))
    return options_.check ? 0 : e->run.size();
  // The kernel reached an error statement and put the variables back: the interpreter runs
  // the statements from the first and stops at the error, without offering them again (the
  // rest of the run, or its loop alone, would compile and stop at the same error).
  for (const ast::Stmt* s : e->run) in.exec_interpreted(*s);
  return e->run.size();
}

namespace {

using Saved = std::vector<std::pair<const ast::Variable*, Value>>;

// The field a Field array of a system trace names (its set is bound: the sizes matched).
runtime::Field& bound_field(const SystemBinding::Array& a, interp::Interpreter& in) {
  const interp::SetBinding& b = *in.variable(*a.var).binding();
  return b.set->field(b.fields[a.field]);
}

// The first n components of a float field as binary64 (binary32 storage widens exactly),
// and back (binary32 storage takes values that came from it, exactly).
std::vector<double> field_values(const runtime::Field& f, size_t n) {
  if (!f.type().single) return std::vector<double>(f.data<double>(), f.data<double>() + n);
  const float* v = f.data<float>();
  return std::vector<double>(v, v + n);
}
void set_field_values(runtime::Field& f, const std::vector<double>& values) {
  if (!f.type().single) {
    std::copy(values.begin(), values.end(), f.data<double>());
    return;
  }
  float* v = f.data<float>();
  for (size_t k = 0; k < values.size(); ++k) v[k] = static_cast<float>(values[k]);
}

// The variables a loop writes, as shared copies: a vector the kernel writes is copied by
// its first write (copy on write), so keeping the old value costs one copy of each written
// vector per call, and only for loops that may stop.
Saved save_loop_variables(const SystemBinding& b, const SystemTrace& t,
                          const std::vector<bool>& writes_scalar, interp::Interpreter& in) {
  Saved out;
  for (size_t i = 0; i < b.arrays.size(); ++i)
    if (t.arrays[i].written && b.arrays[i].var &&
        b.arrays[i].part != SystemBinding::Array::Part::Field)
      out.emplace_back(b.arrays[i].var, in.variable(*b.arrays[i].var));
  for (size_t i = 0; i < b.scalars.size(); ++i)
    if (writes_scalar[i]) out.emplace_back(b.scalars[i], in.variable(*b.scalars[i]));
  return out;
}

// The scalars a kernel stopped by an interrupt hands back: those the ops before the loop and
// its iterations write (the ops after it did not run; a scalar only they write keeps its value).
std::vector<bool> scalars_written_up_to_loop(const SystemTrace& t) {
  std::vector<bool> out(static_cast<size_t>(t.scalars), false);
  for (const auto* ops : {&t.before, &t.body})
    for (const VectorOp& op : *ops) note_scalar_writes(op.body, t.scalars, out);
  return out;
}

// Where the interpreter takes an interrupt that arrives between two iterations: before the
// first statement of the next one (the loop itself when its body is empty).
const ast::Stmt& interrupted_at(const std::vector<const ast::Stmt*>& run) {
  for (const ast::Stmt* s : run)
    if (const auto* loop = s->as<ast::While>())
      return loop->body.empty() ? *s : *loop->body.front();
  return *run.front();
}

}  // namespace

// Runs the loop's kernel on the interpreter's variables. A loop that reaches an error
// statement is put back as it was and left to the interpreter (false), which runs it from
// the start and stops with the error in its own words, at its line. A loop that an interrupt
// (Ctrl-C) stops between two iterations keeps what they wrote and throws interp::Interrupted.
bool TraceController::run_loop_kernel(LoopEntry& entry, interp::Interpreter& in) {
  LoopEntry* e = &entry;
  const auto start = std::chrono::steady_clock::now();
  const double cpu = thread_cpu_ms();
  const SystemBinding& b = e->traced.binding;
  const SystemTrace& t = *e->traced.trace;
  Saved saved;
  if (!t.errors.empty()) saved = save_loop_variables(b, t, e->writes_scalar, in);
  // A vector first assigned in the loop or run is made with the shape of its model: a value
  // left from an earlier run through the same statements may have another.
  for (const SystemBinding::Created& c : b.created) {
    runtime::Shape shape;
    if (c.like_field >= 0) {
      const interp::SetBinding& sb = *in.variable(*c.like).binding();
      shape =
          runtime::Shape::blocked(std::vector<int>{sb.set->size()}, sb.field_shapes[c.like_field]);
    } else {
      shape = in.variable(*c.like).tensor().shape();
    }
    const Value& now = in.variable(*c.var);
    if (now.empty() || !now.is_tensor() || now.tensor().size() != shape.size() ||
        now.tensor().kind() != runtime::ComponentKind::Float)
      in.variable(*c.var) = Value::of_tensor(runtime::Tensor(runtime::ComponentKind::Float, shape));
  }
  std::vector<void*> arrays(b.arrays.size(), nullptr);
  for (int pass = 0; pass < 2; ++pass)
    for (size_t i = 0; i < b.arrays.size(); ++i) {
      if (t.arrays[i].written != (pass == 0)) continue;
      using Part = SystemBinding::Array::Part;
      if (b.arrays[i].part == Part::Scratch) {
        e->scratch.resize(b.arrays.size());
        e->scratch[i].resize(static_cast<size_t>(e->sizes[static_cast<size_t>(b.arrays[i].size)]));
        arrays[i] = e->scratch[i].data();
        continue;
      }
      Value& v = in.variable(*b.arrays[i].var);
      switch (b.arrays[i].part) {
        case Part::Vector:
          arrays[i] = t.arrays[i].written ? static_cast<void*>(v.tensor().mutable_floats())
                                          : const_cast<double*>(v.tensor().floats());
          break;
        case Part::RowPtr: {
          if (t.matrices_in_place) {
            arrays[i] = const_cast<int32_t*>(v.matrix()->pattern().row_ptr().data());
            break;
          }
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
        case Part::Cols:
          arrays[i] = t.matrices_in_place
                          ? const_cast<int32_t*>(v.matrix()->pattern().col_idx().data())
                          : e->pruned[b.arrays[i].var].cols.data();
          break;
        case Part::Values:
          arrays[i] = t.matrices_in_place ? const_cast<double*>(std::as_const(*v.matrix()).values())
                                          : e->pruned[b.arrays[i].var].values.data();
          break;
        case Part::Field: {
          runtime::Field& f = bound_field(b.arrays[i], in);
          // A write counts in the field's write version (and unshares its array).
          if (f.type().single)
            arrays[i] = t.arrays[i].written ? static_cast<void*>(f.data<float>())
                                            : const_cast<float*>(std::as_const(f).data<float>());
          else
            arrays[i] = t.arrays[i].written ? static_cast<void*>(f.data<double>())
                                            : const_cast<double*>(std::as_const(f).data<double>());
          break;
        }
        case Part::Scratch: break;
      }
    }
  std::vector<double> scalars(b.scalars.size(), 0.0);
  for (size_t i = 0; i < b.scalars.size(); ++i) {
    const Value& v = in.variable(*b.scalars[i]);
    if (!v.empty()) scalars[i] = component(v, 0);
  }
  interp::Trap& trap = in.trap();
  const int32_t rc =
      executor_->run_system(
          *e->kernel, {arrays.data(), scalars.data(), e->sizes.data(), trap.interrupt_flag()});
  // Ctrl-C: the loop stopped between two iterations. What it wrote stays (fields are written
  // in place and cannot be put back), as what the interpreter ran before an interrupt stays;
  // the scalars go back to their variables, and the interrupt is raised below.
  const bool interrupted = rc == kSystemInterrupted;
  if (rc != 0 && !interrupted) {
    for (auto& [var, value] : saved) in.variable(*var) = std::move(value);
    ++e->handed_back;
  }
  const std::vector<bool> written =
      interrupted ? scalars_written_up_to_loop(t) : std::vector<bool>();
  for (size_t i = 0; i < b.scalars.size() && (rc == 0 || interrupted); ++i) {
    if (!(interrupted ? written[i] : e->writes_scalar[i])) continue;
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
  e->stats.note.clear();
  if (e->total > 0) {
    char note[160];
    std::snprintf(note, sizeof note,
                  "; products stream %.1f%% of the blocks (zero blocks dropped in %.2f cpu ms)",
                  100.0 * static_cast<double>(e->kept) / static_cast<double>(e->total),
                  e->prune_cpu_ms);
    e->stats.note = note;
  }
  if (e->handed_back > 0)
    e->stats.note += "; " + std::to_string(e->handed_back) + " call" +
                     (e->handed_back > 1 ? "s" : "") +
                     " reached an error statement and ran again interpreted";
  if (interrupted) {
    // Taken and raised as the interpreter's trap point does (exec_trapped), at the statement
    // it would have stopped before: the REPL reports it and returns to its prompt.
    trap.take_interrupt();
    throw interp::Interrupted(interrupted_at(e->run).span, "interrupted");
  }
  return rc == 0;
}

namespace {

// Equal bits, or zeros of either sign (a folded product by a zero, jit/zero_fold.h).
bool same_bits(double a, double b) {
  return std::memcmp(&a, &b, sizeof a) == 0 || (a == 0.0 && b == 0.0);
}

std::string number(double v) {
  char b[40];
  std::snprintf(b, sizeof b, "%.17g", v);
  return b;
}

// The element of a matrix result whose write made block `pos`: the first element whose
// per-element table names it.
int element_of_block(const runtime::MatrixPattern& p, int32_t pos) {
  const runtime::AssemblyIndex& a = p.assembly();
  for (size_t i = 0; i < a.table.size(); ++i)
    if (a.table[i] == pos) return static_cast<int>(i / a.pairs());
  return -1;
}

}  // namespace

// --check-jit on a site: run the kernel, keep what it computed, put the fields back as they
// were and let the interpreter run the site on the same inputs; site_done compares.
bool TraceController::check_site(Entry& e, interp::SiteCall& call) {
  const Trace& t = *e.traced.trace;
  auto p = std::make_unique<Pending>();
  p->at = call.plan.site;
  p->name = e.stats.site;
  p->trace = &t;
  std::vector<std::pair<int, std::vector<std::byte>>> before;
  for (size_t i = 0; i < t.arrays.size(); ++i) {
    const ArraySlot& a = t.arrays[i];
    if (a.kind != ArraySlot::Kind::Field || !a.written) continue;
    const runtime::Field& f = runtime::member_set(call.target, a.member).field(a.index);
    const size_t bytes = static_cast<size_t>(call.target.size()) * f.element_bytes();
    before.emplace_back(static_cast<int>(i), std::vector<std::byte>(f.bytes(), f.bytes() + bytes));
  }
  if (!run_kernel(e, call)) return false;  // an error: the interpreter reports it
  ++e.stats.calls;
  if (options_.corrupt_for_test && !call.results.empty()) {
    Value& r = call.results[0];
    double* v = r.kind() == Value::Kind::Matrix ? r.matrix()->values()
                : r.is_tensor()                 ? r.tensor().mutable_floats()
                                                : nullptr;
    if (v) {
      uint64_t bits;
      std::memcpy(&bits, v, sizeof bits);
      bits ^= 1;
      std::memcpy(v, &bits, sizeof bits);
    }
  }
  p->specialised.resize(call.results.size());
  for (size_t i = 0; i < call.results.size(); ++i) {
    Value& r = call.results[i];
    if (r.kind() == Value::Kind::Matrix) {
      if (r.matrix()->shared_pattern() != call.plan.results[i].pattern) {
        // The interpreter assembles on the full pattern: it makes that matrix itself, and
        // the compiled one is kept whole.
        p->results.emplace_back();
        p->specialised[i] = std::move(r);
        r = Value::of_matrix(nullptr);
        continue;
      }
      const double* v = r.matrix()->values();
      p->results.emplace_back(v, v + r.matrix()->value_count());
    } else if (r.is_tensor() && r.tensor().kind() == runtime::ComponentKind::Float) {
      p->results.emplace_back(r.tensor().floats(), r.tensor().floats() + r.tensor().size());
    } else {
      p->results.emplace_back();
    }
  }
  for (auto& [slot, bytes] : before) {
    const ArraySlot& a = t.arrays[slot];
    runtime::Field& f =
        const_cast<runtime::Set&>(runtime::member_set(call.target, a.member)).field(a.index);
    p->fields.emplace_back(slot, std::vector<std::byte>(f.bytes(), f.bytes() + bytes.size()));
    std::memcpy(f.bytes(), bytes.data(), bytes.size());
  }
  zero_results(call);
  pending_ = std::move(p);
  return false;
}

void TraceController::site_done(interp::SiteCall& call) {
  if (!pending_ || pending_->at != call.plan.site) return;
  const std::unique_ptr<Pending> p = std::move(pending_);
  const ast::FuncDecl& f = *call.plan.func;
  auto differ = [&](const std::string& what, int element, const runtime::Set& set, double interp,
                    double jit) {
    throw interp::RuntimeError(
        call.at,
        "--check-jit: the compiled " + p->name + " differs from the interpreter in " + what +
            (element >= 0 ? " at element " + std::to_string(element) + " of " + set.describe()
                          : "") +
            ": interpreted " + number(interp) + ", compiled " + number(jit));
  };
  for (size_t r = 0; r < call.results.size() && r < p->results.size(); ++r) {
    const Value& v = call.results[r];
    const std::vector<double>& jit = p->results[r];
    const double* in = v.kind() == Value::Kind::Matrix ? v.matrix()->values()
                       : v.is_tensor()                 ? v.tensor().floats()
                                                       : nullptr;
    if (!in) continue;
    if (r < p->specialised.size() && !p->specialised[r].empty()) {
      // The compiled matrix holds the blocks written; every other block of the interpreter's
      // must be zero.
      const runtime::SystemMatrix& full = *v.matrix();
      const runtime::MatrixPattern& fp = full.pattern();
      const runtime::MatrixPattern& sp = p->specialised[r].matrix()->pattern();
      const double* compiled = std::as_const(*p->specialised[r].matrix()).values();
      const size_t bs = static_cast<size_t>(full.block_size());
      for (int row = 0; row < fp.rows(); ++row)
        for (int32_t k = fp.row_ptr()[row]; k < fp.row_ptr()[row + 1]; ++k) {
          const int32_t at = sp.find(row, fp.col_idx()[k]);
          for (size_t c = 0; c < bs; ++c) {
            const double iv = in[static_cast<size_t>(k) * bs + c];
            const double jv = at < 0 ? 0.0 : compiled[static_cast<size_t>(at) * bs + c];
            if (same_bits(iv, jv)) continue;
            differ("result '" + f.results[r].name + "' component " +
                       std::to_string(static_cast<size_t>(k) * bs + c) + " (block " +
                       std::to_string(k) + (at < 0 ? ", left out of the specialised pattern" : "") +
                       ")",
                   element_of_block(fp, k), call.target, iv, jv);
          }
        }
      call.results[r] = std::move(p->specialised[r]);
      continue;
    }
    for (size_t c = 0; c < jit.size(); ++c) {
      if (same_bits(in[c], jit[c])) continue;
      const std::string what = "result '" + f.results[r].name + "' component " + std::to_string(c);
      if (v.kind() == Value::Kind::Matrix) {
        const int32_t pos = static_cast<int32_t>(c / static_cast<size_t>(v.matrix()->block_size()));
        differ(what + " (block " + std::to_string(pos) + ")",
               element_of_block(v.matrix()->pattern(), pos), call.target, in[c], jit[c]);
      }
      const size_t block = v.tensor().shape().block_size();
      differ(what + " (entry " + std::to_string(c / block) + " of the vector)", -1, call.target,
             in[c], jit[c]);
    }
  }
  for (const auto& [slot, bytes] : p->fields) {
    const ArraySlot& a = p->trace->arrays[slot];
    const runtime::Set& set = runtime::member_set(call.target, a.member);
    const runtime::Field& fld = set.field(a.index);
    if (std::memcmp(fld.bytes(), bytes.data(), bytes.size()) == 0) continue;
    const size_t per = fld.element_bytes();
    for (size_t at = 0; at < bytes.size(); ++at)
      if (fld.bytes()[at] != bytes[at]) {
        const int element = static_cast<int>(at / per);
        double iv = 0.0, jv = 0.0;
        if (a.ty == Ty::F64 && !a.single) {
          const size_t c = at / sizeof(double);
          std::memcpy(&iv, fld.bytes() + c * sizeof(double), sizeof iv);
          std::memcpy(&jv, bytes.data() + c * sizeof(double), sizeof jv);
        }
        differ("field '" + fld.name() + "'", element, set, iv, jv);
      }
  }
}

// --check-jit on a loop: the same, with the variables the loop writes kept (as shared
// copies: the kernel's writes copy them first) and put back for the interpreter.
// --check-jit on a loop or a run: run the kernel, keep what it computed, put the variables
// back as they were and let the interpreter run the statements; statement_done compares
// after the last one. Nothing is offered meanwhile (a run's loop would check itself).
// False when the kernel reached an error statement (and put the variables back).
bool TraceController::check_system(LoopEntry& e, interp::Interpreter& in) {
  const SystemBinding& b = e.traced.binding;
  const SystemTrace& t = *e.traced.trace;
  Saved before = save_loop_variables(b, t, e.writes_scalar, in);
  // Written fields, as they were (a run that writes one holds no error statement).
  std::vector<Pending::RunField> fields;
  for (size_t i = 0; i < b.arrays.size(); ++i) {
    if (!t.arrays[i].written || b.arrays[i].part != SystemBinding::Array::Part::Field) continue;
    const runtime::Field& f = bound_field(b.arrays[i], in);
    const size_t n =
        static_cast<size_t>(in.variable(*b.arrays[i].var).binding()->set->size()) * f.components();
    fields.push_back(Pending::RunField{&f, t.arrays[i].name, field_values(f, n)});
  }
  if (!run_loop_kernel(e, in)) return false;  // an error: the interpreter reports it
  auto p = std::make_unique<Pending>();
  p->at = e.run.back();
  p->name = e.stats.site;
  for (auto& [var, value] : before) {
    p->variables.emplace_back(var, in.variable(*var));
    in.variable(*var) = std::move(value);
  }
  for (Pending::RunField& f : fields) {
    runtime::Field& field = const_cast<runtime::Field&>(*f.field);
    std::vector<double> compiled = field_values(field, f.values.size());
    set_field_values(field, f.values);
    f.values = std::move(compiled);
    p->run_fields.push_back(std::move(f));
  }
  pending_ = std::move(p);
  if (e.run.size() > 1 || !e.run.front()->is<ast::While>()) checking_run_ = e.run.back();
  return true;
}

void TraceController::statement_done(const ast::Stmt& stmt, interp::Interpreter& in) {
  if (!pending_ || pending_->at != &stmt) return;
  checking_run_ = nullptr;
  const std::unique_ptr<Pending> p = std::move(pending_);
  for (const Pending::RunField& f : p->run_fields) {
    const std::vector<double> got = field_values(*f.field, f.values.size());
    const size_t per = std::max<size_t>(f.field->components(), 1);
    for (size_t c = 0; c < f.values.size(); ++c)
      if (!same_bits(got[c], f.values[c]))
        throw interp::RuntimeError(
            stmt.span,
            "--check-jit: the compiled " + p->name + " differs from the interpreter in '" + f.name +
                "' component " + std::to_string(c) + " (element " + std::to_string(c / per) +
                "): interpreted " + number(got[c]) + ", compiled " + number(f.values[c]));
  }
  for (const auto& [var, jit] : p->variables) {
    const Value& got = in.variable(*var);
    auto differ = [&](const std::string& where, double a, double b) {
      throw interp::RuntimeError(stmt.span, "--check-jit: the compiled " + p->name +
                                                " differs from the interpreter in '" + var->name +
                                                "'" + where + ": interpreted " + number(a) +
                                                ", compiled " + number(b));
    };
    if (got.is_tensor() && jit.is_tensor()) {
      const runtime::Tensor &a = got.tensor(), &b = jit.tensor();
      if (a.kind() != runtime::ComponentKind::Float || a.size() != b.size()) continue;
      const size_t block = a.shape().block_size();
      for (size_t c = 0; c < a.size(); ++c)
        if (!same_bits(a.floats()[c], b.floats()[c]))
          differ(" component " + std::to_string(c) + " (element " + std::to_string(c / block) + ")",
                 a.floats()[c], b.floats()[c]);
    } else if (got.kind() == Value::Kind::Float && jit.kind() == Value::Kind::Float) {
      if (!same_bits(got.as_float(), jit.as_float())) differ("", got.as_float(), jit.as_float());
    } else if (got.kind() == Value::Kind::Int && jit.kind() == Value::Kind::Int) {
      if (got.as_int() != jit.as_int()) differ("", got.as_int(), jit.as_int());
    }
  }
}

const FusedSums& TraceController::fused_sums(const interp::Interpreter& in) {
  if (!fused_) fused_ = find_fused_sums(in.program());
  return *fused_;
}

// `A = M - s * K` in K's storage (jit/matrix_sum.h). Declined under float32 and check-finite,
// where the interpreter looks at s * K on its own, and when M has a block outside K's pattern.
bool TraceController::run_fused_sum(const ast::Stmt& stmt, const FusedSum& sum,
                                    interp::Interpreter& in) {
  if (!target_ || options_.float32 || options_.check_finite || checking_run_) return false;
  SumState& s = sums_[&stmt];
  if (s.stats.site.empty()) {
    s.stats.line = static_cast<int>(stmt.span.start().line);
    s.stats.site = "statement (line " + std::to_string(s.stats.line) + ")";
    s.stats.key = sum.target->name + " = " + sum.base->name + (sum.subtract ? " - " : " + ") +
                  "s * " + sum.scaled->name + " in the storage of " + sum.scaled->name +
                  " (the map on line " + std::to_string(sum.producer_line) + ")";
  }
  if (++s.runs <= options_.threshold) return false;
  const Value& kv = in.variable(*sum.scaled);
  const Value& mv = in.variable(*sum.base);
  if (kv.kind() != Value::Kind::Matrix || mv.kind() != Value::Kind::Matrix || !kv.matrix() ||
      !mv.matrix())
    return false;
  const Value factor = in.evaluate(*sum.factor, 0);
  if (factor.kind() != Value::Kind::Float) return false;
  const double beta = sum.subtract ? -factor.as_float() : factor.as_float();
  const std::shared_ptr<runtime::SystemMatrix> k = kv.matrix();
  const std::shared_ptr<runtime::SystemMatrix> m = mv.matrix();
  std::optional<runtime::SystemMatrix> want;
  if (options_.check) want = runtime::add(*m, *k, 1.0, beta, &in.patterns());
  const auto start = std::chrono::steady_clock::now();
  const double cpu = thread_cpu_ms();
  if (!runtime::add_into(*m, 1.0, *k, beta)) {
    s.stats.status =
        "interpreted: " + sum.base->name + " has blocks outside the pattern of " + sum.scaled->name;
    return false;
  }
  s.stats.cpu_ms += thread_cpu_ms() - cpu;
  s.stats.run_ms +=
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  ++s.stats.calls;
  s.stats.status = "fused";
  if (want) {
    const runtime::MatrixPattern &pw = want->pattern(), &pk = k->pattern();
    if (pw.row_ptr() != pk.row_ptr() || pw.col_idx() != pk.col_idx())
      throw interp::RuntimeError(stmt.span,
                                 "--check-jit: the fused sum's pattern differs from "
                                 "the interpreter's for '" +
                                     sum.target->name + "'");
    for (size_t c = 0; c < want->value_count(); ++c)
      if (!same_bits(want->values()[c], k->values()[c]))
        throw interp::RuntimeError(
            stmt.span, "--check-jit: the fused sum differs from the interpreter in '" +
                           sum.target->name + "' component " + std::to_string(c) + " (block " +
                           std::to_string(c / static_cast<size_t>(k->block_size())) +
                           "): interpreted " + number(want->values()[c]) + ", compiled " +
                           number(k->values()[c]));
  }
  // K is dead, but a debugger stopped later (Ctrl-C) could still print it: it has no value
  // rather than the sum's.
  in.variable(*sum.scaled) = Value();
  in.variable(*sum.target) = Value::of_matrix(k);
  return true;
}

std::vector<TraceStats> TraceController::stats() const {
  std::vector<TraceStats> out;
  for (const auto& [site, s] : sites_)
    for (const auto& [key, e] : s->kernels) {
      out.push_back(e->stats);
      for (size_t i = 0; i < e->special.size(); ++i) {
        const Entry::Special& sp = e->special[i];
        char note[160];
        if (sp.pattern) {
          std::snprintf(note, sizeof note,
                        "; result %zu specialised to %.1f%% of its blocks (%lld of %lld, built in "
                        "%.2f ms)",
                        i,
                        100.0 * static_cast<double>(sp.pattern->kept) /
                            static_cast<double>(std::max<int64_t>(sp.pattern->total, 1)),
                        static_cast<long long>(sp.pattern->kept),
                        static_cast<long long>(sp.pattern->total), sp.pattern->build_ms);
          out.back().note += note;
        }
      }
      if (e->guard_calls > 0) {
        char note[200];
        std::snprintf(note, sizeof note,
                      "; guard: %zu field version%s and %zu scalar%s compared per call, %.0f ns "
                      "per call",
                      e->deciders->fields.size(), e->deciders->fields.size() == 1 ? "" : "s",
                      e->deciders->scalars.size(), e->deciders->scalars.size() == 1 ? "" : "s",
                      1e6 * e->guard_ms / static_cast<double>(e->guard_calls));
        out.back().note += note;
      }
      if (e->guard_failures > 0)
        out.back().note += "; the guard failed on " + std::to_string(e->guard_failures) + " call" +
                           (e->guard_failures > 1 ? "s" : "") + " (blocks recorded again)";
      if (!e->full_why.empty()) out.back().note += "; full patterns: " + e->full_why;
    }
  for (const auto* states : {&runs_, &loops_})
    for (const auto& [at, s] : *states)
      for (const auto& e : s->entries) out.push_back(e->stats);
  for (const auto& [at, s] : alone_)
    for (const auto& e : s->entries)
      if (e->kernel) out.push_back(e->stats);
  for (const auto& [at, s] : sums_)
    if (!s.stats.status.empty()) out.push_back(s.stats);
  std::stable_sort(out.begin(), out.end(), [](const TraceStats& a, const TraceStats& b) {
    return a.line != b.line ? a.line < b.line : a.site < b.site;
  });
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
