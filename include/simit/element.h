// Element handles, host component types and typed views of one element's field value.
#pragma once

#include <array>
#include <compare>
#include <complex>
#include <cstddef>
#include <cstdint>
#include <initializer_list>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

namespace simit {

using double_complex = std::complex<double>;
using float_complex = std::complex<float>;

// Misuse of the API (a bad handle, a wrong component type, a bind that does not match the
// program). Compile errors and run-time errors of programs derive from it (program.h).
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A handle to one element of one set: its index (elements are numbered 0, 1, ... in
// insertion order). Only meaningful for the set that created it.
class ElementRef {
 public:
  ElementRef() = default;
  explicit ElementRef(int ident) : ident_(ident) {}
  int ident() const { return ident_; }
  bool defined() const { return ident_ >= 0; }
  int getIdent() const { return ident_; }
  auto operator<=>(const ElementRef&) const = default;

 private:
  int ident_ = -1;
};

// What a field or tensor component holds (the runtime's storage kinds a host can bind).
enum class ComponentKind : uint8_t { Int, Float, Bool, Complex };

// A field's type described at run time: component kind, dimensions (empty: a scalar) and
// whether float components are stored as binary32.
struct FieldType {
  ComponentKind kind = ComponentKind::Float;
  std::vector<int> dims;
  bool single = false;
  bool operator==(const FieldType&) const = default;
};

// The host types a field or tensor component may have, and how the runtime stores them.
// `double` is Simit `float` at binary64, `float` is Simit `float` stored as binary32.
template <class T>
struct ComponentTraits;
template <>
struct ComponentTraits<double> {
  static constexpr ComponentKind kind = ComponentKind::Float;
  static constexpr bool single = false;
};
template <>
struct ComponentTraits<float> {
  static constexpr ComponentKind kind = ComponentKind::Float;
  static constexpr bool single = true;
};
template <>
struct ComponentTraits<int32_t> {
  static constexpr ComponentKind kind = ComponentKind::Int;
  static constexpr bool single = false;
};
template <>
struct ComponentTraits<bool> {
  static constexpr ComponentKind kind = ComponentKind::Bool;
  static constexpr bool single = false;
};
template <>
struct ComponentTraits<double_complex> {
  static constexpr ComponentKind kind = ComponentKind::Complex;
  static constexpr bool single = false;
};
template <>
struct ComponentTraits<float_complex> {
  static constexpr ComponentKind kind = ComponentKind::Complex;
  static constexpr bool single = true;
};

template <class T>
concept Component = requires {
  ComponentTraits<T>::kind;
};

// The field type of a host field `FieldRef<T, dims...>`.
template <Component T, int... dims>
FieldType field_type_of() {
  return FieldType{ComponentTraits<T>::kind, {dims...}, ComponentTraits<T>::single};
}

// A view of one tensor of fixed dimensions stored row-major at `data` (a field value of one
// element, or a host tensor). Scalar views (no dims) convert to and from T.
template <Component T, int... dims>
class TensorRef {
 public:
  static constexpr int order = sizeof...(dims);
  static constexpr size_t size = (size_t{1} * ... * static_cast<size_t>(dims));

  explicit TensorRef(T* data) : data_(data) {}

  template <class... I>
  requires(sizeof...(I) == order && (std::is_integral_v<I> && ...)) T& operator()(
      I... indices) const {
    return data_[offset({static_cast<int>(indices)...})];
  }
  // All components in row-major order; the list must have exactly `size` values.
  const TensorRef& operator=(std::initializer_list<T> values) const {
    if (values.size() != size)
      throw Error("expected " + std::to_string(size) + " components but got " +
                  std::to_string(values.size()));
    size_t i = 0;
    for (const T& v : values) data_[i++] = v;
    return *this;
  }
  const TensorRef& operator=(const T& v) const requires(order == 0) {
    *data_ = v;
    return *this;
  }
  operator T() const requires(order == 0) { return *data_; }
  T* data() const { return data_; }
  T* begin() const { return data_; }
  T* end() const { return data_ + size; }

 private:
  static size_t offset(std::array<int, order> idx) {
    constexpr std::array<int, order> extent{dims...};
    size_t off = 0;
    for (int k = 0; k < order; ++k) {
      if (idx[k] < 0 || idx[k] >= extent[k])
        throw Error("index " + std::to_string(idx[k]) + " out of range for dimension " +
                    std::to_string(k) + " of size " + std::to_string(extent[k]));
      off = off * extent[k] + idx[k];
    }
    return off;
  }
  T* data_;
};

}  // namespace simit
