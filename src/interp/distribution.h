// The seam of a distributed run (src/dist): each MPI rank runs the program over its local part
// of every set: the elements it owns and ghosts, copies of elements other ranks own, in the
// whole set's order. A rank holds every element of an edge set that touches a vertex it owns,
// so the rows of its owned vertices in an assembled matrix or vector are complete (their
// blocks summed in the order one process sums them); ghost rows are partial. The interpreter
// asks this seam for a reduction over a set (the owners' element sums, in the blocked order
// over the whole set), and to refresh a vector's ghost entries from their owners after an
// operation that leaves them partial (an assembled vector, a matrix-vector product). What
// cannot run this way yet is refused at its statement.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "runtime/set.h"
#include "runtime/system_matrix.h"

namespace simit::interp {

class Distribution {
 public:
  virtual ~Distribution() = default;
  // The local indices of the elements of `set` this rank owns, ascending; null for a set the
  // run does not split, which every rank holds and owns whole.
  virtual const std::vector<int32_t>* owned(const runtime::Set& set) const = 0;
  // Whether `set` is split over the ranks, so that its ghost entries need refreshing after a
  // partial write. Every rank answers alike (a refresh is collective), whatever its own part.
  virtual bool split(const runtime::Set& set) const = 0;
  // The sum over the whole set of `element_sums` (one per local element of `set`; the ghosts'
  // are not read), in the contract's blocked order over the whole set (docs/arithmetic.md):
  // the bits one process gets, on every rank. Collective.
  virtual double blocked_sum(const runtime::Set& set,
                             std::span<const double> element_sums) const = 0;
  // Overwrites the ghost entries of `values` (element_bytes bytes per element of `set`, in its
  // order) with their owners' entries. Collective: every rank calls it in the same order.
  virtual void refresh(const runtime::Set& set, std::span<std::byte> values,
                       size_t element_bytes) const = 0;
  // x = A \ b for a square matrix over `rows` (its owned rows complete), b and x over the same
  // local elements: x's owned entries (the interpreter then refreshes its ghosts). Collective.
  // False, with the reason in `why`, where the ranks cannot solve (the default).
  virtual bool solve(const runtime::SystemMatrix& a, const runtime::Set& rows,
                     std::span<const double> b, std::span<double> x, std::string& why) const {
    (void)a, (void)rows, (void)b, (void)x;
    why = "this build has no distributed solver";
    return false;
  }
};

}  // namespace simit::interp
