// The engine's pool of worker threads: one job at a time, split into numbered tasks that the
// workers and the calling thread claim in turn. Which thread runs a task never decides a
// result: callers write per-task outputs indexed by the task (docs/arithmetic.md).
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <thread>
#include <type_traits>
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
  // task has returned. One job at a time: the pool is the engine's, and the engine runs one
  // statement at a time. `task` is called, never copied (no allocation per job).
  template <class F>
  void run(int64_t tasks, F&& task) {
    using T = std::remove_reference_t<F>;
    run(tasks, Task{const_cast<void*>(static_cast<const void*>(&task)),
                    [](void* f, int64_t i) { (*static_cast<T*>(f))(i); }});
  }

 private:
  struct Task {
    void* object;
    void (*call)(void*, int64_t);
  };
  void run(int64_t tasks, Task task);
  void work();
  // Claims and runs tasks of the current job until none is left.
  void claim();

  std::vector<std::thread> workers_;
  // The job: its task and size, written before `work_` publishes it. work_ holds the job's
  // number (high 32 bits) and its tasks not yet claimed (low 32 bits), so that a claim is one
  // compare-and-swap and a thread late from an earlier job can claim nothing of a later one.
  Task task_{};
  int64_t tasks_ = 0;
  std::atomic<uint64_t> work_{0};
  std::atomic<int64_t> finished_{0};  // tasks of the current job that have returned
  // Workers asleep (between jobs, after spinning a while) and what wakes them.
  std::atomic<int> sleepers_{0};
  std::atomic<bool> stop_{false};
  std::mutex mutex_;
  std::condition_variable wake_;
};

}  // namespace simit::jit

// What a compiled solver loop calls to run an outlined pass over `units` units on `pool` (a
// ThreadPool, or null: on the calling thread): op(context, first, end) for contiguous ranges
// of units that cover [0, units) once (jit/llvm/emit_parallel.cpp).
extern "C" void simit_jit_parallel_for(void* pool, void (*op)(const int64_t*, int64_t, int64_t),
                                       const int64_t* context, int64_t units);
