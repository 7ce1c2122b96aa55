// A pass's ranges learnt from its times (jit/range_split.h).
#include "jit/range_split.h"

#include <algorithm>

namespace simit::jit {

namespace {

// The weight of a call's times in a unit's cost: enough to follow a change within a few
// calls, little enough that one call slowed by something else (another process on the core)
// moves the bounds only a little.
constexpr double kRate = 0.25;

}  // namespace

const std::vector<int64_t>& RangeSplit::bounds(int64_t units, int parts) {
  if (static_cast<int64_t>(cost_.size()) != units) {
    cost_.assign(static_cast<size_t>(units), 1.0);
    timed_ = false;
  }
  bounds_.assign(static_cast<size_t>(parts) + 1, units);
  times_.assign(static_cast<size_t>(parts), 0.0);
  bounds_[0] = 0;
  double total = 0;
  for (double c : cost_) total += c;
  // Bound k: the first unit at which the costs before it reach k / parts of the total.
  double before = 0;
  int64_t u = 0;
  for (int k = 1; k < parts; ++k) {
    const double goal = total * k / parts;
    while (u < units && before + cost_[static_cast<size_t>(u)] / 2 < goal)
      before += cost_[static_cast<size_t>(u++)];
    bounds_[static_cast<size_t>(k)] = u;
  }
  return bounds_;
}

void RangeSplit::record() {
  const double* times = times_.data();
  const size_t parts = bounds_.size() - 1;
  for (size_t k = 0; k < parts; ++k) {
    const int64_t first = bounds_[k], end = bounds_[k + 1];
    if (first >= end) continue;
    const double per_unit = std::max(times[k], 0.0) / static_cast<double>(end - first);
    for (int64_t u = first; u < end; ++u) {
      double& c = cost_[static_cast<size_t>(u)];
      c = timed_ ? c + kRate * (per_unit - c) : per_unit;
    }
  }
  // A range that took no measurable time leaves costs of 0, which would send every unit
  // to it: each unit costs at least a millionth of the mean.
  double total = 0;
  for (double c : cost_) total += c;
  const double least = total / static_cast<double>(std::max<size_t>(cost_.size(), 1)) * 1e-6;
  for (double& c : cost_) c = std::max(c, least > 0 ? least : 1e-12);
  timed_ = true;
}

}  // namespace simit::jit
