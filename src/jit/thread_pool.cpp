// The engine's worker threads (jit/thread_pool.h). A job is short (one map over a set, one
// pass of a solver loop: a few microseconds to milliseconds), so handing one out is a store
// and a claim is a compare-and-swap, without a lock; a worker spins a while on the job word
// before it sleeps, and the caller spins until the last task returns.
#include "jit/thread_pool.h"

#include <algorithm>
#include <chrono>

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#endif

namespace simit::jit {

namespace {

// How long a worker polls the job word before it sleeps, and the caller polls for the last
// task before it yields: waking a sleeping thread takes tens of microseconds, as long as a
// solver loop's pass, so a worker that slept between two passes would never take part.
// (Measured in time: a pause instruction takes 3 to 140 cycles, by processor.)
constexpr auto kSpinFor = std::chrono::microseconds(500);
constexpr int kPausesPerClockRead = 64;

void relax() {
#if defined(__x86_64__) || defined(__i386__)
  _mm_pause();
#else
  std::this_thread::yield();
#endif
}

constexpr uint64_t kLeft = 0xffffffffu;  // the low half of the job word: tasks not yet claimed

}  // namespace

ThreadPool::ThreadPool(int threads) {
  for (int i = 1; i < threads; ++i) workers_.emplace_back([this] { work(); });
}

ThreadPool::~ThreadPool() {
  {
    std::lock_guard lock(mutex_);
    stop_.store(true);
  }
  wake_.notify_all();
  for (std::thread& t : workers_) t.join();
}

void ThreadPool::claim() {
  uint64_t w = work_.load(std::memory_order_acquire);
  while ((w & kLeft) != 0) {
    if (!work_.compare_exchange_weak(w, w - 1, std::memory_order_acq_rel)) continue;
    // The claim succeeded, so the job is still running and task_ and tasks_ are its own.
    const auto i = tasks_ - static_cast<int64_t>(w & kLeft);
    task_.call(task_.object, i);
    finished_.fetch_add(1, std::memory_order_acq_rel);
    w = work_.load(std::memory_order_acquire);
  }
}

void ThreadPool::run(int64_t tasks, Task task) {
  if (tasks <= 0) return;
  if (workers_.empty() || tasks == 1) {
    for (int64_t i = 0; i < tasks; ++i) task.call(task.object, i);
    return;
  }
  task_ = task;
  tasks_ = tasks;
  finished_.store(0, std::memory_order_relaxed);
  const uint64_t job = (work_.load(std::memory_order_relaxed) >> 32) + 1;
  work_.store((job << 32) | static_cast<uint64_t>(tasks), std::memory_order_seq_cst);
  // A worker that counted itself asleep after this load tests the job word after the store
  // above, and sees the job; one counted before it is woken (taking the lock first means it
  // is either waiting or about to test).
  if (sleepers_.load(std::memory_order_seq_cst) > 0) {
    { std::lock_guard lock(mutex_); }
    wake_.notify_all();
  }
  claim();
  const auto until = std::chrono::steady_clock::now() + kSpinFor;
  for (int spins = 1; finished_.load(std::memory_order_acquire) != tasks; ++spins) {
    relax();
    if (spins % kPausesPerClockRead == 0 && std::chrono::steady_clock::now() > until)
      std::this_thread::yield();
  }
}

void ThreadPool::work() {
  for (;;) {
    claim();
    const auto until = std::chrono::steady_clock::now() + kSpinFor;
    for (int spins = 1; (work_.load(std::memory_order_acquire) & kLeft) == 0; ++spins) {
      if (stop_.load(std::memory_order_relaxed)) return;
      relax();
      if (spins % kPausesPerClockRead == 0 && std::chrono::steady_clock::now() > until) break;
    }
    if ((work_.load(std::memory_order_acquire) & kLeft) != 0) continue;
    std::unique_lock lock(mutex_);
    sleepers_.fetch_add(1, std::memory_order_seq_cst);
    wake_.wait(lock, [this] {
      return stop_.load() || (work_.load(std::memory_order_seq_cst) & kLeft) != 0;
    });
    sleepers_.fetch_sub(1, std::memory_order_relaxed);
    if (stop_.load()) return;
  }
}

}  // namespace simit::jit

// A few ranges per thread, so that a thread that finishes early takes another.
extern "C" void simit_jit_parallel_for(void* pool, void (*op)(const int64_t*, int64_t, int64_t),
                                       const int64_t* context, int64_t units) {
  auto* p = static_cast<simit::jit::ThreadPool*>(pool);
  if (!p || p->threads() == 1 || units <= 1) {
    if (units > 0) op(context, 0, units);
    return;
  }
  const int64_t tasks = std::min<int64_t>(units, int64_t{4} * p->threads());
  p->run(tasks, [&](int64_t t) { op(context, t * units / tasks, (t + 1) * units / tasks); });
}
