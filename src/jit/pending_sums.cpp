// PendingSums (jit/pending_sums.h): fused sums summed where they are read.
#include "jit/pending_sums.h"

namespace simit::jit {

PendingSums::~PendingSums() { runtime::residency::bring_back_all_of(*this); }

void PendingSums::hold(double* host, runtime::LazySum sum) {
  {
    std::lock_guard<std::mutex> guard(lock_);
    sums_[host] = std::make_unique<runtime::LazySum>(std::move(sum));
    ++held_;
  }
  runtime::residency::mark_elsewhere(host, *this);
}

const runtime::LazySum* PendingSums::find(const void* host) const {
  if (!runtime::residency::is_elsewhere(host, *this)) return nullptr;
  std::lock_guard<std::mutex> guard(lock_);
  auto it = sums_.find(host);
  return it == sums_.end() ? nullptr : it->second.get();
}

std::unique_ptr<runtime::LazySum> PendingSums::take(const void* host) noexcept {
  std::lock_guard<std::mutex> guard(lock_);
  auto it = sums_.find(host);
  if (it == sums_.end()) return nullptr;
  std::unique_ptr<runtime::LazySum> s = std::move(it->second);
  sums_.erase(it);
  return s;
}

void PendingSums::bring_back(void* host) {
  if (std::unique_ptr<runtime::LazySum> s = take(host)) {
    s->write(static_cast<double*>(host));
    std::lock_guard<std::mutex> guard(lock_);
    ++written_;
  }
}

void PendingSums::released(const void* host) noexcept { take(host); }

}  // namespace simit::jit
