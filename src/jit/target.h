// What a code generation target offers the JIT: a trace in, a kernel out. A kernel runs
// through Kernel::run (no caller holds a function pointer), and an Executor (jit/executor.h)
// decides how a map kernel's elements are split into calls. Only the targets' own folders
// (jit/cpu, jit/llvm) include LLVM's headers.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "jit/loop_ir.h"

namespace simit::jit {

// How an executor that keeps its own copy of an array (a GPU's) brings it up to date for a
// call (MapArgs::array_fill): by copying the host's, or, where the host set every value to
// one constant for this call, by setting its copy to that constant where it lies.
enum class ArrayFill : uint8_t {
  Copy = 0,
  Zero = 1,          // the host zeroed it (a result): every byte 0
  NegativeZero = 2,  // the host set every double to -0.0 (a split run's deferred blocks)
};

// A map kernel's arguments: one pointer per ArraySlot, one double per scalar argument (ints
// and booleans converted exactly), the target set's endpoint table.
struct MapArgs {
  void* const* arrays = nullptr;
  const double* scalars = nullptr;
  const int32_t* endpoints = nullptr;
  // What an executor that copies the arguments into another memory (a GPU's) needs: how many
  // arrays and scalars there are, each array's bytes and whether the kernel writes it, and
  // the endpoint table's entries per element. Executors on the host ignore them.
  size_t array_count = 0;
  const size_t* array_bytes = nullptr;
  const uint8_t* array_written = nullptr;
  size_t scalar_count = 0;
  int32_t arity = 0;
  // Residency, for such an executor that keeps its copies between calls: per array, a stamp
  // naming the host copy's contents before this call's own access (array_version_in) and
  // after the caller bound it (array_version_out; they differ where binding a field for
  // writing counts as a write). Equal stamps mean equal contents, for good (a stamp is never
  // reused for other contents, not even at the address of a freed array); 0 means unknown:
  // copied every call. array_fill: per array, what the host set it to for this call when it
  // set every value to one constant (a result zeroed, deferred blocks at -0.0): the copy is
  // set where it lies rather than copied. Likewise the endpoint table's stamp. Null arrays:
  // every stamp 0, every array copied.
  const uint64_t* array_version_in = nullptr;
  const uint64_t* array_version_out = nullptr;
  const ArrayFill* array_fill = nullptr;
  uint64_t endpoints_version = 0;
  // Per array, whether it is a runtime array whose accessors bring a newer copy back
  // (runtime/residency.h): such an executor may leave what the kernel wrote there in its own
  // memory until the host touches the array. Null: every written array is copied back.
  const uint8_t* array_resident = nullptr;
};

// The elements [begin, end) of a map's target set.
struct ElementRange {
  int32_t begin = 0;
  int32_t end = 0;
};

// A system kernel's arguments: `scalars` holds the program's scalars (in, then out), `sizes`
// the lengths the trace names, `interrupt` the host's interrupt flag (a byte, nonzero while
// an interrupt is pending: interp::Trap::interrupt_flag), which its while loop reads at the
// top of every iteration.
struct SystemArgs {
  void* const* arrays = nullptr;
  double* scalars = nullptr;
  const int64_t* sizes = nullptr;
  const void* interrupt = nullptr;
  // The executor's thread pool (jit/thread_pool.h) its passes run on, or null: one thread.
  void* pool = nullptr;
  // For an executor that copies the arrays elsewhere (a device program on the GPU): how many
  // arrays and sizes there are, each array's size in bytes and whether the kernel writes it,
  // and how many of `scalars` there are.
  size_t array_count = 0, size_count = 0, scalar_count = 0;
  const size_t* array_bytes = nullptr;
  const bool* array_written = nullptr;
  // As MapArgs::array_resident.
  const uint8_t* array_resident = nullptr;
  // Where a host kernel with a loop stores the iterations it ran (--jit-stats), or null; a
  // device program leaves it as it is.
  int64_t* iterations = nullptr;
};

// A system kernel's return when its loop stopped for the interrupt flag (the scalars written
// back: everything as a whole number of iterations leaves it, the ops after the loop not run).
inline constexpr int32_t kSystemInterrupted = -1;

// What a kernel computes in SIMD (docs/jit.md, "What vectorises"): a map kernel's lanes, or
// why it has none, and what LLVM's vectorisers did with the kernel's innermost loops (the
// only loops LLVM's loop vectoriser looks at).
struct SimdLoop {
  int number = 0;       // the loop's place among the kernel's loops, in emission order (from 1)
  std::string what;     // what the loop does, e.g. "vector pass", "a sum's runs one by one"
  int width = 1;        // elements per vector operation: 1 when not vectorised
  int interleave = 1;   // vector operations in flight per iteration
  std::string why_not;  // when not vectorised: LLVM's reason in short words
};
struct SimdReport {
  bool reported = false;      // filled in by the target (the CPU's; not the GPU's)
  bool map = false;           // a map or apply kernel (which may run in lanes), not a system one
  int lanes = 1;              // a map kernel's elements at once
  std::string lanes_why_not;  // a map kernel not in lanes: why
  // Whether LLVM's loop and SLP vectorisers ran (not on a large trace, compiled without
  // optimisation: jit/tunables.h).
  bool vectorisers = true;
  std::vector<SimdLoop> loops;  // the innermost loops the loop vectoriser reported on
  int slp_groups = 0;  // straight-line code the SLP vectoriser turned into vector operations
  // The --jit-stats note: "SIMD: 4 elements at once", "SIMD: 2 of 3 loops vectorised
  // (width 4); not: reduction in the contract's order (1)" (jit/jit_stats.cpp).
  std::string summary() const;
};

struct DeviceProgram;

class Kernel {
 public:
  virtual ~Kernel() = default;
  // A map kernel over `range`: 0, or 1 + the index of the failed check in Trace::errors with
  // the element in *failed_element.
  virtual int32_t run(const MapArgs& args, ElementRange range, int32_t* failed_element) const = 0;
  // A system kernel: 0; kSystemInterrupted; or 1 + the index in SystemTrace::errors of the
  // error statement it reached (the scalars and vectors are then partly updated).
  virtual int32_t run(const SystemArgs& args) const = 0;
  // A device program's step `step` (jit/device_program.h) over its units [first, end), with
  // `context` its context array: for a kernel compiled from a SystemTrace with `device` set
  // by a target whose code runs in this process (the emulated GPU's). Throws otherwise.
  virtual void run_step(int32_t step, int64_t* context, int64_t first, int64_t end) const;
  // Set for a device program: its steps (their ops not kept: the trace may go first).
  std::shared_ptr<const DeviceProgram> program;

  double compile_ms = 0.0;
  int lanes = 1;        // elements computed at once (a map kernel in SIMD lanes)
  bool cached = false;  // loaded from the kernel cache rather than compiled
  std::string llvm_ir;  // the optimised module, when asked for (`--dump=llvm`)
  SimdReport simd;      // what runs in SIMD (kept with the kernel in the kernel cache)
};

// A code generation target (the host CPU; NVIDIA GPUs next).
class Target {
 public:
  virtual ~Target() = default;
  virtual const char* name() const = 0;
  // Null with `error` set when the trace could not be compiled.
  virtual std::unique_ptr<Kernel> compile(const Trace& trace, bool keep_ir, std::string& error) = 0;
  virtual std::unique_ptr<Kernel> compile(const SystemTrace& trace, bool keep_ir,
                                          std::string& error) = 0;
};

// Functions of the host process compiled code calls (their addresses are built into it).
struct HostCalls {
  // int32_t (int32_t fn, int32_t n, int32_t float32, const double* in, double* out)
  void* decompose = nullptr;
  // void (void* pool, void (*op)(const int64_t*, int64_t, int64_t), const int64_t* context,
  // int64_t units): simit_jit_parallel_for (jit/thread_pool.h)
  void* parallel_for = nullptr;
};

// The host CPU through LLVM ORC; null with `error` set when LLVM cannot target this machine.
// With a `cache_dir`, compiled kernels are kept there and reused by later runs.
std::unique_ptr<Target> make_cpu_target(const HostCalls& host, const std::string& cache_dir,
                                        std::string& error);

}  // namespace simit::jit
