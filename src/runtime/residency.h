// Host arrays whose newest contents live in another memory (a GPU's): the registry that lets
// an executor leave what its kernels wrote where they wrote it, and brings it back when the
// host touches the array.
//
// A runtime array (a tensor's heap block, a field's array, a system matrix's values) is
// marked "elsewhere" by the executor that holds its newest contents (a `Holder`). Every
// accessor of those arrays asks `before_host_access` first: while nothing is elsewhere that is
// one load and a branch; otherwise the array, if it is elsewhere, is brought back before the
// host reads or writes it. An array freed while elsewhere is dropped (`before_free`, called by
// the arrays' deallocators), never copied into. Hosts that keep raw pointers into arrays
// (a scene's stepper, the API's and Python's views) read them after a call returns, and the
// interpreter brings everything back then (`bring_back_all`).
//
// Executors marshalling an array into their own memory use the arrays' `raw_*` accessors,
// which do not bring it back: the copy they hold is the newest.
#pragma once

#include <atomic>
#include <cstddef>
#include <memory>

namespace simit::runtime::residency {

class Holder {
 public:
  virtual ~Holder() = default;
  // Copies the newer contents of the host array at `host` into it.
  virtual void bring_back(void* host) = 0;
  // The host array at `host` is being freed: its newer contents are dropped, and nothing
  // may be copied there any more.
  virtual void released(const void* host) noexcept = 0;
};

namespace detail {
extern std::atomic<long> elsewhere_count;
void sync(const void* host);
void freeing(const void* host) noexcept;
}  // namespace detail

// Whether any array's newest contents are elsewhere.
inline bool any_elsewhere() { return detail::elsewhere_count.load(std::memory_order_acquire) != 0; }

// Before the host reads or writes the array starting at `host`: brought back if elsewhere.
inline void before_host_access(const void* host) {
  if (any_elsewhere()) [[unlikely]]
    detail::sync(host);
}

// Before the array starting at `host` is freed: dropped if elsewhere.
inline void before_free(const void* host) noexcept {
  if (any_elsewhere()) [[unlikely]]
    detail::freeing(host);
}

// The array starting at `host` now has its newest contents in `holder`'s memory.
void mark_elsewhere(void* host, Holder& holder);
// Whether the array starting at `host` has its newest contents in `holder`'s memory.
bool is_elsewhere(const void* host, const Holder& holder);
// The host is about to set every value of the array starting at `host` without reading it
// (a matrix zeroed): the holder drops its newer contents, as for a freed array.
void settle(const void* host);
// Every array elsewhere brought back (all holders', or `holder`'s alone).
void bring_back_all();
void bring_back_all_of(Holder& holder);
// How many arrays are elsewhere now.
long count();

// A heap block's deleter that drops the block's newer contents first (std::shared_ptr<T[]>).
struct FreeHostArray {
  template <class T>
  void operator()(T* p) const noexcept {
    before_free(p);
    delete[] p;
  }
};

// A runtime heap block of `bytes` uninitialised bytes, freed through FreeHostArray.
inline std::shared_ptr<std::byte[]> new_host_array(std::size_t bytes) {
  return std::shared_ptr<std::byte[]>(new std::byte[bytes], FreeHostArray{});
}

}  // namespace simit::runtime::residency
