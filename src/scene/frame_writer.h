// A scene's output frames written on a thread of their own, one at a time, so that the next
// frame computes while the last one goes to disk: on fem dragon160k a frame's .vtu is 7 MB,
// and writing it took about 4 ms (into a fresh folder) to 10-16 ms (over an earlier run's
// frames) of a 75 ms frame on one thread, most of it the kernel copying the bytes.
#pragma once

#include <condition_variable>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>

namespace simit::scene {

class FrameWriter {
 public:
  FrameWriter() = default;
  // Waits for the job being run; its error, if any, is dropped (the run is ending on another
  // error, or wait() has reported it).
  ~FrameWriter();
  FrameWriter(const FrameWriter&) = delete;
  FrameWriter& operator=(const FrameWriter&) = delete;

  // Runs `job` on the writer thread once the job posted before it has finished. When that
  // one failed, its exception is thrown here instead and `job` is not run: a run stops at the
  // first frame it could not write, one frame later than a run that writes in its own thread.
  void post(std::function<void()> job);
  // Waits until the job posted last has finished; throws its exception if it failed.
  void wait();
  // Whether a job has been posted and has not finished.
  bool busy();
  // Tests: every writer starts a job only when the next post or wait comes, after what the
  // poster did in between (the next frame's step), so that a job that read the poster's data
  // rather than its own copy would be seen to.
  static void hold_jobs_for_test(bool on);

 private:
  void work();
  // Lets a held job start (hold_jobs_for_test) and waits until none is posted or running.
  void finish(std::unique_lock<std::mutex>& lock);

  std::thread thread_;  // started by the first post
  std::mutex mutex_;
  std::condition_variable changed_;
  std::function<void()> job_;  // the job to run (empty: none waiting)
  bool running_ = false;       // the thread is running a job
  bool stop_ = false;
  bool release_ = false;      // a held job may start
  std::exception_ptr error_;  // the last job's failure, until post or wait reports it
};

}  // namespace simit::scene
