// Executors: how a compiled map kernel's elements are split into kernel calls, in which
// order and on which threads. The controller marshals a site's arguments once and hands the
// kernel to its executor; no caller holds a function pointer. Every executor leaves the
// results the serial one leaves, bit for bit (docs/arithmetic.md).
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "jit/target.h"

namespace simit::runtime {
class SystemMatrix;
}

namespace simit::jit {

class DeferredPlan;

// What a map kernel's run came to: code 0, or 1 + the index of the failed check in
// Trace::errors with `element` the lowest element whose check failed.
struct MapOutcome {
  int32_t code = 0;
  int32_t element = -1;
  bool interrupted = false;  // stopped between two chunks for the interrupt flag
};

// How the kernel's writes relate across elements, as its trace says.
enum class MapWrites {
  Disjoint,  // each element writes only its own blocks and fields: any chunk order gives the
             // same bits
  Shared,    // elements add into shared blocks (assembly): element order decides the bits
  // Elements add into shared blocks, but the kernel reads where each element's blocks go
  // from tables built for chunks of exactly the `chunk` elements it is run with: a block's
  // first chunk adds in place, later chunks' contributions go to scratch blocks added in
  // element order after the run (jit/defer_assembly.h). Chunks may run in any order.
  Deferred,
};

class Executor {
 public:
  virtual ~Executor() = default;
  virtual const char* name() const = 0;
  // Whether chunks run apart from one another (on threads, or shuffled), so that a kernel
  // that assembles is worth compiling with deferred writes.
  virtual bool parallel() const { return false; }
  // The chunk of a map over n elements (a deferred assembly's tables are built for it).
  virtual int32_t chunk_for(int32_t n) const;
  // Runs `kernel` over the elements [0, n) in chunks of `chunk` elements. `interrupt`, when
  // set, is asked between two chunks whether to stop there.
  virtual MapOutcome run_map(const Kernel& kernel, const MapArgs& args, int32_t n, int32_t chunk,
                             MapWrites writes, const std::function<bool()>& interrupt) = 0;
  // A system kernel runs in one call (its loops over sets are inside it).
  virtual int32_t run_system(const Kernel& kernel, const SystemArgs& args) {
    return kernel.run(args);
  }
  // task(i) for every i in [0, tasks), on the executor's threads where it has some; the
  // tasks must write apart (a deferred assembly's additions, block by block).
  virtual void for_each(int64_t tasks, const std::function<void(int64_t)>& task) {
    for (int64_t i = 0; i < tasks; ++i) task(i);
  }
  // After a run_map with MapWrites::Deferred that succeeded, before the results are read:
  // each deferred block of `plan` added to its block, in element order (DeferredPlan::finish).
  // `values`: per result its values (null for results not assembled). Here: the plan's finish
  // on the host, its tasks through for_each; an executor whose memory is elsewhere adds them
  // there.
  virtual void finish_deferred(const DeferredPlan& plan, const std::vector<double*>& values);
  // `b = alpha a + beta b` in b's storage, with runtime::add_into's bits (a fused matrix sum,
  // jit/matrix_sum.h), where this executor's memory holds b's newest values: true when it
  // ran there; false leaves it to the host (here, always).
  virtual bool add_into(const runtime::SystemMatrix& a, double alpha, runtime::SystemMatrix& b,
                        double beta, bool float32) {
    (void)a, (void)alpha, (void)b, (void)beta, (void)float32;
    return false;
  }
};

// Whether the elements of a map kernel write apart (fields and results at their own index
// only) or add into shared blocks.
MapWrites writes_of(const Trace& trace);

// The chunks in element order on the calling thread.
std::unique_ptr<Executor> make_serial_executor();
// For the tests of the seam: a map whose writes are disjoint runs in chunks of `chunk`
// elements (small, so that the corpus's small sets have several) in an order shuffled by
// `seed`; a map that adds into shared blocks runs its chunks in element order, which its bits
// depend on. A failure is the one of the lowest element, as the serial executor reports it.
std::unique_ptr<Executor> make_shuffled_executor(uint64_t seed, int32_t chunk);
// Map chunks on a pool of `threads` threads (the caller among them); a map that adds into
// shared blocks without deferred writes runs serially. A failure is the lowest element's:
// once one chunk fails, the chunks above it are skipped and those below still run. Ctrl-C
// stops every thread at its next chunk.
// `min_chunk` (0: kMinThreadChunk) is for the tests, whose sets are small.
std::unique_ptr<Executor> make_threaded_executor(int threads, int32_t min_chunk = 0);

}  // namespace simit::jit
