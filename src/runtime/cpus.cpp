// The CPUs this process may run on (runtime/cpus.h).
#include "runtime/cpus.h"

#include <algorithm>
#include <cerrno>
#include <thread>

#if defined(__linux__)
#include <sched.h>
#endif

namespace simit::runtime {

int usable_cpus() {
#if defined(__linux__)
  // The mask is read into a set sized for `cpus` CPUs, grown while the kernel's is larger
  // (EINVAL): a fixed cpu_set_t holds 1024 only.
  for (int cpus = 1024; cpus <= (1 << 20); cpus *= 2) {
    cpu_set_t* set = CPU_ALLOC(cpus);
    if (!set) break;
    const size_t size = CPU_ALLOC_SIZE(cpus);
    const int got = sched_getaffinity(0, size, set);
    const int why = errno;
    const int n = got == 0 ? CPU_COUNT_S(size, set) : 0;
    CPU_FREE(set);
    if (got == 0 && n > 0) return n;
    if (got == 0 || why != EINVAL) break;
  }
#endif
  return std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
}

}  // namespace simit::runtime
