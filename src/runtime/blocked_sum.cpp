// The blocked order of reductions over sets (runtime/blocked_sum.h), as plain loops.
#include "runtime/blocked_sum.h"

#include <algorithm>

namespace simit::runtime {

namespace {

template <class T>
T chunk_partial_of(const T* x, const T* y, size_t group, size_t begin_elem, size_t end_elem) {
  T lanes[kSumLanes] = {};
  for (size_t e = begin_elem; e < end_elem; ++e) {
    T t{};
    const size_t first = e * group;
    for (size_t c = 0; c < group; ++c) t = t + x[first + c] * y[first + c];
    T& lane = lanes[(e - begin_elem) % kSumLanes];
    lane = lane + t;
  }
  return fold_lanes(lanes);
}

template <class T>
T blocked_dot_of(const T* x, const T* y, size_t n_components, size_t group) {
  const size_t elements = n_components / group;
  T sum{};
  for (size_t begin = 0; begin < elements; begin += kSumChunk)
    sum = sum + chunk_partial_of(x, y, group, begin, std::min(elements, begin + kSumChunk));
  return sum;
}

}  // namespace

double chunk_partial(const double* x, const double* y, size_t group, size_t begin_elem,
                     size_t end_elem) {
  return chunk_partial_of(x, y, group, begin_elem, end_elem);
}

std::complex<double> chunk_partial(const std::complex<double>* x, const std::complex<double>* y,
                                   size_t group, size_t begin_elem, size_t end_elem) {
  return chunk_partial_of(x, y, group, begin_elem, end_elem);
}

double chunk_partial_of_sums(const double* sums, size_t count) {
  double lanes[kSumLanes] = {};
  const size_t n = std::min(count, kSumChunk);
  // Whole rounds of the lanes first, each lane's additions independent of the others' (so the
  // compiler can use vector additions; the order within a lane is unchanged), then the rest.
  size_t e = 0;
  for (; e + kSumLanes <= n; e += kSumLanes)
    for (size_t l = 0; l < kSumLanes; ++l) lanes[l] = lanes[l] + sums[e + l];
  for (size_t l = 0; e + l < n; ++l) lanes[l] = lanes[l] + sums[e + l];
  return fold_lanes(lanes);
}

double combine_partials(const double* partials, size_t chunks) {
  double sum = 0.0;
  for (size_t k = 0; k < chunks; ++k) sum = sum + partials[k];
  return sum;
}

double blocked_dot(const double* x, const double* y, size_t n_components, size_t group) {
  return blocked_dot_of(x, y, n_components, group);
}

std::complex<double> blocked_dot(const std::complex<double>* x, const std::complex<double>* y,
                                 size_t n_components, size_t group) {
  return blocked_dot_of(x, y, n_components, group);
}

}  // namespace simit::runtime
