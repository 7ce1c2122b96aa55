// Dense tensors shared by every executor: a component kind, a (possibly blocked) shape and
// contiguous row-major storage in which each block is stored whole, one after another.
// Small tensors live inline (no heap allocation); large storage is shared copy-on-write.
#pragma once

#include <complex>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <memory>
#include <new>
#include <string>
#include <vector>

#include "runtime/residency.h"
#include "runtime/shape.h"

namespace simit::runtime {

// Component (scalar) kinds: int is 32-bit, float is binary64 storage, bool one byte.
enum class ComponentKind : uint8_t { Int, Float, Bool, Complex, String };
const char* component_name(ComponentKind k);
// 0 for String (stored out of line).
inline size_t component_bytes(ComponentKind k) {
  switch (k) {
    case ComponentKind::Int: return 4;
    case ComponentKind::Float: return 8;
    case ComponentKind::Bool: return 1;
    case ComponentKind::Complex: return 16;
    case ComponentKind::String: return 0;
  }
  return 0;
}

using Complex = std::complex<double>;

// Raw bytes: inline up to kInlineBytes, otherwise a shared heap block cloned before writes.
// A heap block whose newest contents are in an executor's memory is brought back before the
// host reads or writes it (runtime/residency.h); raw_data() and raw_mutable_data() do not.
class Storage {
 public:
  static constexpr size_t kInlineBytes = 128;

  Storage() = default;
  explicit Storage(size_t bytes);  // zero-filled
  // Shares an existing heap block of at least `bytes` bytes (no copy; a null block with
  // `bytes` > 0 allocates zeros). Writes through either owner copy it first.
  Storage(std::shared_ptr<std::byte[]> heap, size_t bytes);
  Storage(const Storage& o) { copy_from(o); }
  Storage(Storage&& o) noexcept { move_from(o); }
  Storage& operator=(const Storage& o);
  Storage& operator=(Storage&& o) noexcept;
  ~Storage() = default;

  size_t bytes() const { return bytes_; }
  // Resizes to `bytes` without clearing them (the caller writes every byte) and drops any
  // shared heap block.
  void reset_uninit(size_t bytes) {
    bytes_ = bytes;
    if (bytes > kInlineBytes)
      heap_ = residency::new_host_array(bytes);
    else if (heap_)
      heap_.reset();
  }
  const std::byte* data() const {
    if (!heap_) return inline_;
    residency::before_host_access(heap_.get());
    return heap_.get();
  }
  std::byte* mutable_data() {  // unshares heap storage first
    if (!heap_) return inline_;
    residency::before_host_access(heap_.get());
    return mutable_heap();
  }
  // For an executor copying the bytes into its own memory, which holds the newest.
  const std::byte* raw_data() const { return heap_ ? heap_.get() : inline_; }
  std::byte* raw_mutable_data() {  // unshares heap storage first (bringing it back to copy)
    if (!heap_) return inline_;
    if (heap_.use_count() > 1) residency::before_host_access(heap_.get());
    return mutable_heap();
  }
  // The shared heap block (null when the bytes are inline).
  const std::shared_ptr<std::byte[]>& heap() const { return heap_; }

 private:
  void copy_from(const Storage& o);
  void move_from(Storage& o) noexcept;
  std::byte* mutable_heap();

  alignas(16) std::byte inline_[kInlineBytes];
  std::shared_ptr<std::byte[]> heap_;
  size_t bytes_ = 0;
};

class Tensor {
 public:
  Tensor() : storage_(sizeof(double)) {}           // the float scalar 0.0
  Tensor(ComponentKind kind, const Shape& shape);  // all components zero / empty
  // A tensor over an existing heap block (e.g. a set field's array), shared without a copy:
  // the first write through either owner copies it (copy-on-write). Not for String.
  Tensor(ComponentKind kind, const Shape& shape, std::shared_ptr<std::byte[]> heap);

  ComponentKind kind() const { return kind_; }
  const Shape& shape() const { return shape_; }
  size_t size() const { return shape_.size(); }

  // Typed views of the components; the kind must match.
  const int32_t* ints() const { return reinterpret_cast<const int32_t*>(storage_.data()); }
  const double* floats() const { return reinterpret_cast<const double*>(storage_.data()); }
  const bool* bools() const { return reinterpret_cast<const bool*>(storage_.data()); }
  const Complex* complexes() const { return reinterpret_cast<const Complex*>(storage_.data()); }
  const std::string* strings() const { return strings_ ? strings_->data() : nullptr; }
  int32_t* mutable_ints() { return reinterpret_cast<int32_t*>(storage_.mutable_data()); }
  double* mutable_floats() { return reinterpret_cast<double*>(storage_.mutable_data()); }
  // floats() and mutable_floats() for an executor copying them into its own memory, where a
  // newer copy of them may be (runtime/residency.h): not brought back.
  const double* raw_floats() const { return reinterpret_cast<const double*>(storage_.raw_data()); }
  double* raw_mutable_floats() { return reinterpret_cast<double*>(storage_.raw_mutable_data()); }
  bool* mutable_bools() { return reinterpret_cast<bool*>(storage_.mutable_data()); }
  Complex* mutable_complexes() { return reinterpret_cast<Complex*>(storage_.mutable_data()); }
  std::string* mutable_strings();
  // The heap block holding the components, shared with copies of this tensor (and with a
  // set field it was read from or stored into); null when they are inline or strings.
  const std::shared_ptr<std::byte[]>& shared_buffer() const { return storage_.heap(); }

  // The components [offset, offset + shape.size()) as a tensor of `shape` (a block).
  Tensor range(size_t offset, const Shape& shape) const;
  // Overwrites the components from `offset` with all of `src` (same kind).
  void write_range(size_t offset, const Tensor& src);
  // Sets components [offset, offset + count) to one value.
  void fill(size_t offset, size_t count, int32_t v);
  void fill(size_t offset, size_t count, double v);
  void fill(size_t offset, size_t count, bool v);
  void fill(size_t offset, size_t count, Complex v);
  void fill(size_t offset, size_t count, const std::string& v);
  // Same components, another shape of the same size.
  void reshape(const Shape& shape);
  // Makes this a tensor of `kind` and `shape` in place whose components are not cleared:
  // the caller writes every one before reading (interpreter temporaries). Not for String.
  void reset_uninit(ComponentKind kind, const Shape& shape) {
    if (kind == ComponentKind::String) string_uninit();
    kind_ = kind;
    shape_ = shape;
    if (strings_) strings_.reset();
    try {
      storage_.reset_uninit(component_bytes(kind) * shape.size());
    } catch (const std::bad_alloc&) {
      out_of_memory(kind, shape);
    }
  }
  // Drops shared storage (heap block, strings) so the object can be recycled cheaply.
  void release_shared() {
    if (strings_) strings_.reset();
    if (storage_.heap()) storage_.reset_uninit(0);
  }

  // Exact equality of kind, shape and components (float components compared with ==).
  bool operator==(const Tensor& o) const;

 private:
  [[noreturn]] static void string_uninit();
  // Throws the Fault that names the tensor that could not be allocated.
  [[noreturn]] static void out_of_memory(ComponentKind kind, const Shape& shape);
  ComponentKind kind_ = ComponentKind::Float;
  Shape shape_;
  Storage storage_;
  std::shared_ptr<std::vector<std::string>> strings_;  // String kind only
};

}  // namespace simit::runtime
