// The trace controller: the compiled executor behind the interpreter's site hook. It counts
// each site's executions, traces and compiles the hot ones for their key, keeps the kernels,
// and falls back to the interpreter (recording why) for whatever it cannot compile.
#pragma once

#include <map>
#include <memory>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "interp/assembly_plan.h"
#include "jit/executor.h"
#include "jit/lower.h"
#include "jit/matrix_sum.h"
#include "jit/pending_sums.h"
#include "jit/system_trace.h"
#include "jit/target.h"
#include "jit/trace_site.h"
#include "jit/tunables.h"

namespace simit::jit {

struct JitOptions {
  long threshold = kHotThreshold;  // executions before a site is compiled (0: at once)
  // A production run (not the REPL): a site over a set of at least kEagerElements elements
  // compiles at its first execution, whatever the threshold.
  bool eager = false;
  // Where compiled kernels are cached between runs; empty: no cache.
  std::string cache_dir;
  bool float32 = false;       // the interpreter's float32 mode
  bool check_finite = false;  // the interpreter's check-finite mode
  // Where `--dump=loop-ir,llvm,ptx` prints each compiled trace; null prints nothing.
  std::ostream* dump = nullptr;
  bool dump_loop_ir = false;
  bool dump_llvm = false;
  bool dump_passes = false;  // `--dump=passes`: the loop IR as traced and after each pass
  // Differential mode (`--check-jit`): each compiled call also runs interpreted on the same
  // inputs; the first result, field or variable that differs stops the run naming it.
  bool check = false;
  // `--check-ptx`: each trace compiled for the CPU is also compiled for the GPU and its PTX
  // assembled by ptxas (jit/ptx/ptx_check.h); PTX that ptxas rejects stops the run.
  // `--dump=ptx`: that PTX printed where the other dumps print.
  bool check_ptx = false;
  bool dump_ptx = false;
  // For the tests of the check alone: the lowest bit of a compiled map's first matrix or
  // vector value (else an apply's first written field, else a compiled statement's first
  // value) is flipped after the kernel runs.
  bool corrupt_for_test = false;
  // For the tests of the executor seam: nonzero runs map kernels through the shuffled
  // executor (jit/executor.h) with this seed instead of the serial one.
  uint64_t shuffle_seed = 0;
  // Threads compiled maps and solver loops run on (the engine's pool; 1: the calling thread).
  int threads = 1;
  // `--executor gpu`: map kernels compiled for the GPU (PTX for gpu_arch) and run on it
  // (jit/ptx/gpu_executor.h); a map the GPU target refuses, and every system trace, runs on
  // the host as under `jit`. gpu_emulated: the host-memory driver and the CPU target's
  // kernels stand in for the GPU (the tests of the data path where there is none).
  bool gpu = false;
  bool gpu_emulated = false;
  std::string gpu_arch;  // "": ptx::kDefaultGpuArch
  // For the tests of threads on small sets: the smallest chunk of a map (0: kMinThreadChunk).
  int min_chunk_for_test = 0;
};

// One trace's figures for `--jit-stats`.
struct TraceStats {
  std::string site;    // function and line of the map
  std::string key;     // what it was compiled for
  std::string status;  // "compiled", or why it runs interpreted
  double compile_ms = 0.0;
  long calls = 0;
  double run_ms = 0.0;  // wall time in the kernels
  double cpu_ms = 0.0;  // this thread's CPU time in them (steadier on a busy machine)
  size_t ir_nodes = 0;
  std::string note;  // e.g. the fraction of matrix blocks a loop's products stream
  int line = 0;      // the site's first line: stats() lists the sites in source order
};

class TraceController : public interp::SiteHook {
 public:
  explicit TraceController(JitOptions options);
  ~TraceController() override;

  bool run_site(interp::SiteCall& call) override;
  // A while loop of system-level statements (a CG loop) outside any compiled run, as a whole.
  bool run_statement(const frontend::ast::Stmt& stmt, interp::ExecState& in) override;
  // A run of system-level statements (a CG function's set-up, loop and residual), compiled
  // as one trace; when a statement of it cannot be compiled, the statements before it.
  size_t run_statements(const frontend::ast::Block& block, size_t first, size_t count,
                        interp::ExecState& in) override;
  void site_done(interp::SiteCall& call) override;
  void statement_done(const frontend::ast::Stmt& stmt, interp::ExecState& in) override;
  // The specialised results' last matrices that nothing else holds: dropped on the GPU.
  void drop_reusable() override;

  std::vector<TraceStats> stats() const;
  // A table of stats(), one line per trace.
  void print_stats(std::ostream& os) const;
  // Whether the host can compile at all (LLVM found a target); why not otherwise.
  const std::string& unavailable() const { return target_error_; }

 private:
  LowerOptions lower_options() const;
  struct Entry;
  struct SiteState;
  struct LoopEntry;
  struct LoopState;
  LoopEntry* system_entry_for(LoopState& s, std::vector<const frontend::ast::Stmt*> run,
                              interp::ExecState& in);
  Entry* entry_for(interp::SiteCall& call);
  Lowered lower_for_device(Entry& e);
  Lowered lower_system_for_device(LoopEntry& e);
  bool run_kernel(Entry& e, interp::SiteCall& call);
  // Per result: its pattern table (null for a vector) and the pattern it belongs to.
  bool prepare_deferred(Entry& e, interp::SiteCall& call, const std::vector<const int32_t*>& tables,
                        const std::vector<runtime::PatternPtr>& patterns, int32_t chunk,
                        MapWrites& writes);
  std::vector<const int32_t*> prepare_results(Entry& e, interp::SiteCall& call,
                                              std::vector<runtime::PatternPtr>* patterns = nullptr);
  void guard_results(Entry& e, interp::SiteCall& call, const std::vector<double>& scalars);
  void drop_specialised(Entry& e, interp::SiteCall& call);
  void specialise_results(Entry& e, interp::SiteCall& call);

  struct Pending;  // a compiled call's results, awaiting the interpreter's for --check-jit
  bool check_site(Entry& e, interp::SiteCall& call);
  bool check_system(LoopEntry& e, interp::ExecState& in);
  bool run_loop_kernel(LoopEntry& e, interp::ExecState& in);

  JitOptions options_;
  std::unique_ptr<Pending> pending_;
  std::unique_ptr<Target> target_;
  std::string target_error_;
  std::unique_ptr<Executor> executor_;
  // `--executor gpu`: the GPU's target (null when emulated: the CPU's compiles) and executor.
  std::unique_ptr<Target> device_target_;
  std::unique_ptr<Executor> device_executor_;
  // Fused sums that a solver loop's copy sums as it reads them (jit/pending_sums.h).
  PendingSums pending_sums_;
  std::map<const void*, std::unique_ptr<SiteState>> sites_;
  std::map<const void*, std::unique_ptr<LoopState>> loops_;  // by while loop
  std::map<const void*, std::unique_ptr<LoopState>> runs_;   // by a run's first statement
  std::map<const void*, std::unique_ptr<LoopState>> alone_;  // statements alone, by statement
  // The body of each system-level while loop seen: a run in it is not compiled while the loop
  // itself may still be (a cold loop's iterations would compile its body for nothing).
  std::map<const frontend::ast::Block*, const frontend::ast::While*> loop_of_body_;
  bool in_loop_to_compile(const frontend::ast::Block& block) const;
  bool may_compile(const frontend::ast::While& loop) const;
  // Every statement nested in a loop's body, to its loop: a statement alone is not compiled
  // there while the loop may be.
  std::map<const frontend::ast::Stmt*, const frontend::ast::While*> loop_of_stmt_;
  void note_loop(const frontend::ast::While& loop);
  bool run_alone(const frontend::ast::Stmt& stmt, interp::ExecState& in);
  // The program's fused matrix sums (jit/matrix_sum.h), found on first use.
  std::optional<FusedSums> fused_;
  const FusedSums& fused_sums(const interp::ExecState& in);
  struct SumState {
    long runs = 0;
    long pending = 0;  // calls left pending (jit/pending_sums.h)
    TraceStats stats;
    // runtime::fits_into(m, k), for the last patterns it was asked of (a walk over both).
    runtime::PatternPtr fits_m, fits_k;
    bool fitted = false;
    bool fits(const runtime::SystemMatrix& m, const runtime::SystemMatrix& k) {
      if (!m.is_float() || !k.is_float() || m.block_rows() != k.block_rows() ||
          m.block_cols() != k.block_cols())
        return false;
      if (fits_m != m.shared_pattern() || fits_k != k.shared_pattern()) {
        fitted = runtime::fits_into(m, k);
        fits_m = m.shared_pattern();
        fits_k = k.shared_pattern();
      }
      return fitted;
    }
  };
  std::map<const frontend::ast::Stmt*, SumState> sums_;
  bool run_fused_sum(const frontend::ast::Stmt& stmt, const FusedSum& sum, interp::ExecState& in);
  // While a checked run's statements run interpreted, up to this one, nothing is offered.
  const frontend::ast::Stmt* checking_run_ = nullptr;
};

}  // namespace simit::jit
