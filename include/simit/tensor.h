// Dense host tensors of fixed dimensions, for binding non-set externs and the parameters
// and results of exported functions.
#pragma once

#include <algorithm>
#include <array>
#include <initializer_list>
#include <vector>

#include "simit/element.h"

namespace simit {

// What Function::bind needs to know about a host tensor: its component type, its
// dimensions (empty: a scalar) and where its row-major components live. The host owns the
// storage, which must outlive the binding.
struct TensorSlot {
  ComponentKind kind = ComponentKind::Float;
  bool single = false;  // float / float_complex components (binary32)
  std::vector<int> dims;
  void* data = nullptr;
};

// A dense tensor with value semantics, zero-initialised. Components are row-major; for a
// blocked Simit type (`vector[2](vector[3](float))`) list the dimensions of every level,
// outermost first (`Tensor<double, 2, 3>`), and store block after block.
template <Component T, int... dims>
class Tensor {
 public:
  static constexpr int order = sizeof...(dims);
  static constexpr size_t size = (size_t{1} * ... * static_cast<size_t>(dims));

  Tensor() { values_.fill(T{}); }
  Tensor(std::initializer_list<T> values) : Tensor() { view() = values; }
  Tensor(const T& v) requires(order == 0) { values_[0] = v; }

  template <class... I>
  requires(sizeof...(I) == order && (std::is_integral_v<I> && ...)) T& operator()(I... indices) {
    return view()(indices...);
  }
  template <class... I>
  requires(sizeof...(I) == order && (std::is_integral_v<I> && ...)) const T& operator()(
      I... indices) const {
    return const_cast<Tensor*>(this)->view()(indices...);
  }
  Tensor& operator=(const T& v) requires(order == 0) {
    values_[0] = v;
    return *this;
  }
  operator T() const requires(order == 0) { return values_[0]; }

  TensorRef<T, dims...> view() { return TensorRef<T, dims...>(values_.data()); }
  T* data() { return values_.data(); }
  const T* data() const { return values_.data(); }
  auto begin() { return values_.begin(); }
  auto end() { return values_.end(); }
  auto begin() const { return values_.begin(); }
  auto end() const { return values_.end(); }
  bool operator==(const Tensor&) const = default;

  TensorSlot slot() {
    return TensorSlot{
        ComponentTraits<T>::kind, ComponentTraits<T>::single, {dims...}, values_.data()};
  }

 private:
  std::array<T, size> values_;
};

}  // namespace simit
