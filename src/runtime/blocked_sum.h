// The one order in which a reduction over a set is summed (docs/arithmetic.md, "Sums"): the
// elements in fixed chunks, each chunk over kSumLanes lane accumulators folded by a halving
// tree, the chunks' partials added in chunk order. It does not depend on the thread count or
// the device, so a threaded or GPU executor that computes the chunks' partials in parallel and
// combines them with combine_partials gives the interpreter's bits.
#pragma once

#include <complex>
#include <cstddef>

namespace simit::runtime {

// Lanes per chunk: a GPU warp, or eight 4-wide AVX2 vectors.
inline constexpr size_t kSumLanes = 32;
// Elements per chunk.
inline constexpr size_t kSumChunk = 256;
static_assert(kSumChunk % kSumLanes == 0, "a chunk is whole rounds of the lanes");
static_assert((kSumLanes & (kSumLanes - 1)) == 0, "the halving tree needs a power of two");

// Chunks of a reduction over `elements` elements (the last one may be short).
constexpr size_t sum_chunks(size_t elements) { return (elements + kSumChunk - 1) / kSumChunk; }

// The halving tree over kSumLanes accumulators: for w = 16, 8, 4, 2, 1 and i < w,
// a[i] = a[i] + a[i + w]. Returns a[0]; `a` is overwritten.
template <class T>
T fold_lanes(T* a) {
  for (size_t w = kSumLanes / 2; w >= 1; w /= 2)
    for (size_t i = 0; i < w; ++i) a[i] = a[i] + a[i + w];
  return a[0];
}

// One chunk's partial of sum over elements e in [begin_elem, end_elem) (at most kSumChunk of
// them, begin_elem the chunk's first) of t_e, where t_e sums x[c] * y[c] over the `group`
// components of element e from +0.0 in order: t_e goes to lane (e - begin_elem) % kSumLanes,
// the lanes start at +0.0, and fold_lanes gives the partial.
double chunk_partial(const double* x, const double* y, size_t group, size_t begin_elem,
                     size_t end_elem);
std::complex<double> chunk_partial(const std::complex<double>* x, const std::complex<double>* y,
                                   size_t group, size_t begin_elem, size_t end_elem);

// One chunk's partial from its element sums t_0 .. t_{count-1} (count <= kSumChunk), already
// summed: the lanes and the tree of chunk_partial. A distributed run's ranks use it on the
// element sums of chunks their owned elements fill, or that several ranks share.
double chunk_partial_of_sums(const double* sums, size_t count);

// +0.0 + partials[0] + partials[1] + ..., left to right.
double combine_partials(const double* partials, size_t chunks);

// The whole reduction: sum of x[k] * y[k] over k < n_components, in elements of `group`
// components (n_components a multiple of group; group >= 1), chunk by chunk.
double blocked_dot(const double* x, const double* y, size_t n_components, size_t group);
std::complex<double> blocked_dot(const std::complex<double>* x, const std::complex<double>* y,
                                 size_t n_components, size_t group);

}  // namespace simit::runtime
