// The engine's pool of worker threads: one job at a time. Two kinds of job:
// - a run of numbered tasks (a map's chunks): each thread has a home range of consecutive
//   tasks, the same share of every job, and a thread that has finished its own range takes
//   tasks from the back of the others';
// - one given range per thread (a solver loop's pass, simit_jit_parallel_for): the caller
//   posts each worker its range on the worker's own cache line, and the worker reports on
//   another; the caller runs a range itself when its worker has not taken it in time.
// Which thread runs a task never decides a result: callers write per-task outputs indexed by
// the task (docs/arithmetic.md).
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <thread>
#include <type_traits>
#include <unordered_map>
#include <vector>

#include "jit/range_split.h"

namespace simit::jit {

class ThreadPool {
 public:
  // `threads` in all, the caller included (1: no worker threads), on a machine where this
  // process may use `cpus` CPUs (by default, runtime::usable_cpus()).
  explicit ThreadPool(int threads, int cpus = 0);
  ~ThreadPool();
  ThreadPool(const ThreadPool&) = delete;
  ThreadPool& operator=(const ThreadPool&) = delete;

  int threads() const { return static_cast<int>(workers_.size()) + 1; }
  // The ranges of a solver loop's pass, named by its outlined function, learnt from its
  // earlier calls on this pool (jit/range_split.h). Only the thread that runs jobs calls it.
  RangeSplit& split_of(const void* pass) { return splits_[pass]; }
  // Runs task(i) for i in [0, tasks) on the pool and the calling thread; returns when every
  // task has returned. Thread t (0: the caller) starts with tasks [t * tasks / threads,
  // (t + 1) * tasks / threads), in order. One job at a time: the pool is the engine's, and the
  // engine runs one statement at a time. `task` is called, never copied (no allocation per job).
  template <class F>
  void run(int64_t tasks, F&& task) {
    using T = std::remove_reference_t<F>;
    run(tasks, Task{const_cast<void*>(static_cast<const void*>(&task)),
                    [](void* f, int64_t i) { (*static_cast<T*>(f))(i); }});
  }
  // Runs op(context, bounds[t], bounds[t + 1]) for each t in [0, parts), parts <= threads():
  // range t on thread t (0: the caller), or on the caller when thread t has not taken it by
  // the time the caller has waited kStealAfter for it (at once in a pool with more threads
  // than CPUs). times[t]: the seconds range t took.
  using RangeOp = void (*)(const int64_t*, int64_t, int64_t);
  void run_ranges(RangeOp op, const int64_t* context, const int64_t* bounds, int parts,
                  double* times);

 private:
  struct Task {
    void* object;
    void (*call)(void*, int64_t);
  };
  // What the caller posts to a worker, on the worker's own cache line, which the worker polls:
  // `word` is the job's number times 2, plus 1 for a given range (op, context, first, end:
  // read only by the thread that claimed the range, so never while the caller rewrites them).
  struct alignas(64) Post {
    std::atomic<uint64_t> word{0};
    RangeOp op = nullptr;
    const int64_t* context = nullptr;
    int64_t first = 0, end = 0;
  };
  // The last job whose given range of this worker someone took: the worker, or the caller
  // when the worker was late. Only the worker touches it while it keeps up, so its claim is
  // a compare-and-swap in its own cache.
  struct alignas(64) Claim {
    std::atomic<uint64_t> job{0};
  };
  // What a worker reports of its given range: the job it finished, and the seconds it took.
  struct alignas(64) Report {
    std::atomic<uint64_t> job{0};
    double seconds = 0;
  };
  // Each thread's home range of the current job, in one word: the job's number (high 32
  // bits), then the first and the end of the tasks not yet claimed (16 bits each), so that a
  // claim is one compare-and-swap and a thread late from an earlier job claims nothing of a
  // later one. Its own cache line: the owner claims from it on every task.
  struct alignas(64) Range {
    std::atomic<uint64_t> word{0};
  };
  // Tasks in one job (the rest of a larger run goes in further jobs).
  static constexpr int64_t kMaxJobTasks = 0xffff;

  void run(int64_t tasks, Task task);
  void run_job(int64_t first, int64_t tasks);
  // Posts `word` to workers 1 to posts - 1.
  void post(uint64_t word, int posts);
  // Wakes the workers that sleep, once the posts are stored.
  void wake_sleepers();
  // Waits until the caller's tasks are done: `done()` true. Spins, then yields.
  template <class Done>
  void wait(Done done);
  void work(int self);
  // Runs worker `self`'s range of ranged job `job` if nobody has taken it (the worker, or the
  // caller when the worker is late): whether this call ran it.
  bool take_range(int self, uint64_t job);
  // Claims and runs tasks of job `job`: those of range `self` from the front, then those of
  // the other ranges from the back, until none is left.
  void claim(int self, uint32_t job);
  bool claim_one(Range& range, uint32_t job, bool front);

  // More threads than the CPUs this process may use: the workers and the caller yield the
  // core between polls rather than pause, since a thread that spins keeps one that has work
  // off its core. The fem bunny on 7 threads of a 2-core machine: 14.3 ms a frame when they
  // paused, 20.2 when the workers slept at once (a wake per pass), 6.9 when they yield (5.6
  // on one thread).
  const bool oversubscribed_;
  std::vector<std::thread> workers_;
  std::unique_ptr<Range[]> ranges_;
  std::unique_ptr<Post[]> posts_;
  std::unique_ptr<Claim[]> claims_;
  std::unique_ptr<Report[]> reports_;
  std::unordered_map<const void*, RangeSplit> splits_;
  // The task job: its task and the number of its first task (a run of more than
  // kMaxJobTasks tasks is several jobs), written before the ranges and the posts publish it.
  Task task_{};
  int64_t first_ = 0;
  uint64_t job_ = 0;                  // the last job's number (only the caller uses it)
  std::atomic<int64_t> finished_{0};  // tasks of the current task job that have returned
  // Workers asleep (between jobs, after spinning a while) and what wakes them.
  std::atomic<int> sleepers_{0};
  std::atomic<bool> stop_{false};
  std::mutex mutex_;
  std::condition_variable wake_;
};

}  // namespace simit::jit

// What a compiled solver loop calls to run an outlined pass over `units` units on `pool` (a
// ThreadPool, or null: on the calling thread): op(context, first, end) for contiguous ranges
// of units that cover [0, units) once (jit/llvm/emit_parallel.cpp): one range per thread, its
// bounds learnt from the pass's earlier calls (jit/range_split.h).
extern "C" void simit_jit_parallel_for(void* pool, void (*op)(const int64_t*, int64_t, int64_t),
                                       const int64_t* context, int64_t units);
