// The bytes a compiled solver loop moves: each pass and product reads and writes whole
// arrays, so one iteration's traffic follows from the arrays its ops touch and their sizes
// (`--jit-stats`: "an iteration moves N MB", and the rate the calls reached).
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "jit/loop_ir.h"

namespace simit::jit {

struct LoopTraffic {
  int64_t before = 0, per_iteration = 0, after = 0;  // bytes read plus bytes written
  int64_t matrices = 0;  // of per_iteration: the products' matrices (values, columns, rows)
};

// Which arrays a trace's ops move, by slot (counted once per read and once per write), for
// sizes that change from call to call: made once per trace, summed per call.
struct TrafficPlan {
  struct Section {
    std::vector<int> matrices, vectors;
  };
  Section before, body, after;
  LoopTraffic bytes(std::span<const size_t> array_bytes) const;
};

// Counted as STREAM counts: every array an op reads once, every array it writes once more
// (no write-allocate traffic); a product's vector once (its components are reused from the
// cache across the rows that read them). `array_bytes` holds each array slot's size in bytes
// as the call binds it.
TrafficPlan plan_traffic(const SystemTrace& t);
LoopTraffic loop_traffic(const SystemTrace& t, std::span<const size_t> array_bytes);

// A loop's calls, for --jit-stats: those whose kernel counted the iterations it ran (a device
// program does not) add their bytes and their kernel's time.
struct TrafficCount {
  LoopTraffic last;  // the last counted call's
  int64_t iterations = 0, bytes = 0;
  double ms = 0.0;
  void add(const LoopTraffic& t, int64_t call_iterations, double kernel_ms);
  // "; an iteration moves 13.1 MB (its matrices 12.0 MB); 2000 iterations at 32.4 GB/s", or
  // "" before a counted call.
  std::string note() const;
};

}  // namespace simit::jit
