// Specialised results (jit/specialise.h): a map's matrix results on the patterns of the
// blocks it writes, recorded on a compiled call and guarded on the later ones.
#include <algorithm>
#include <chrono>
#include <cstring>
#include <functional>
#include <sstream>

#include "interp/exec_state.h"
#include "interp/runtime_error.h"
#include "interp/set_binding.h"
#include "jit/controller_state.h"
#include "jit/matrix_sum.h"
#include "jit/pruned_matrix.h"
#include "jit/specialise.h"
#include "jit/write_guard.h"
#include "runtime/residency.h"
#include "runtime/system_ops.h"

namespace simit::jit {

namespace ast = frontend::ast;
using interp::Value;

// The matrix results: on the specialised pattern where there is one, otherwise on the full
// one (made here when the interpreter left it to the hook). Returns the tables to use.
std::vector<const int32_t*> TraceController::prepare_results(
    Entry& e, interp::SiteCall& call, std::vector<runtime::PatternPtr>* patterns) {
  e.special.resize(call.results.size());
  std::vector<const int32_t*> tables(call.results.size(), nullptr);
  if (patterns) patterns->assign(call.results.size(), nullptr);
  for (size_t i = 0; i < call.results.size(); ++i) {
    interp::AssemblyPlan::Result& r = call.plan.results[i];
    if (!r.is_matrix || !r.pattern) continue;
    Entry::Special& s = e.special[i];
    const runtime::BlockDims bd = runtime::block_dims(r.block);
    const bool special = s.pattern && s.pattern->full == r.pattern;
    const runtime::PatternPtr& pattern = special ? s.pattern->pattern : r.pattern;
    if (special || !call.results[i].matrix()) {
      if (s.last && s.last.use_count() == 1 && s.last->shared_pattern() == pattern) {
        // Zeroed on the executor's threads (the stiffness of dragon160k is 13.7 MB); every
        // value set anew, so a newer copy on the GPU is dropped, not brought back first.
        runtime::residency::settle(s.last->raw_values());
        double* v = s.last->raw_values();
        const int64_t n = static_cast<int64_t>(s.last->value_count());
        constexpr int64_t kPerTask = int64_t{1} << 17;
        executor_->for_each((n + kPerTask - 1) / kPerTask, [v, n](int64_t t) {
          std::fill(v + t * kPerTask, v + std::min(n, (t + 1) * kPerTask), 0.0);
        });
      } else {
        s.last = std::make_shared<runtime::SystemMatrix>(pattern, bd.rows, bd.cols,
                                                         runtime::ComponentKind::Float);
      }
      call.results[i] = Value::of_matrix(s.last);
    }
    tables[i] = special ? s.pattern->table.data() : r.pattern->assembly().table.data();
    if (patterns) (*patterns)[i] = pattern;
  }
  return tables;
}

// Before a call: the guard of the specialised results (drops them when the inputs that
// decide the writes changed), and the results whose blocks this call records.
void TraceController::guard_results(Entry& e, interp::SiteCall& call,
                                    const std::vector<double>& scalars) {
  const Trace& t = *e.traced.trace;
  if (t.writes_fields) return;
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

void TraceController::drop_reusable() {
  for (auto& [site, state] : sites_)
    for (auto& [key, e] : state->kernels)
      for (Entry::Special& s : e->special)
        if (s.last && s.last.use_count() == 1) runtime::residency::settle(s.last->raw_values());
}

}  // namespace simit::jit
