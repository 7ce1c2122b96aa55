// The engine's worker threads (jit/thread_pool.h). A job is short (one map over a set, one
// pass of a solver loop: a few microseconds to milliseconds), so handing one out is a store
// per thread and a claim is a compare-and-swap, without a lock; a worker spins a while on the
// job number before it sleeps, and the caller spins until the last task returns.
#include "jit/thread_pool.h"

#include <algorithm>
#include <chrono>

#include "runtime/cpus.h"

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#endif

namespace simit::jit {

namespace {

// How long a worker polls the job number before it sleeps, and the caller polls for the last
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

// A range's word: job (32 bits), front (16), end (16).
constexpr uint64_t range_word(uint32_t job, uint64_t front, uint64_t end) {
  return uint64_t{job} << 32 | front << 16 | end;
}
constexpr uint32_t job_of(uint64_t w) { return static_cast<uint32_t>(w >> 32); }
constexpr uint64_t front_of(uint64_t w) { return (w >> 16) & 0xffff; }
constexpr uint64_t end_of(uint64_t w) { return w & 0xffff; }

}  // namespace

ThreadPool::ThreadPool(int threads, int cpus)
    : oversubscribed_(threads > (cpus > 0 ? cpus : runtime::usable_cpus())),
      ranges_(new Range[static_cast<size_t>(std::max(1, threads))]) {
  for (int i = 1; i < threads; ++i) workers_.emplace_back([this, i] { work(i); });
}

ThreadPool::~ThreadPool() {
  {
    std::lock_guard lock(mutex_);
    stop_.store(true);
  }
  wake_.notify_all();
  for (std::thread& t : workers_) t.join();
}

bool ThreadPool::claim_one(Range& range, uint32_t job, bool front) {
  uint64_t w = range.word.load(std::memory_order_acquire);
  for (;;) {
    if (job_of(w) != job || front_of(w) >= end_of(w)) return false;
    const uint64_t taken = front ? range_word(job, front_of(w) + 1, end_of(w))
                                 : range_word(job, front_of(w), end_of(w) - 1);
    if (range.word.compare_exchange_weak(w, taken, std::memory_order_acq_rel)) break;
  }
  // The claim succeeded, so the job is still running and task_ and first_ are its own.
  const auto i = static_cast<int64_t>(front ? front_of(w) : end_of(w) - 1);
  task_.call(task_.object, first_ + i);
  finished_.fetch_add(1, std::memory_order_acq_rel);
  return true;
}

void ThreadPool::claim(int self, uint32_t job) {
  const int threads = this->threads();
  while (claim_one(ranges_[static_cast<size_t>(self)], job, true)) {
  }
  for (int k = 1; k < threads; ++k)
    while (claim_one(ranges_[static_cast<size_t>((self + k) % threads)], job, false)) {
    }
}

void ThreadPool::run(int64_t tasks, Task task) {
  if (tasks <= 0) return;
  if (workers_.empty() || tasks == 1) {
    for (int64_t i = 0; i < tasks; ++i) task.call(task.object, i);
    return;
  }
  task_ = task;
  for (int64_t first = 0; first < tasks; first += kMaxJobTasks)
    run_job(first, std::min(kMaxJobTasks, tasks - first));
}

void ThreadPool::run_job(int64_t first, int64_t tasks) {
  first_ = first;
  finished_.store(0, std::memory_order_relaxed);
  const uint32_t job = job_.load(std::memory_order_relaxed) + 1;
  const int threads = this->threads();
  for (int t = 0; t < threads; ++t)
    ranges_[static_cast<size_t>(t)].word.store(
        range_word(job, static_cast<uint64_t>(t * tasks / threads),
                   static_cast<uint64_t>((t + 1) * tasks / threads)),
        std::memory_order_release);
  job_.store(job, std::memory_order_seq_cst);
  // A worker that counted itself asleep after this load tests the job number after the store
  // above, and sees the job; one counted before it is woken (taking the lock first means it
  // is either waiting or about to test).
  if (sleepers_.load(std::memory_order_seq_cst) > 0) {
    { std::lock_guard lock(mutex_); }
    wake_.notify_all();
  }
  claim(0, job);
  const auto until = std::chrono::steady_clock::now() + kSpinFor;
  for (int spins = 1; finished_.load(std::memory_order_acquire) != tasks; ++spins) {
    if (oversubscribed_) {
      std::this_thread::yield();  // a worker still running a task may need this core
      continue;
    }
    relax();
    if (spins % kPausesPerClockRead == 0 && std::chrono::steady_clock::now() > until)
      std::this_thread::yield();
  }
}

void ThreadPool::work(int self) {
  uint32_t seen = 0;
  for (;;) {
    uint32_t job = job_.load(std::memory_order_acquire);
    if (job != seen) {
      seen = job;
      claim(self, job);
    }
    const auto until = std::chrono::steady_clock::now() + kSpinFor;
    for (int spins = 1; job_.load(std::memory_order_acquire) == seen; ++spins) {
      if (stop_.load(std::memory_order_relaxed)) return;
      if (oversubscribed_)
        std::this_thread::yield();
      else
        relax();
      if (spins % kPausesPerClockRead == 0 && std::chrono::steady_clock::now() > until) break;
    }
    if (job_.load(std::memory_order_acquire) != seen) continue;
    std::unique_lock lock(mutex_);
    sleepers_.fetch_add(1, std::memory_order_seq_cst);
    wake_.wait(lock, [&] { return stop_.load() || job_.load(std::memory_order_seq_cst) != seen; });
    sleepers_.fetch_sub(1, std::memory_order_relaxed);
    if (stop_.load()) return;
  }
}

}  // namespace simit::jit

// One range per thread, each its home task (jit/thread_pool.h), so that a thread computes the
// same rows in every pass and finds them in its own cache: on a 2-core machine whose cores
// take 500 ns to pass a cache line back and forth, the fem bunny's solve took 108 ms over 30
// frames on four ranges a thread claimed in turn, 94 ms on one home range a thread.
extern "C" void simit_jit_parallel_for(void* pool, void (*op)(const int64_t*, int64_t, int64_t),
                                       const int64_t* context, int64_t units) {
  auto* p = static_cast<simit::jit::ThreadPool*>(pool);
  if (!p || p->threads() == 1 || units <= 1) {
    if (units > 0) op(context, 0, units);
    return;
  }
  const int parts = static_cast<int>(std::min<int64_t>(units, p->threads()));
  simit::jit::RangeSplit& split = p->split_of(reinterpret_cast<const void*>(op));
  const std::vector<int64_t>& bounds = split.bounds(units, parts);
  double* times = split.times();
  p->run(parts, [&](int64_t t) {
    const auto start = std::chrono::steady_clock::now();
    const auto k = static_cast<size_t>(t);
    if (bounds[k] < bounds[k + 1]) op(context, bounds[k], bounds[k + 1]);
    times[k] = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  });
  split.record();
}
