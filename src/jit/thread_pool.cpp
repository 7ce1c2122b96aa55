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
// Long enough, too, to outlast a small scene's output between two frames: at 0.5 ms the
// workers slept while the fem bunny's frame was written, and the next frame's first map
// (tet_force, 0.48 ms on one thread) ran mostly on the caller while they woke: 0.38-0.40 ms a
// call on 2 threads, against 0.25-0.26 at 5 ms and at 20 ms (springs' spring_force: 0.128
// against 0.103). OpenMP runtimes poll as long or longer (libgomp some milliseconds, Intel's
// 200 ms by default). (Measured in time: a pause instruction takes 3 to 140 cycles, by
// processor.)
constexpr auto kSpinFor = std::chrono::milliseconds(5);
constexpr int kPausesPerClockRead = 64;
// How long the caller waits for a worker to report its given range before it looks whether
// the worker has taken it, and takes it itself if not (a worker asleep, or off its core). A
// pass that keeps up takes a few microseconds more on one thread than on the other.
constexpr auto kStealAfter = std::chrono::microseconds(10);

void relax() {
#if defined(__x86_64__) || defined(__i386__)
  _mm_pause();
#else
  std::this_thread::yield();
#endif
}

// Runs op over units [first, end) (nothing when empty); the seconds it took.
double run_timed(ThreadPool::RangeOp op, const int64_t* context, int64_t first, int64_t end) {
  const auto start = std::chrono::steady_clock::now();
  if (first < end) op(context, first, end);
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
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
      ranges_(new Range[static_cast<size_t>(std::max(1, threads))]),
      posts_(new Post[static_cast<size_t>(std::max(1, threads))]),
      claims_(new Claim[static_cast<size_t>(std::max(1, threads))]),
      reports_(new Report[static_cast<size_t>(std::max(1, threads))]) {
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

void ThreadPool::post(uint64_t word, int posts) {
  for (int t = 1; t < posts; ++t)
    posts_[static_cast<size_t>(t)].word.store(word, std::memory_order_release);
}

void ThreadPool::wake_sleepers() {
  // A worker that counted itself asleep after this load tests its post after the posts'
  // stores, and sees the job; one counted before it is woken (taking the lock first means it
  // is either waiting or about to test).
  std::atomic_thread_fence(std::memory_order_seq_cst);
  if (sleepers_.load(std::memory_order_seq_cst) > 0) {
    { std::lock_guard lock(mutex_); }
    wake_.notify_all();
  }
}

template <class Done>
void ThreadPool::wait(Done done) {
  const auto until = std::chrono::steady_clock::now() + kSpinFor;
  for (int spins = 1; !done(); ++spins) {
    if (oversubscribed_) {
      std::this_thread::yield();  // a worker still running a task may need this core
      continue;
    }
    relax();
    if (spins % kPausesPerClockRead == 0 && std::chrono::steady_clock::now() > until)
      std::this_thread::yield();
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
  const uint64_t job = ++job_;
  const int threads = this->threads();
  for (int t = 0; t < threads; ++t)
    ranges_[static_cast<size_t>(t)].word.store(
        range_word(static_cast<uint32_t>(job), static_cast<uint64_t>(t * tasks / threads),
                   static_cast<uint64_t>((t + 1) * tasks / threads)),
        std::memory_order_release);
  post(job << 1, threads);
  wake_sleepers();
  claim(0, static_cast<uint32_t>(job));
  wait([&] { return finished_.load(std::memory_order_acquire) == tasks; });
}

bool ThreadPool::take_range(int self, uint64_t job) {
  Claim& claim = claims_[static_cast<size_t>(self)];
  uint64_t last = claim.job.load(std::memory_order_relaxed);
  // The worker and the caller only ever set `job`: a failed exchange means the other took it.
  if (last >= job || !claim.job.compare_exchange_strong(last, job, std::memory_order_acq_rel))
    return false;
  const Post& p = posts_[static_cast<size_t>(self)];
  reports_[static_cast<size_t>(self)].seconds = run_timed(p.op, p.context, p.first, p.end);
  return true;
}

void ThreadPool::run_ranges(RangeOp op, const int64_t* context, const int64_t* bounds, int parts,
                            double* times) {
  parts = std::clamp(parts, 1, threads());
  const uint64_t job = ++job_;
  for (int t = 1; t < parts; ++t) {
    Post& p = posts_[static_cast<size_t>(t)];
    p.op = op;
    p.context = context;
    p.first = bounds[t];
    p.end = bounds[t + 1];
  }
  post(job << 1 | 1, parts);
  times[0] = run_timed(op, context, bounds[0], bounds[1]);
  // After the caller's own range: the fence waits for the posts' stores, which by now have
  // long reached the workers.
  wake_sleepers();
  for (int t = 1; t < parts; ++t) {
    Report& report = reports_[static_cast<size_t>(t)];
    // Until kStealAfter has passed, the caller polls the report only, so that a worker that
    // keeps up finds its claim word in its own cache; a pool with more threads than CPUs
    // takes a late range at once, since its worker may be waiting for this core.
    const auto steal_at = std::chrono::steady_clock::now() + kStealAfter;
    int polls = 0;
    wait([&] {
      if (report.job.load(std::memory_order_acquire) == job) return true;
      if (!oversubscribed_ &&
          (++polls % kPausesPerClockRead != 0 || std::chrono::steady_clock::now() < steal_at))
        return false;
      return take_range(t, job);
    });
    times[t] = report.seconds;
  }
}

void ThreadPool::work(int self) {
  Post& mine = posts_[static_cast<size_t>(self)];
  uint64_t seen = 0;
  for (;;) {
    const uint64_t word = mine.word.load(std::memory_order_acquire);
    if (word != seen) {
      seen = word;
      if (word & 1) {
        if (take_range(self, word >> 1))
          reports_[static_cast<size_t>(self)].job.store(word >> 1, std::memory_order_release);
      } else {
        claim(self, static_cast<uint32_t>(word >> 1));
      }
    }
    const auto until = std::chrono::steady_clock::now() + kSpinFor;
    for (int spins = 1; mine.word.load(std::memory_order_acquire) == seen; ++spins) {
      if (stop_.load(std::memory_order_relaxed)) return;
      if (oversubscribed_)
        std::this_thread::yield();
      else
        relax();
      if (spins % kPausesPerClockRead == 0 && std::chrono::steady_clock::now() > until) break;
    }
    if (mine.word.load(std::memory_order_acquire) != seen) continue;
    std::unique_lock lock(mutex_);
    sleepers_.fetch_add(1, std::memory_order_seq_cst);
    wake_.wait(lock,
               [&] { return stop_.load() || mine.word.load(std::memory_order_seq_cst) != seen; });
    sleepers_.fetch_sub(1, std::memory_order_relaxed);
    if (stop_.load()) return;
  }
}

}  // namespace simit::jit

// One range per thread (jit/thread_pool.h, run_ranges), so that a thread computes the same
// rows in every pass and finds them in its own cache: on a 2-core machine whose cores take
// 500 ns to pass a cache line back and forth, the fem bunny's solve took 108 ms over 30 frames
// on four ranges a thread claimed in turn, 94 ms on one home range a thread.
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
  p->run_ranges(op, context, bounds.data(), parts, split.times());
  split.record();
}
