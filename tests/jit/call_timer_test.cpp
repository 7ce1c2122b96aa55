// --jit-stats' timing of a call (jit/controller_state.h, CallTimer): a trace whose calls are
// short counts their wall time as CPU time, without the system call that reads the CPU time;
// a trace whose calls are long (and its first call) reads the thread's CPU time.
#include <gtest/gtest.h>

#include <chrono>

#include "jit/controller_state.h"

namespace simit::jit {
namespace {

// Busy for `ms` of wall time (CPU time too, on an idle core).
void spin(double ms) {
  const auto until =
      std::chrono::steady_clock::now() + std::chrono::duration<double, std::milli>(ms);
  while (std::chrono::steady_clock::now() < until) {
  }
}

TEST(CallTimer, ShortCallsCountTheirWallTimeAsCpuTime) {
  TraceStats s;
  s.calls = 100;
  s.run_ms = 1.0;  // 0.01 ms a call
  s.cpu_ms = 1.0;
  CallTimer timer(s);
  spin(0.05);
  timer.done();
  EXPECT_EQ(s.calls, 101);
  EXPECT_GE(s.run_ms, 1.05);
  EXPECT_EQ(s.cpu_ms, s.run_ms);  // the same wall time, added to both
}

TEST(CallTimer, LongCallsAndTheFirstReadTheThreadsCpuTime) {
  for (long calls : {0L, 10L}) {
    TraceStats s;
    s.calls = calls;
    s.run_ms = 5.0 * static_cast<double>(calls);  // 5 ms a call
    CallTimer timer(s);
    spin(20.0);
    timer.done();
    const double wall = s.run_ms - 5.0 * static_cast<double>(calls);
    EXPECT_GE(wall, 20.0);
    // CPU time: the spin's, read from the thread's clock (its resolution, and a busy machine
    // taking the core away, keep it from equalling the wall time to the bit).
    EXPECT_GT(s.cpu_ms, 0.0);
    EXPECT_LE(s.cpu_ms, wall + 1.0);
    EXPECT_NE(s.cpu_ms, wall) << "read from the thread's CPU clock, not the wall clock";
  }
}

}  // namespace
}  // namespace simit::jit
