// Binary32 values of system matrices and vectors (runtime/system_ops.h): whether every value
// is one, and a matrix's values rounded to them (--float32, docs/arithmetic.md).
#include <algorithm>
#include <bit>
#include <cstdint>
#include <type_traits>

#include "runtime/system_ops.h"

namespace simit::runtime {

namespace {

// Whether rounding v[0 .. n-1] to binary32 leaves every bit as it is: a comparison of bits,
// which vectorises (a comparison of doubles with its NaN case runs value by value). A NaN
// whose payload the rounding changes fails it, though it counts as a binary32 value. The
// binary32 checks run it over chunks of kBitsChunk values.
constexpr size_t kBitsChunk = 2048;
bool same_bits_as_binary32(const double* v, size_t n) {
  uint64_t differ = 0;
  for (size_t i = 0; i < n; ++i)
    differ |= std::bit_cast<uint64_t>(static_cast<double>(static_cast<float>(v[i]))) ^
              std::bit_cast<uint64_t>(v[i]);
  return differ == 0;
}

template <class T>
bool binary32_values(const T* v, size_t n) {
  if constexpr (std::is_same_v<T, double>) {
    // Chunk by chunk, first by bits, which vectorises; a chunk whose bits the rounding changes
    // value by value (a NaN counts as a binary32 value whatever its payload).
    for (size_t at = 0; at < n; at += kBitsChunk) {
      const size_t end = std::min(n, at + kBitsChunk);
      if (same_bits_as_binary32(v + at, end - at)) continue;
      for (size_t i = at; i < end; ++i)
        if (!is_binary32(v[i])) return false;
    }
    return true;
  } else {
    bool all = true;
    for (size_t i = 0; i < n; ++i) {
      if constexpr (std::is_same_v<T, Complex>)
        all = all && is_binary32(v[i].real()) && is_binary32(v[i].imag());
      else
        all = all && is_binary32(v[i]);
    }
    return all;
  }
}

}  // namespace

void round_to_float32(SystemMatrix& m) {
  const size_t n = m.value_count();  // read once, as round_to_float32(Tensor&) does
  if (m.kind() == ComponentKind::Float) {
    double* v = m.values();
    // Chunk by chunk, a chunk whose values are binary32 values already (a map's sums, each
    // addition rounded) only read: on fem dragon160k's 31 MB stiffness the pass then writes
    // nothing (a NaN whose bits the rounding changes is rounded, as before).
    for (size_t at = 0; at < n; at += kBitsChunk) {
      const size_t end = std::min(n, at + kBitsChunk);
      if (!same_bits_as_binary32(v + at, end - at))
        for (size_t i = at; i < end; ++i) v[i] = static_cast<float>(v[i]);
    }
  } else if (m.kind() == ComponentKind::Complex) {
    Complex* c = m.complexes();
    for (size_t i = 0; i < n; ++i)
      c[i] = Complex(static_cast<float>(c[i].real()), static_cast<float>(c[i].imag()));
  }
}

bool is_binary32(std::span<const double> values) {
  return binary32_values(values.data(), values.size());
}

bool is_binary32(const SystemMatrix& m) {
  if (m.kind() == ComponentKind::Float) return binary32_values(m.values(), m.value_count());
  if (m.kind() == ComponentKind::Complex) return binary32_values(m.complexes(), m.value_count());
  return true;
}

}  // namespace simit::runtime
