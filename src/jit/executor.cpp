// The serial, threaded and test-only shuffled executors (jit/executor.h).
#include "jit/executor.h"

#include <algorithm>
#include <atomic>
#include <climits>
#include <numeric>
#include <random>
#include <vector>

#include "jit/deferred_plan.h"
#include "jit/thread_pool.h"
#include "jit/tunables.h"

namespace simit::jit {

int32_t Executor::chunk_for(int32_t) const { return kChunkElements; }

void Executor::finish_deferred(const DeferredPlan& plan, const std::vector<double*>& values) {
  plan.finish(values, [this](int64_t tasks, const std::function<void(int64_t)>& task) {
    for_each(tasks, task);
  });
}

namespace {

// The lowest failure among chunks that ran apart: per chunk its code and element.
MapOutcome lowest_failure(const std::vector<std::pair<int32_t, int32_t>>& failures) {
  MapOutcome out;
  for (const auto& [code, element] : failures)
    if (code != 0 && (out.code == 0 || element < out.element)) {
      out.code = code;
      out.element = element;
    }
  return out;
}

class SerialExecutor : public Executor {
 public:
  const char* name() const override { return "serial"; }
  MapOutcome run_map(const Kernel& kernel, const MapArgs& args, int32_t n, int32_t chunk, MapWrites,
                     const std::function<bool()>& interrupt) override {
    MapOutcome out;
    for (int32_t begin = 0; begin < n; begin += chunk) {
      const int32_t end = std::min(n, begin + chunk);
      out.code = kernel.run(args, {begin, end}, &out.element);
      if (out.code != 0) return out;
      if (end < n && interrupt && interrupt()) {
        out.interrupted = true;
        return out;
      }
    }
    return out;
  }
};

class ShuffledExecutor : public Executor {
 public:
  ShuffledExecutor(uint64_t seed, int32_t chunk) : rng_(seed), chunk_(chunk > 0 ? chunk : 1) {}
  const char* name() const override { return "shuffled"; }
  bool parallel() const override { return true; }
  int32_t chunk_for(int32_t) const override { return chunk_; }
  MapOutcome run_map(const Kernel& kernel, const MapArgs& args, int32_t n, int32_t chunk,
                     MapWrites writes, const std::function<bool()>& interrupt) override {
    if (writes == MapWrites::Shared)
      return serial_.run_map(kernel, args, n, chunk, writes, interrupt);
    const int32_t chunks = n <= 0 ? 0 : (n - 1) / chunk + 1;
    std::vector<int32_t> order(static_cast<size_t>(chunks));
    std::iota(order.begin(), order.end(), 0);
    std::shuffle(order.begin(), order.end(), rng_);
    MapOutcome out;
    for (size_t i = 0; i < order.size(); ++i) {
      const int32_t begin = order[i] * chunk, end = std::min(n, begin + chunk);
      int32_t element = -1;
      const int32_t code = kernel.run(args, {begin, end}, &element);
      // The serial executor stops at the first failing element; every chunk runs here, and
      // the failure of the lowest element is the one reported.
      if (code != 0 && (out.code == 0 || element < out.element)) {
        out.code = code;
        out.element = element;
      }
      if (out.code == 0 && i + 1 < order.size() && interrupt && interrupt()) {
        out.interrupted = true;
        return out;
      }
    }
    return out;
  }

 private:
  std::mt19937_64 rng_;
  int32_t chunk_;
  SerialExecutor serial_;
};

class ThreadedExecutor : public Executor {
 public:
  ThreadedExecutor(int threads, int32_t min_chunk)
      : pool_(threads), min_chunk_(min_chunk > 0 ? min_chunk : kMinThreadChunk) {}
  const char* name() const override { return "threads"; }
  bool parallel() const override { return true; }
  // One chunk per thread, its home share (jit/thread_pool.h), up to kChunkElements: every
  // block shared between two chunks costs a deferred addition, and on the bunny's 19,000
  // springs four chunks a thread deferred a third of the contributions and cost more than
  // the second thread saved (a thread that finishes early still takes a chunk not started).
  int32_t chunk_for(int32_t n) const override {
    const int64_t per = (static_cast<int64_t>(n) + pool_.threads() - 1) / pool_.threads();
    const int64_t c = std::clamp<int64_t>(per, min_chunk_, kChunkElements);
    return min_chunk_ < kMinThreadChunk
               ? static_cast<int32_t>(c)
               : static_cast<int32_t>((c + kLanes32 - 1) / kLanes32 * kLanes32);
  }
  int32_t run_system(const Kernel& kernel, const SystemArgs& args) override {
    SystemArgs on_pool = args;
    on_pool.pool = &pool_;
    return kernel.run(on_pool);
  }
  void for_each(int64_t tasks, const std::function<void(int64_t)>& task) override {
    if (tasks <= 1 || pool_.threads() == 1) return Executor::for_each(tasks, task);
    pool_.run(tasks, task);
  }
  MapOutcome run_map(const Kernel& kernel, const MapArgs& args, int32_t n, int32_t chunk,
                     MapWrites writes, const std::function<bool()>& interrupt) override {
    const int32_t chunks = n <= 0 ? 0 : (n - 1) / chunk + 1;
    if (writes == MapWrites::Shared || chunks <= 1 || pool_.threads() == 1)
      return serial_.run_map(kernel, args, n, chunk, writes, interrupt);
    std::vector<std::pair<int32_t, int32_t>> failures(static_cast<size_t>(chunks), {0, -1});
    std::atomic<int32_t> lowest{INT32_MAX};  // the lowest element that failed so far
    std::atomic<bool> stopped{false};        // an interrupt was seen
    pool_.run(chunks, [&](int64_t k) {
      const int32_t begin = static_cast<int32_t>(k) * chunk, end = std::min(n, begin + chunk);
      // Chunks above a failure cannot hold the lowest one; the chunks below still run.
      if (stopped.load(std::memory_order_relaxed) || begin > lowest.load(std::memory_order_relaxed))
        return;
      if (interrupt && interrupt()) {
        stopped.store(true, std::memory_order_relaxed);
        return;
      }
      int32_t element = -1;
      const int32_t code = kernel.run(args, {begin, end}, &element);
      if (code == 0) return;
      failures[static_cast<size_t>(k)] = {code, element};
      int32_t seen = lowest.load(std::memory_order_relaxed);
      while (element < seen && !lowest.compare_exchange_weak(seen, element)) {
      }
    });
    MapOutcome out = lowest_failure(failures);
    out.interrupted = out.code == 0 && stopped.load();
    return out;
  }

 private:
  ThreadPool pool_;
  int32_t min_chunk_;
  SerialExecutor serial_;
};

bool at_element(const ExprRef& index) { return index && index->kind == ExprKind::Element; }

bool disjoint(const std::vector<Stmt>& body) {
  for (const Stmt& s : body) {
    if (s.kind == StmtKind::Assemble && (s.pair >= 0 || !at_element(s.index))) return false;
    if (s.kind == StmtKind::Store && !at_element(s.index)) return false;
    if (!disjoint(s.body) || !disjoint(s.orelse)) return false;
  }
  return true;
}

}  // namespace

MapWrites writes_of(const Trace& trace) {
  return disjoint(trace.body) ? MapWrites::Disjoint : MapWrites::Shared;
}

std::unique_ptr<Executor> make_serial_executor() { return std::make_unique<SerialExecutor>(); }

std::unique_ptr<Executor> make_shuffled_executor(uint64_t seed, int32_t chunk) {
  return std::make_unique<ShuffledExecutor>(seed, chunk);
}

std::unique_ptr<Executor> make_threaded_executor(int threads, int32_t min_chunk) {
  return std::make_unique<ThreadedExecutor>(threads, min_chunk);
}

}  // namespace simit::jit
