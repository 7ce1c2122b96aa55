// The writer thread of a scene's output frames (scene/frame_writer.h).
#include "scene/frame_writer.h"

#include <atomic>
#include <utility>

namespace simit::scene {

namespace {

std::atomic<bool> g_hold_jobs{false};

}  // namespace

void FrameWriter::hold_jobs_for_test(bool on) { g_hold_jobs.store(on); }

void FrameWriter::finish(std::unique_lock<std::mutex>& lock) {
  release_ = true;
  changed_.notify_all();
  changed_.wait(lock, [&] { return !job_ && !running_; });
  release_ = false;
}

FrameWriter::~FrameWriter() {
  {
    std::unique_lock lock(mutex_);
    finish(lock);
    stop_ = true;
  }
  changed_.notify_all();
  if (thread_.joinable()) thread_.join();
}

void FrameWriter::post(std::function<void()> job) {
  std::unique_lock lock(mutex_);
  finish(lock);
  if (error_) std::rethrow_exception(std::exchange(error_, nullptr));
  job_ = std::move(job);
  if (!thread_.joinable()) thread_ = std::thread([this] { work(); });
  lock.unlock();
  changed_.notify_all();
}

void FrameWriter::wait() {
  std::unique_lock lock(mutex_);
  finish(lock);
  if (error_) std::rethrow_exception(std::exchange(error_, nullptr));
}

bool FrameWriter::busy() {
  std::lock_guard lock(mutex_);
  return job_ || running_;
}

void FrameWriter::work() {
  std::unique_lock lock(mutex_);
  for (;;) {
    changed_.wait(lock, [&] { return stop_ || (job_ && (release_ || !g_hold_jobs.load())); });
    if (!job_) return;  // stopped with nothing left to run
    std::function<void()> job = std::move(job_);
    job_ = nullptr;
    running_ = true;
    lock.unlock();
    std::exception_ptr error;
    try {
      job();
    } catch (...) {
      error = std::current_exception();
    }
    job = nullptr;  // what the job owned (the frame's copies) goes before the next one comes
    lock.lock();
    running_ = false;
    error_ = error;
    changed_.notify_all();
  }
}

}  // namespace simit::scene
