// Fused matrix sums left pending (jit/fused_sum_run.cpp): under --float32, `A = M - s * K` in
// K's storage is not written by a pass of its own. K's values are marked as held here
// (runtime/residency.h); a solver loop's binary32 copy of A sums each block as it copies it
// (PrunedMatrix::assign), and anything else that reads A's values first has the sum written
// into them, so every reader sees what the eager sum would have left.
#pragma once

#include <memory>
#include <mutex>
#include <unordered_map>

#include "runtime/lazy_sum.h"
#include "runtime/residency.h"

namespace simit::jit {

class PendingSums final : public runtime::residency::Holder {
 public:
  PendingSums() = default;
  // What is pending is written first: a matrix may outlive the engine (the API's values).
  ~PendingSums() override;
  PendingSums(const PendingSums&) = delete;
  PendingSums& operator=(const PendingSums&) = delete;

  // `host` (b's values, home now) holds `sum` from here on, until it is read or freed.
  void hold(double* host, runtime::LazySum sum);
  // The sum pending in the values at `host`, or null when they hold their values.
  const runtime::LazySum* find(const void* host) const;
  // How many sums were left pending, and how many of them a host read then wrote.
  long held() const { return held_; }
  long written() const { return written_; }

  void bring_back(void* host) override;
  void released(const void* host) noexcept override;

 private:
  std::unique_ptr<runtime::LazySum> take(const void* host) noexcept;

  mutable std::mutex lock_;
  std::unordered_map<const void*, std::unique_ptr<runtime::LazySum>> sums_;
  long held_ = 0, written_ = 0;
};

}  // namespace simit::jit
