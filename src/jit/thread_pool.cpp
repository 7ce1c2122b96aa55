// The engine's worker threads (jit/thread_pool.h). A job is short (one map over a set, one
// pass of a solver loop: tens of microseconds to milliseconds), so a worker spins a little
// on the job counter before it sleeps: waking a sleeping thread costs about as much as a
// small pass.
#include "jit/thread_pool.h"

#include <algorithm>

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#endif

namespace simit::jit {

namespace {
// Polls of the job counter before a worker sleeps (about 100 microseconds).
constexpr int kSpins = 4000;

void relax() {
#if defined(__x86_64__) || defined(__i386__)
  _mm_pause();
#else
  std::this_thread::yield();
#endif
}
}  // namespace

ThreadPool::ThreadPool(int threads) {
  for (int i = 1; i < threads; ++i) workers_.emplace_back([this] { work(); });
}

ThreadPool::~ThreadPool() {
  {
    std::lock_guard lock(mutex_);
    stop_ = true;
    published_.store(generation_ + 1, std::memory_order_release);
  }
  wake_.notify_all();
  for (std::thread& t : workers_) t.join();
}

void ThreadPool::claim(const std::function<void(int64_t)>& task, int64_t tasks) {
  for (int64_t i; (i = next_.fetch_add(1, std::memory_order_relaxed)) < tasks;) task(i);
}

void ThreadPool::run(int64_t tasks, const std::function<void(int64_t)>& task) {
  if (tasks <= 0) return;
  if (workers_.empty() || tasks == 1) {
    for (int64_t i = 0; i < tasks; ++i) task(i);
    return;
  }
  {
    std::lock_guard lock(mutex_);
    task_ = &task;
    tasks_ = tasks;
    next_.store(0, std::memory_order_relaxed);
    ++generation_;
    published_.store(generation_, std::memory_order_release);
  }
  wake_.notify_all();
  claim(task, tasks);
  // Every task is claimed; wait for the workers still inside one.
  std::unique_lock lock(mutex_);
  done_.wait(lock, [this] { return busy_ == 0; });
  task_ = nullptr;
}

void ThreadPool::work() {
  uint64_t seen = 0;
  for (;;) {
    for (int i = 0; i < kSpins && published_.load(std::memory_order_acquire) == seen; ++i) relax();
    std::unique_lock lock(mutex_);
    wake_.wait(lock, [&] { return stop_ || generation_ != seen; });
    if (stop_) return;
    seen = generation_;
    const std::function<void(int64_t)>* task = task_;
    const int64_t tasks = tasks_;
    if (!task) continue;  // the job finished before this worker woke
    ++busy_;
    lock.unlock();
    claim(*task, tasks);
    lock.lock();
    if (--busy_ == 0) done_.notify_all();
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
