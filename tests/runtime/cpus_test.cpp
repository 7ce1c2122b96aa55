// The CPUs this process may run on (runtime/cpus.h): the affinity mask, which a thread
// narrowed to one CPU sees as one.
#include <gtest/gtest.h>

#include <thread>

#if defined(__linux__)
#include <sched.h>
#endif

#include "runtime/cpus.h"

namespace simit::runtime {
namespace {

TEST(UsableCpus, CountsTheAffinityMask) {
  const int all = usable_cpus();
  EXPECT_GE(all, 1);
#if defined(__linux__)
  cpu_set_t mine;
  CPU_ZERO(&mine);
  ASSERT_EQ(sched_getaffinity(0, sizeof mine, &mine), 0);
  if (CPU_COUNT(&mine) > 0 && CPU_COUNT(&mine) < CPU_SETSIZE) {
    EXPECT_EQ(all, CPU_COUNT(&mine));
  }
  // A thread allowed on one CPU only (the first this process may use).
  int first = 0;
  while (first < CPU_SETSIZE && !CPU_ISSET(first, &mine)) ++first;
  ASSERT_LT(first, CPU_SETSIZE);
  int seen = 0;
  std::thread t([&] {
    cpu_set_t one;
    CPU_ZERO(&one);
    CPU_SET(first, &one);
    if (sched_setaffinity(0, sizeof one, &one) == 0) seen = usable_cpus();
  });
  t.join();
  EXPECT_EQ(seen, 1);
#endif
}

}  // namespace
}  // namespace simit::runtime
