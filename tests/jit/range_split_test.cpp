// A solver loop pass's ranges learnt from its times (jit/range_split.h): equal shares at
// first, then bounds that give each range an equal share of the estimated cost.
#include "jit/range_split.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

namespace simit::jit {
namespace {

TEST(RangeSplit, StartsEvenAndMovesTheBoundsTowardsEqualTimes) {
  RangeSplit split;
  EXPECT_EQ(split.bounds(15, 2), (std::vector<int64_t>{0, 7, 15}));
  EXPECT_EQ(split.bounds(2, 2), (std::vector<int64_t>{0, 1, 2}));
  EXPECT_EQ(split.bounds(12, 3), (std::vector<int64_t>{0, 4, 8, 12}));
  // Units 0-3 cost 3 each and 4-11 cost 1 (total 20): range 0 (4 units) took 12, range 1
  // (4 units) 4 and range 2 4. Then each unit costs its own, and a bound falls where the
  // costs before it come nearest a third of 20 (6.67: 6, after units 0 and 1) and two thirds
  // (13.33: 13, after units 0 to 4).
  double* t = split.times();
  t[0] = 12, t[1] = 4, t[2] = 4;
  split.record();
  EXPECT_EQ(split.bounds(12, 3), (std::vector<int64_t>{0, 2, 5, 12}));
  // The same times again, now of ranges of 2, 3 and 7 units: a unit's cost moves a quarter
  // of the way to its range's time per unit, and the bounds follow.
  for (int call = 0; call < 40; ++call) {
    const std::vector<int64_t> b = split.bounds(12, 3);
    double* times = split.times();
    for (int k = 0; k < 3; ++k) {
      times[k] = 0;
      for (int64_t u = b[k]; u < b[k + 1]; ++u) times[k] += u < 4 ? 3.0 : 1.0;
    }
    split.record();
  }
  EXPECT_EQ(split.bounds(12, 3), (std::vector<int64_t>{0, 2, 5, 12}));
  // New units: equal shares again.
  EXPECT_EQ(split.bounds(10, 2), (std::vector<int64_t>{0, 5, 10}));
  // Ranges that took no time leave every unit a cost: still ascending bounds over all.
  double* z = split.times();
  z[0] = 0, z[1] = 0;
  split.record();
  EXPECT_EQ(split.bounds(10, 2), (std::vector<int64_t>{0, 5, 10}));
  // More parts than units: empty ranges at the end.
  EXPECT_EQ(split.bounds(2, 4).front(), 0);
  EXPECT_EQ(split.bounds(2, 4).back(), 2);
}

}  // namespace
}  // namespace simit::jit
