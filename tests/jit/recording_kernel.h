// A map kernel for the executors' tests: it records the ranges it is asked to run (from any
// thread) and fails at chosen elements, as a compiled check would.
#pragma once

#include <algorithm>
#include <mutex>
#include <vector>

#include "jit/target.h"

namespace simit::jit {

class RecordingKernel : public Kernel {
 public:
  mutable std::mutex mutex;
  mutable std::vector<ElementRange> ranges;
  std::vector<int32_t> failing;  // elements whose check fails (error 0)
  int32_t run(const MapArgs&, ElementRange r, int32_t* failed) const override {
    {
      std::lock_guard lock(mutex);
      ranges.push_back(r);
    }
    for (int32_t e = r.begin; e < r.end; ++e)
      if (std::find(failing.begin(), failing.end(), e) != failing.end()) {
        *failed = e;
        return 1;
      }
    return 0;
  }
  int32_t run(const SystemArgs&) const override { return 0; }
};

}  // namespace simit::jit
