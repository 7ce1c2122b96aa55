// A solver loop as a device runs it: a system trace (jit/loop_ir.h) cut into steps, each a
// kernel over independent units (one component, one row, one lane of a chunk) or a single
// thread's scalar work, launched one after another with nothing read back between them. The
// program's scalars live in the device's context array, so a CG iteration's alpha, beta and
// r'r never leave the device; the while loop's condition sets a stop word that every later
// step of the loop reads, so a host that launches several iterations at once runs exactly
// the interpreter's number of them.
//
// The blocked sums of the contract (docs/arithmetic.md, "Sums") are three steps: Lanes (one
// unit per chunk and lane: the lane's elements in increasing order, from +0.0), Tree (one
// unit per chunk: the halving tree over its 32 lanes) and Combine (one thread: the sum's
// value so far plus the chunks' partials in chunk order). No unit reads what another unit of
// its step writes, so a step's units may run in any order, on any number of threads, and
// give the bits of the CPU's kernel.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "jit/loop_ir.h"

namespace simit::jit {

// The context array (int64 words) every step reads: pointers to the arrays' table (device
// addresses, one per ArraySlot), to the sizes, to the lane accumulators and to the chunk
// partials; the stop word (nonzero once the loop's condition failed); the error word (1 +
// the index in SystemTrace::errors of the error statement reached, or 0); then the locals,
// one word each (a local's value stored in its own type at the word's address).
enum ContextWord : int { kCtxArrays, kCtxSizes, kCtxLanes, kCtxPartials, kCtxStop, kCtxError };
inline constexpr int kContextHead = 6;

struct DeviceStep {
  enum class Kind : uint8_t {
    // One thread: its `parts` one after another (neighbouring one-thread work shares a
    // launch); the parts are of the three kinds below.
    Thread,
    Serial,     // a scalar op's statements
    Condition,  // the while condition; false sets the stop word, and the parts after it
                // (the next iteration's) do not run
    Combine,    // each sum plus its chunks' partials, in chunk order
    Each,       // a unit per component: a pass without sums
    Rows,       // a unit per row block: a product without sums (and its fused body)
    Lanes,      // a unit per (chunk, lane): a pass or product with sums, each lane's part
    Tree,       // a unit per chunk: the halving tree over the chunk's lanes
  };
  Kind kind = Kind::Serial;
  const VectorOp* op = nullptr;   // the op it runs (null for the condition and a Thread)
  bool in_loop = false;           // skipped once the stop word is set
  int size = -1;                  // the sizes entry its elements come from
  int group = 1;                  // components per element (a pass's runs); 1 for rows
  int sums = 0;                   // the op's sums (Lanes, Tree, Combine)
  std::vector<DeviceStep> parts;  // a Thread's
};

// The loop is rotated so that the condition shares a launch with the one-thread work around
// it: `before` ends with the first condition and the body's leading one-thread steps (when
// they set only temporaries, so that an interrupt between two batches still finds whole
// iterations), and `loop` is the rest of the body, the condition, and those leading steps
// again, for the next iteration.
struct DeviceProgram {
  std::vector<DeviceStep> before, loop, after;
  bool has_loop = false;
  int locals = 0;
  int scalars = 0;  // the first locals: the program's scalars, in and out
  std::vector<Ty> local_types;
  // Words of the context array.
  int context_words() const { return kContextHead + locals; }
  // Units of `step` for these sizes (a kernel's threads).
  int64_t units(const DeviceStep& step, const std::vector<int64_t>& sizes) const;
  // Doubles the lane accumulators and the chunk partials need for these sizes (at least 1).
  int64_t lane_doubles(const std::vector<int64_t>& sizes) const;
  int64_t partial_doubles(const std::vector<int64_t>& sizes) const;
  // Every step, before then loop then after: a step's index in this order names its kernel.
  std::vector<const DeviceStep*> all() const;
};

// Why the trace does not run as a device program, or "": a pass or product that checks,
// decomposes or sets a program scalar (its units could not run apart), or a scalar op that
// calls the runtime.
std::string device_refusal(const SystemTrace& t);
// The steps of a trace device_refusal accepts. The steps point into `t`'s ops.
DeviceProgram plan_device_program(const SystemTrace& t);
// The same with its steps' ops null, for a kernel to keep (the trace may go first).
std::shared_ptr<const DeviceProgram> detached_device_program(const SystemTrace& t);
// The name of step `index`'s kernel in a module whose kernels share `prefix`.
std::string device_step_name(const std::string& prefix, size_t index);

}  // namespace simit::jit
