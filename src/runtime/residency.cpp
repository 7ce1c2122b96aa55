// The registry of host arrays whose newest contents are elsewhere (runtime/residency.h).
#include "runtime/residency.h"

#include <mutex>
#include <unordered_map>
#include <vector>

namespace simit::runtime::residency {

namespace detail {
std::atomic<long> elsewhere_count{0};
}  // namespace detail

namespace {

// One lock over the table: it is touched only while something is elsewhere, and then by the
// thread that runs the program (a worker reading a host array takes it too).
std::mutex& table_lock() {
  static std::mutex m;
  return m;
}
std::unordered_map<const void*, Holder*>& table() {
  static std::unordered_map<const void*, Holder*> t;
  return t;
}

// Takes `host` out of the table; its holder, or null when it was not elsewhere.
Holder* take(const void* host) {
  std::lock_guard<std::mutex> lock(table_lock());
  auto it = table().find(host);
  if (it == table().end()) return nullptr;
  Holder* h = it->second;
  table().erase(it);
  detail::elsewhere_count.fetch_sub(1, std::memory_order_release);
  return h;
}

}  // namespace

namespace detail {

void sync(const void* host) {
  // Taken out first: the holder copies outside the lock, and a second access finds the
  // array home.
  if (Holder* h = take(host)) h->bring_back(const_cast<void*>(host));
}

void freeing(const void* host) noexcept {
  if (Holder* h = take(host)) h->released(host);
}

}  // namespace detail

void mark_elsewhere(void* host, Holder& holder) {
  Holder* before = nullptr;
  {
    std::lock_guard<std::mutex> lock(table_lock());
    auto [it, fresh] = table().emplace(host, &holder);
    if (fresh) detail::elsewhere_count.fetch_add(1, std::memory_order_release);
    if (it->second != &holder) before = it->second;
    it->second = &holder;
  }
  // Another holder's copy, older now, must not pass for the newest there any more.
  if (before) before->released(host);
}

bool is_elsewhere(const void* host, const Holder& holder) {
  if (!any_elsewhere()) return false;
  std::lock_guard<std::mutex> lock(table_lock());
  auto it = table().find(host);
  return it != table().end() && it->second == &holder;
}

void settle(const void* host) { detail::freeing(host); }

namespace {

// Every array of `only` (null: of every holder) taken out of the table and brought back.
void bring_back_where(const Holder* only) {
  if (!any_elsewhere()) return;
  std::vector<std::pair<const void*, Holder*>> out;
  {
    std::lock_guard<std::mutex> lock(table_lock());
    for (auto it = table().begin(); it != table().end();) {
      if (!only || it->second == only) {
        out.emplace_back(it->first, it->second);
        it = table().erase(it);
        detail::elsewhere_count.fetch_sub(1, std::memory_order_release);
      } else {
        ++it;
      }
    }
  }
  for (auto& [host, h] : out) h->bring_back(const_cast<void*>(host));
}

}  // namespace

void bring_back_all() { bring_back_where(nullptr); }
void bring_back_all_of(Holder& holder) { bring_back_where(&holder); }

long count() { return detail::elsewhere_count.load(std::memory_order_acquire); }

}  // namespace simit::runtime::residency
