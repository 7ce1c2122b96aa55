// The tables a deferred map kernel (jit/defer_assembly.h) runs with, built once per
// topology and chunk size and kept with the site's kernel, and the additions of the deferred
// blocks after a run.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "jit/loop_ir.h"
#include "runtime/set.h"
#include "runtime/system_matrix.h"

namespace simit::jit {

class DeferredPlan {
 public:
  // What one result of the call is: its pattern table (a matrix; null for a vector), the
  // pattern that owns it (kept alive, so its address names it), its blocks and components.
  struct Source {
    const int32_t* table = nullptr;
    runtime::PatternPtr pattern;
    int64_t blocks = 0;
    int components = 1;
  };

  // Tables for running `t` over `target` in chunks of `chunk` elements (split: true) or in
  // element order (split: false: every entry points at its block). False when chunks cannot
  // run apart on this topology (an element writes one block through two of its members): the
  // call then runs with split false, in order.
  bool prepare(const Trace& t, const runtime::Set& target, const std::vector<Source>& results,
               int32_t chunk, bool split);
  // For the array slots of a Table or a Deferred array of result `result`.
  const int32_t* table(int result) const;
  double* deferred(int result);
  // Their lengths: the table's entries and the deferred blocks' values.
  size_t table_entries(int result) const;
  size_t deferred_values(int result) const;
  // After a split run: each deferred block added to its block, in element order. `values`:
  // per result its values (null for results not assembled). The blocks are split into
  // tasks run through `for_each` (each task adds into its own blocks, each block's
  // contributions in element order: the bits do not depend on how the tasks run).
  void finish(
      const std::vector<double*>& values,
      const std::function<void(int64_t, const std::function<void(int64_t)>&)>& for_each = {}) const;
  // Deferred blocks of the last split prepared (for --jit-stats).
  int64_t deferred_blocks() const;

  // One result's gather index and deferred blocks, for an executor that adds them itself (a
  // GPU's, in device memory): `blocks` blocks have deferred blocks, block[i] (ascending) adds
  // deferred blocks k[start[i] .. start[i + 1]) (ascending: element order), each `components`
  // values of `deferred` (the array deferred(result) gives; deferred block 0, the sink, is
  // never listed). finish's contract: to[c] += from[c] for each k in turn, from the block's
  // value after the run.
  struct Gather {
    int result = -1;
    int components = 1;
    size_t blocks = 0;
    const int32_t* block = nullptr;  // `blocks` entries
    const int32_t* start = nullptr;  // `blocks` + 1 entries
    const int32_t* k = nullptr;      // start[blocks] entries
    const double* deferred = nullptr;
    size_t deferred_values = 0;
    bool round32 = false;  // --float32: each addition rounded to binary32
  };
  // Per result written, its gather index; empty unless the last prepare split the elements.
  std::vector<Gather> gathers() const;
  // Names the split tables (and gather index) in use: a value of its own each time they are
  // built, unique in the process, so a copy of them elsewhere knows when it is stale (a new
  // topology, chunk or result pattern). 0 before the first split.
  uint64_t build_id() const { return build_id_; }

 private:
  struct Result {
    int result = -1;
    bool vector = false;
    int components = 1;
    std::vector<int> written;  // the pairs (matrix) or members (vector) the trace writes
    int stride = 0;            // table entries per element
    const int32_t* source = nullptr;
    std::vector<int32_t> plain;  // a vector's member table
    std::vector<int32_t> split;  // the table with later chunks' entries sent to deferred blocks
    std::vector<int32_t> dest;   // per deferred block, its block (block 0: the sink, -1)
    // The gather index: the blocks that have deferred blocks, ascending, and for block
    // gather_block[i] its deferred blocks gather_k[gather_start[i] .. gather_start[i + 1]),
    // ascending (element order).
    std::vector<int32_t> gather_block, gather_start, gather_k;
    std::vector<double> scratch;
  };
  bool float32_ = false;  // the trace's: each addition of finish rounded to binary32
  bool build(Result& r, const runtime::Set& target, int64_t blocks);

  // What the tables were built for.
  uint64_t set_id_ = 0, set_version_ = 0;
  int32_t size_ = -1, chunk_ = 0;
  std::vector<runtime::PatternPtr> patterns_;
  std::vector<const int32_t*> sources_;
  bool built_split_ = false, split_ok_ = false, split_ = false;
  uint64_t build_id_ = 0;
  std::vector<Result> results_;
};

}  // namespace simit::jit
