// Stamps naming a map argument's contents (jit/array_stamps.h).
#include "jit/array_stamps.h"

#include <algorithm>
#include <memory>
#include <mutex>
#include <unordered_map>

namespace simit::jit {

namespace {

uint64_t mixed(uint64_t h) {  // splitmix64's finaliser
  h ^= h >> 30;
  h *= 0xbf58476d1ce4e5b9ULL;
  h ^= h >> 27;
  h *= 0x94d049bb133111ebULL;
  return h ^ (h >> 31);
}

}  // namespace

uint64_t stamp(StampKind kind, std::initializer_list<uint64_t> parts) {
  uint64_t h = mixed(static_cast<uint64_t>(kind));
  for (uint64_t p : parts) h = mixed(h ^ mixed(p + 0x9e3779b97f4a7c15ULL));
  return h ? h : 1;
}

uint64_t field_stamp(const runtime::Set& set, int field) {
  if (set.fields_pinned()) return 0;
  return stamp(StampKind::Field,
               {set.id(), static_cast<uint64_t>(field), set.field(field).write_version()});
}

uint64_t endpoints_stamp(const runtime::Set& set) {
  return stamp(StampKind::Endpoints,
               {set.id(), set.topology_version(), static_cast<uint64_t>(set.size())});
}

uint64_t pattern_number(const runtime::PatternPtr& p) {
  struct Known {
    std::weak_ptr<const runtime::MatrixPattern> pattern;
    uint64_t number = 0;
  };
  // Process-wide (controllers may run on several threads), by address; an entry whose
  // pattern has gone is renumbered when a pattern turns up at its address again, and the
  // entries of patterns gone are dropped whenever the table has doubled.
  static std::mutex mutex;
  static std::unordered_map<const runtime::MatrixPattern*, Known> known;
  static uint64_t next = 0;
  static size_t sweep_at = 256;
  std::lock_guard<std::mutex> lock(mutex);
  Known& k = known[p.get()];
  if (k.number == 0 || k.pattern.owner_before(p) || p.owner_before(k.pattern)) {
    k.pattern = p;
    k.number = ++next;
  }
  const uint64_t number = k.number;
  if (known.size() >= sweep_at) {
    std::erase_if(known, [](const auto& entry) { return entry.second.pattern.expired(); });
    sweep_at = std::max<size_t>(256, 2 * known.size());
  }
  return number;
}

}  // namespace simit::jit
