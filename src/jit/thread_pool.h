// The engine's pool of worker threads: one job at a time, split into numbered tasks that the
// workers and the calling thread claim in turn. Which thread runs a task never decides a
// result: callers write per-task outputs indexed by the task (docs/arithmetic.md).
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace simit::jit {

class ThreadPool {
 public:
  // `threads` in all, the caller included (1: no worker threads).
  explicit ThreadPool(int threads);
  ~ThreadPool();
  ThreadPool(const ThreadPool&) = delete;
  ThreadPool& operator=(const ThreadPool&) = delete;

  int threads() const { return static_cast<int>(workers_.size()) + 1; }
  // Runs task(i) for i in [0, tasks) on the pool and the calling thread; returns when every
  // task has returned. Tasks are claimed in increasing order. One job at a time: the pool is
  // the engine's, and the engine runs one statement at a time.
  void run(int64_t tasks, const std::function<void(int64_t)>& task);

 private:
  void work();
  void claim(const std::function<void(int64_t)>& task, int64_t tasks);

  std::vector<std::thread> workers_;
  std::mutex mutex_;
  std::condition_variable wake_, done_;
  // The current job, published under mutex_ with a new generation.
  const std::function<void(int64_t)>* task_ = nullptr;
  int64_t tasks_ = 0;
  uint64_t generation_ = 0;
  bool stop_ = false;
  std::atomic<uint64_t> published_{0};  // generation_, readable without the lock (spinning)
  std::atomic<int64_t> next_{0};        // the next task to claim
  int busy_ = 0;                        // workers inside the current job
};

}  // namespace simit::jit

// What a compiled solver loop calls to run an outlined pass over `units` units on `pool` (a
// ThreadPool, or null: on the calling thread): op(context, first, end) for contiguous ranges
// of units that cover [0, units) once (jit/llvm/emit_parallel.cpp).
extern "C" void simit_jit_parallel_for(void* pool, void (*op)(const int64_t*, int64_t, int64_t),
                                       const int64_t* context, int64_t units);
