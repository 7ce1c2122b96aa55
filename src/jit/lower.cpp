// The lowering driver (jit/lower.h): the pass lists and the one sequence that runs them.
#include "jit/lower.h"

#include "jit/defer_assembly.h"

namespace simit::jit {

namespace {

template <class T>
struct Pass {
  const char* name;
  // Rewrites the trace; returns the number of loops it removed (for the stats).
  int (*run)(T&);
};

int fuse(SystemTrace& t) { return fuse_passes(t); }
// A map that cannot defer stays as it is (and runs its chunks in order).
int defer(Trace& t) {
  defer_assembly(t);
  return 0;
}

// The tracer folds as it goes: a map's only pass is for parallel executors.
constexpr Pass<Trace> kMapPasses[] = {{nullptr, nullptr}};
constexpr Pass<Trace> kParallelMapPasses[] = {{"defer-assembly", &defer}, {nullptr, nullptr}};
constexpr Pass<SystemTrace> kSystemPasses[] = {{"fuse-passes", &fuse}, {nullptr, nullptr}};

template <class T>
void dump_after(const LowerOptions& o, const char* stage, const T& t) {
  if (!o.dump || !o.dump_passes) return;
  *o.dump << "; loop IR after " << stage << "\n";
  print(*o.dump, t);
}

template <class T, size_t N>
Lowered run_pipeline(T& t, const Pass<T> (&passes)[N], Target& target, const LowerOptions& o) {
  Lowered out;
  dump_after(o, "trace", t);
  if (std::string bad = verify(t); !bad.empty()) {
    out.failure = "loop IR failed verification after trace: " + bad;
    out.verify_failed = true;
    return out;
  }
  for (const Pass<T>& p : passes) {
    if (!p.name) break;
    out.loops_fused += p.run(t);
    dump_after(o, p.name, t);
    if (std::string bad = verify(t); !bad.empty()) {
      out.failure = std::string("loop IR failed verification after ") + p.name + ": " + bad;
      out.verify_failed = true;
      return out;
    }
  }
  out.ir_nodes = node_count(t);
  out.kernel = target.compile(t, o.dump_llvm, out.failure);
  if (!out.kernel) return out;
  if (o.dump && o.dump_loop_ir) print(*o.dump, t);
  if (o.dump && o.dump_llvm) *o.dump << out.kernel->llvm_ir;
  return out;
}

}  // namespace

Lowered lower(Trace& trace, Target& target, const LowerOptions& options) {
  if (options.defer_assembly) return run_pipeline(trace, kParallelMapPasses, target, options);
  return run_pipeline(trace, kMapPasses, target, options);
}

Lowered lower(SystemTrace& trace, Target& target, const LowerOptions& options) {
  return run_pipeline(trace, kSystemPasses, target, options);
}

}  // namespace simit::jit
