// The trace controller (jit/controller.h): the hot-count state machine and the dispatch of
// sites, loops and runs of statements to their kernels.
#include <algorithm>
#include <chrono>
#include <cstring>
#include <functional>
#include <sstream>

#include "interp/exec_state.h"
#include "interp/runtime_error.h"
#include "interp/set_binding.h"
#include "jit/controller_state.h"
#include "jit/decompose_call.h"
#include "jit/lower.h"
#include "jit/matrix_sum.h"
#include "jit/pruned_matrix.h"
#include "jit/ptx/gpu_executor.h"
#include "jit/ptx/ptx_check.h"
#include "jit/ptx/ptx_target.h"
#include "jit/specialise.h"
#include "jit/thread_pool.h"
#include "jit/write_guard.h"
#include "runtime/system_ops.h"

namespace simit::jit {

namespace ast = frontend::ast;
using interp::Value;

namespace {

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

// --check-ptx and --dump=ptx: a trace compiled for the CPU compiled for the GPU as well
// (jit/ptx/ptx_check.h); PTX that ptxas rejects stops the run at `at`.
template <class T>
void check_gpu(const T& t, const std::string& site, const JitOptions& o,
               const frontend::SourceSpan& at) {
  if (!o.check_ptx && !(o.dump_ptx && o.dump)) return;
  ptx::CheckOptions c;
  c.gpu_arch = o.gpu_arch;
  c.assemble = o.check_ptx;
  c.dump = o.dump_ptx ? o.dump : nullptr;
  if (std::string bad = ptx::check_trace(t, site, c); !bad.empty())
    throw interp::RuntimeError(at, bad);
}

}  // namespace

TraceController::TraceController(JitOptions options) : options_(options) {
  HostCalls host;
  host.decompose = reinterpret_cast<void*>(&simit_jit_decompose);
  host.parallel_for = reinterpret_cast<void*>(&simit_jit_parallel_for);
  target_ = make_cpu_target(host, options_.cache_dir, target_error_);
  if (options_.shuffle_seed)
    executor_ = make_shuffled_executor(options_.shuffle_seed, kShuffledChunk);
  else if (options_.threads > 1)
    executor_ = make_threaded_executor(options_.threads, options_.min_chunk_for_test);
  else
    executor_ = make_serial_executor();
  if (options_.gpu) {
    // The engine checked that a GPU opens (executor_unavailable); a driver failing between
    // the two says so here.
    std::string why;
    device_executor_ =
        options_.gpu_emulated ? ptx::make_emulated_gpu_executor() : ptx::make_gpu_executor(why);
    if (!device_executor_) throw std::runtime_error("--executor gpu cannot run: " + why);
    if (!options_.gpu_emulated) {
      device_target_ = ptx::make_ptx_target(
          options_.gpu_arch.empty() ? ptx::kDefaultGpuArch : options_.gpu_arch, why);
      if (!device_target_) throw std::runtime_error("--executor gpu cannot run: " + why);
    }
  }
}

TraceController::~TraceController() = default;

LowerOptions TraceController::lower_options() const {
  LowerOptions o;
  o.dump = options_.dump;
  o.dump_loop_ir = options_.dump_loop_ir;
  o.dump_passes = options_.dump_passes;
  o.dump_llvm = options_.dump_llvm;
  o.defer_assembly = executor_->parallel();
  return o;
}

// Under `--executor gpu`: the trace lowered with deferred writes for the GPU's target and
// marked to run on the GPU; no kernel (the trace as it was) when the GPU cannot run it, with
// why in the trace's note, so that the host's target compiles it.
Lowered TraceController::lower_for_device(Entry& e) {
  Lowered none;
  if (!device_executor_) return none;
  const Trace traced = *e.traced.trace;
  LowerOptions o = lower_options();
  o.defer_assembly = true;
  Lowered l = lower(*e.traced.trace, device_target_ ? *device_target_ : *target_, o);
  std::string why = l.failure;
  // Emulated, the CPU's target compiles what the GPU's refuses: refused all the same.
  if (l.kernel && !device_target_) why = ptx::gpu_refusal(*e.traced.trace);
  // Elements that add into shared blocks without deferred writes would run one launch each.
  if (l.kernel && writes_of(*e.traced.trace) == MapWrites::Shared && !e.traced.trace->deferred)
    why = "its elements add into shared blocks that cannot be deferred";
  if (!why.empty() || !l.kernel) {
    *e.traced.trace = traced;
    e.stats.note += "; on the host: " + why;
    return none;
  }
  e.on_device = true;
  e.stats.note += device_target_ ? "; on the GPU" : "; on the GPU (emulated)";
  return l;
}

// Under `--executor gpu`: the system trace lowered as a device program (its steps kernels of
// their own, jit/device_program.h) for the GPU's target (emulated: the CPU's, whose steps
// the emulated executor calls), and marked to run on the GPU; no kernel (the trace as it
// was) when the GPU cannot run it, with why in the note, so that the host's target compiles
// it and it runs on the host.
Lowered TraceController::lower_system_for_device(LoopEntry& e) {
  Lowered none;
  if (!device_executor_) return none;
  const SystemTrace traced = *e.traced.trace;
  e.traced.trace->device = true;
  // The loop's products read each matrix where it is, as the interpreter does, rather than a
  // copy without its zero blocks made on the host every call: the matrix may be on the
  // device already (its map and the fused sum left it there, runtime/residency.h), and the
  // copy would bring it back and send it again. Under --float32 the copy stays (binary32:
  // half the bytes, and its vectors' binary32 marks rest on it).
  if (!options_.float32) e.traced.trace->matrices_in_place = true;
  Lowered l = lower(*e.traced.trace, device_target_ ? *device_target_ : *target_, lower_options());
  if (!l.kernel) {
    *e.traced.trace = traced;
    e.where = "; on the host: " + l.failure;
    e.stats.note = e.where;
    return none;
  }
  e.on_device = true;
  e.where = device_target_ ? "; on the GPU" : "; on the GPU (emulated)";
  e.stats.note = e.where;
  return l;
}

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
    const interp::ExecState& in = call.interpreter;
    shape.global = [&in](const ast::Variable& v) -> const Value* { return &in.global(v); };
    e->traced = trace_site(shape);
    if (!e->traced.trace) {
      // The trace depends on the site, not on the key: no retries.
      e->stats.status = "interpreted: " + e->traced.reason;
      s.failures = kMaxFailures;
      s.gave_up = e->stats.status;
    } else {
      Lowered l = lower_for_device(*e);
      if (!l.kernel) l = lower(*e->traced.trace, *target_, lower_options());
      e->stats.ir_nodes = l.ir_nodes;
      if (!l.kernel) {
        give_up("interpreted: " + l.failure);
      } else {
        e->kernel = std::move(l.kernel);
        e->stats.status = e->on_device ? "compiled for the GPU" : "compiled";
        e->writes = writes_of(*e->traced.trace);
        if (e->kernel->simd.reported) e->stats.note += "; " + e->kernel->simd.summary();
        if (e->kernel->cached) e->stats.note += "; from the kernel cache";
        e->stats.compile_ms = e->kernel->compile_ms;
      }
    }
  }
  Entry* out = e.get();
  s.kernels[key] = std::move(e);
  if (out->kernel) check_gpu(*out->traced.trace, out->stats.site, options_, call.at);
  return out;
}

bool TraceController::run_site(interp::SiteCall& call) {
  // A production run compiles a map over a large set at its first execution: interpreting
  // it even once costs more than compiling it (a frame of fem on dragon160k: 4 s against
  // 0.1 s compiled).
  const bool eager = options_.eager && call.target.size() >= kEagerElements;
  if (!eager && call.plan.runs <= options_.threshold) return false;
  Entry* e = entry_for(call);
  if (!e || !e->kernel) return false;
  if (options_.check) return check_site(*e, call);
  CallTimer timer(e->stats);
  const bool done = run_kernel(*e, call);
  timer.done();
  // Under --float32 a reduction's every addition rounds (in place, in DeferredPlan::finish,
  // in the device's gathers) and the results start at zero: the map's final rounding would
  // only read them (on fem dragon160k 13.7 MB of stiffness, 1.3% of a frame).
  const Trace& t = *e->traced.trace;
  call.results_binary32 = done && t.float32 && t.reduce;
  return done;
}

// The kernel of a while loop alone or of a run of statements, for the lengths its variables
// have now: found, or traced and compiled. A run whose statement j > 1 cannot be traced is
// traced again without it and the statements after it (s.length shrinks).
TraceController::LoopEntry* TraceController::system_entry_for(LoopState& s,
                                                              std::vector<const ast::Stmt*> run,
                                                              interp::ExecState& in) {
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
      Lowered l = lower_system_for_device(*e);
      if (!l.kernel) l = lower(t, *target_, lower_options());
      e->sizes = current_sizes(e->traced.binding, in);
      std::ostringstream key;
      for (size_t i = 0; i < t.sizes.size(); ++i) key << (i ? ", " : "") << t.sizes[i];
      key << "; " << l.loops_fused << " loops fused away";
      e->stats.key = key.str();
      e->writes_scalar.assign(static_cast<size_t>(t.scalars), false);
      for (const auto* ops : {&t.before, &t.body, &t.after})
        for (const VectorOp& op : *ops) note_scalar_writes(op.body, t.scalars, e->writes_scalar);
      if (!l.kernel) {
        fail(l.failure, l.verify_failed);
      } else {
        e->kernel = std::move(l.kernel);
        e->stats.status = e->on_device ? "compiled for the GPU" : "compiled";
        e->stats.compile_ms = e->kernel->compile_ms;
        e->stats.ir_nodes = l.ir_nodes;
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
  if (!out->kernel) return nullptr;
  check_gpu(*out->traced.trace, out->stats.site, options_, first.span);
  return out;
}

bool TraceController::run_statement(const ast::Stmt& stmt, interp::ExecState& in) {
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
  // A while loop iterates: a production run compiles it at its first execution.
  if (++state->runs <= options_.threshold && !options_.eager) return false;
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
bool TraceController::run_alone(const ast::Stmt& stmt, interp::ExecState& in) {
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
                                       interp::ExecState& in) {
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
      if (const auto* loop = block[i]->as<ast::While>()) {
        note_loop(*loop);
        state->has_loop = true;
      }
  }
  if (state->length == 0 || checking_run_ || in_loop_to_compile(block)) return 0;
  // A run with a while loop, as a loop alone, compiles at once in a production run.
  if (++state->runs <= options_.threshold && !(options_.eager && state->has_loop)) return 0;
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

}  // namespace simit::jit
