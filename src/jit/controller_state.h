// The trace controller's private state, shared by the files that implement it: the kernels
// it keeps per site and per run of statements, a --check-jit call's pending results, and the
// helpers more than one of those files uses.
#pragma once

#include <chrono>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "interp/exec_state.h"
#include "jit/controller.h"
#include "jit/deferred_plan.h"
#include "jit/loop_traffic.h"
#include "jit/pruned_matrix.h"
#include "jit/specialise.h"
#include "jit/write_guard.h"

namespace simit::jit {

namespace ast = frontend::ast;
using interp::Value;
using Saved = std::vector<std::pair<const ast::Variable*, Value>>;

struct TraceController::Entry {
  TracedSite traced;
  std::unique_ptr<Kernel> kernel;
  MapWrites writes = MapWrites::Shared;
  bool on_device = false;  // the kernel runs through the GPU executor
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
  // A deferred kernel's tables (jit/deferred_plan.h).
  std::unique_ptr<DeferredPlan> plan;
  bool split_noted = false;  // --jit-stats says once how the chunks split
  // --float32 calls left to the interpreter: a float argument that is not a binary32 value
  // (the kernel reads its float arguments as binary32 values).
  long not_binary32 = 0;
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
  bool on_device = false;  // a device program, run through the GPU executor
  std::string where;       // --jit-stats: "; on the GPU", or "; on the host: why"
  // Per matrix the loop multiplies (by the variable): its non-zero blocks, rebuilt per call.
  std::map<const ast::Variable*, PrunedMatrix> pruned;
  int64_t kept = 0, total = 0;  // blocks streamed and blocks in the patterns, over all calls
  double prune_cpu_ms = 0.0;
  std::vector<int64_t> sizes;       // the lengths it was traced for
  std::vector<bool> writes_scalar;  // per scalar local
  long handed_back = 0;             // calls that reached an error statement
  long not_binary32 = 0;  // float32 calls left to the interpreter: a matrix not in binary32
  std::vector<std::vector<double>> scratch;  // per array slot: a scratch vector's storage
  // Per array slot under float32: a vector's binary32 storage (the program's vectors are
  // copied in before the call and out after it; the scratch vectors live there).
  std::vector<std::vector<float>> single;
  // --jit-stats: which arrays an iteration moves (made at the first call), the bytes its
  // calls moved and how fast.
  std::optional<TrafficPlan> traffic_plan;
  TrafficCount traffic;
  TraceStats stats;
};

struct TraceController::LoopState {
  size_t length = 0;  // a run: how many of its statements are traced (a prefix, after a failure)
  long runs = 0;
  bool has_loop = false;  // a run: one of its statements is a while loop
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

double thread_cpu_ms();

// Times one call of a trace into its stats (run_ms, cpu_ms, calls) when it is done. Reading a
// thread's CPU time is a system call (about 1.4 us in a virtual machine, more than a small
// map's kernel: cloth calls five sites 50 times a frame), so it is read only for a trace
// whose calls have taken 0.2 ms or more on average; a shorter call counts its wall time as
// its CPU time.
class CallTimer {
 public:
  explicit CallTimer(TraceStats& stats);
  void done();

 private:
  TraceStats& stats_;
  std::chrono::steady_clock::time_point start_;
  double cpu_ = -1.0;  // the thread's CPU time at the start, or -1 when not read
};
// "812 bytes", "41.5 KB", "18.4 MB".
std::string bytes_text(long long bytes);

// The lengths a system trace's sizes name, as the interpreter's values hold them now (-1
// where a value is missing or of another kind).
std::vector<int64_t> current_sizes(const SystemBinding& b, interp::ExecState& in);

// Marks the program scalars (locals below `scalars`) a block sets, in branches too.
void note_scalar_writes(const std::vector<Stmt>& body, int scalars, std::vector<bool>& writes);

double component(const Value& v, int i);

void zero_results(interp::SiteCall& call);

// Equal bits, or zeros of either sign (a folded product by a zero, jit/zero_fold.h).
bool same_bits(double a, double b);

std::string number(double v);

// The field a Field array of a system trace names (its set is bound: the sizes matched).
runtime::Field& bound_field(const SystemBinding::Array& a, interp::ExecState& in);

// The first n components of a float field as binary64 (binary32 storage widens exactly),
// and back (binary32 storage takes values that came from it, exactly).
std::vector<double> field_values(const runtime::Field& f, size_t n);

void set_field_values(runtime::Field& f, const std::vector<double>& values);

// The variables a loop writes, as shared copies: a vector the kernel writes is copied by
// its first write (copy on write), so keeping the old value costs one copy of each written
// vector per call, and only for loops that may stop.
Saved save_loop_variables(const SystemBinding& b, const SystemTrace& t,
                          const std::vector<bool>& writes_scalar, interp::ExecState& in);

}  // namespace simit::jit
