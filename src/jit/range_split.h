// How a solver loop's pass is shared among threads: one contiguous range of units per thread,
// its bounds learnt from the times of the pass's earlier calls. The same rows in one range
// cost different times on different cores (rows of different lengths; rows whose vector
// entries the other core wrote last and must send over), so equal shares of units leave one
// thread waiting; each call's times move the bounds towards equal times. Which thread computes
// which unit never changes a result (docs/arithmetic.md: a unit's partial is its own).
#pragma once

#include <cstdint>
#include <vector>

namespace simit::jit {

class RangeSplit {
 public:
  // The bounds of `parts` ranges over `units` units: parts + 1 entries, from 0 to `units`,
  // ascending (a range may be empty). Equal shares until times are recorded, and again when
  // the units change.
  const std::vector<int64_t>& bounds(int64_t units, int parts);
  // Where the caller puts the time range k of the last bounds took, for each k (any unit of
  // time, the same for all), and record() then reads them.
  double* times() { return times_.data(); }
  void record();

 private:
  // Each unit's estimated cost: the time of its range over its length, averaged over calls.
  std::vector<double> cost_;
  std::vector<int64_t> bounds_;
  std::vector<double> times_;
  bool timed_ = false;
};

}  // namespace simit::jit
