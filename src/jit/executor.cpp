// The serial executor and the test-only shuffled one (jit/executor.h).
#include "jit/executor.h"

#include <algorithm>
#include <numeric>
#include <random>
#include <vector>

namespace simit::jit {

namespace {

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
  MapOutcome run_map(const Kernel& kernel, const MapArgs& args, int32_t n, int32_t chunk,
                     MapWrites writes, const std::function<bool()>& interrupt) override {
    if (writes == MapWrites::Shared)
      return serial_.run_map(kernel, args, n, chunk, writes, interrupt);
    chunk = chunk_;
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

}  // namespace simit::jit
