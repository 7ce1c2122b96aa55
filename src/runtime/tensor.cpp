// Dense tensor storage.
#include "runtime/tensor.h"

#include <algorithm>
#include <new>

#include "runtime/fault.h"

namespace simit::runtime {

const char* component_name(ComponentKind k) {
  switch (k) {
    case ComponentKind::Int: return "int";
    case ComponentKind::Float: return "float";
    case ComponentKind::Bool: return "bool";
    case ComponentKind::Complex: return "complex";
    case ComponentKind::String: return "string";
  }
  return "?";
}

// ---------------------------------------------------------------------------
// Storage

Storage::Storage(size_t bytes) : bytes_(bytes) {
  if (bytes > kInlineBytes) {
    heap_ = residency::new_host_array(bytes);
    std::memset(heap_.get(), 0, bytes);
  } else {
    std::memset(inline_, 0, bytes);
  }
}

Storage::Storage(std::shared_ptr<std::byte[]> heap, size_t bytes) : bytes_(bytes) {
  if (heap) {
    heap_ = std::move(heap);
  } else if (bytes > kInlineBytes) {
    heap_ = residency::new_host_array(bytes);
    std::memset(heap_.get(), 0, bytes);
  } else {
    std::memset(inline_, 0, bytes);
  }
}

void Storage::copy_from(const Storage& o) {
  bytes_ = o.bytes_;
  heap_ = o.heap_;  // shared until someone writes
  if (!heap_) std::memcpy(inline_, o.inline_, bytes_);
}

void Storage::move_from(Storage& o) noexcept {
  bytes_ = o.bytes_;
  heap_ = std::move(o.heap_);
  if (!heap_) std::memcpy(inline_, o.inline_, bytes_);
  o.bytes_ = 0;
}

Storage& Storage::operator=(const Storage& o) {
  if (this != &o) copy_from(o);
  return *this;
}

Storage& Storage::operator=(Storage&& o) noexcept {
  if (this != &o) move_from(o);
  return *this;
}

std::byte* Storage::mutable_heap() {
  if (heap_.use_count() > 1) {
    std::shared_ptr<std::byte[]> copy = residency::new_host_array(bytes_);
    std::memcpy(copy.get(), heap_.get(), bytes_);
    heap_ = std::move(copy);
  }
  return heap_.get();
}

// ---------------------------------------------------------------------------
// Tensor

Tensor::Tensor(ComponentKind kind, const Shape& shape) try
    : kind_(kind), shape_(shape), storage_(component_bytes(kind) * shape.size()) {
  if (kind == ComponentKind::String)
    strings_ = std::make_shared<std::vector<std::string>>(shape.size());
} catch (const std::bad_alloc&) {
  out_of_memory(kind, shape);
}

void Tensor::out_of_memory(ComponentKind kind, const Shape& shape) {
  throw Fault("out of memory while allocating a " + shape.str() + " " + component_name(kind) +
              " tensor (" + std::to_string(component_bytes(kind) * shape.size()) + " bytes)");
}

Tensor::Tensor(ComponentKind kind, const Shape& shape, std::shared_ptr<std::byte[]> heap)
    : kind_(kind), shape_(shape), storage_(std::move(heap), component_bytes(kind) * shape.size()) {
  if (kind == ComponentKind::String) throw Fault("string tensors cannot share a heap block");
}

std::string* Tensor::mutable_strings() {
  if (!strings_) return nullptr;
  if (strings_.use_count() > 1) strings_ = std::make_shared<std::vector<std::string>>(*strings_);
  return strings_->data();
}

Tensor Tensor::range(size_t offset, const Shape& shape) const {
  if (offset + shape.size() > size()) throw Fault("tensor range out of bounds");
  Tensor out(kind_, shape);
  if (kind_ == ComponentKind::String) {
    std::copy_n(strings() + offset, shape.size(), out.mutable_strings());
  } else {
    size_t w = component_bytes(kind_);
    std::memcpy(out.storage_.mutable_data(), storage_.data() + offset * w, shape.size() * w);
  }
  return out;
}

void Tensor::write_range(size_t offset, const Tensor& src) {
  if (src.kind_ != kind_ || offset + src.size() > size())
    throw Fault("tensor write out of bounds or of another component kind");
  if (kind_ == ComponentKind::String) {
    std::copy_n(src.strings(), src.size(), mutable_strings() + offset);
    return;
  }
  size_t w = component_bytes(kind_);
  std::memcpy(storage_.mutable_data() + offset * w, src.storage_.data(), src.size() * w);
}

void Tensor::fill(size_t offset, size_t count, int32_t v) {
  std::fill_n(mutable_ints() + offset, count, v);
}
void Tensor::fill(size_t offset, size_t count, double v) {
  std::fill_n(mutable_floats() + offset, count, v);
}
void Tensor::fill(size_t offset, size_t count, bool v) {
  std::fill_n(mutable_bools() + offset, count, v);
}
void Tensor::fill(size_t offset, size_t count, Complex v) {
  std::fill_n(mutable_complexes() + offset, count, v);
}
void Tensor::fill(size_t offset, size_t count, const std::string& v) {
  std::fill_n(mutable_strings() + offset, count, v);
}

void Tensor::reshape(const Shape& shape) {
  if (shape.size() != size()) throw Fault("cannot reshape " + shape_.str() + " to " + shape.str());
  shape_ = shape;
}

void Tensor::string_uninit() { throw Fault("string tensors are always initialised"); }

bool Tensor::operator==(const Tensor& o) const {
  if (kind_ != o.kind_ || shape_ != o.shape_) return false;
  size_t n = size();
  switch (kind_) {
    case ComponentKind::Int: return std::equal(ints(), ints() + n, o.ints());
    case ComponentKind::Float: return std::equal(floats(), floats() + n, o.floats());
    case ComponentKind::Bool: return std::equal(bools(), bools() + n, o.bools());
    case ComponentKind::Complex: return std::equal(complexes(), complexes() + n, o.complexes());
    case ComponentKind::String: return std::equal(strings(), strings() + n, o.strings());
  }
  return false;
}

}  // namespace simit::runtime
