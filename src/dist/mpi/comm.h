// The ranks of an MPI run as the distributed layer uses them: one communicator (the world),
// and the few collective operations its set-up needs. Every call is collective unless it
// says otherwise; an MPI error throws CommError (MPI's error handler returns instead of
// aborting, so that the caller reports it).
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "dist/overlap.h"

namespace simit::dist::mpi {

class CommError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// MPI from construction to destruction (MPI_Init, MPI_Finalize): one per process.
class Session {
 public:
  Session(int* argc, char*** argv);
  ~Session();
  Session(const Session&) = delete;
  Session& operator=(const Session&) = delete;

  int rank() const { return rank_; }
  int size() const { return size_; }

  // The sum over the ranks of each rank's `value`, on every rank.
  int64_t sum(int64_t value) const;
  // The sum of the ranks' `value`s below this one (0 on rank 0): where a rank's rows start in
  // a numbering of every rank's rows, one range after another.
  int64_t sum_below(int64_t value) const;
  // Every rank's `value`, in rank order, on `root` (empty elsewhere).
  std::vector<int64_t> gather(int64_t value, int root = 0) const;
  // `values` as `root` holds them, on every rank (resized there).
  void broadcast(std::vector<int32_t>& values, int root = 0) const;
  // `parts[r]` (one per rank, given on `root` only) on rank r: rank 0's part of a scene read
  // there, say. Point to point from `root`, in pieces an int counts.
  std::vector<std::byte> scatter(std::vector<std::vector<std::byte>> parts, int root = 0) const;
  // Overwrites the ghost entries of `values` (element_bytes bytes per local element, in local
  // order) with their owners' entries, as `plan` says: point to point with the plan's ranks
  // only (MPI_Isend/Irecv, then wait for all). Collective over the ranks of the plans, which
  // must be the layouts of one overlap_layout input (dist/overlap.h). Throws
  // std::invalid_argument, before any message, when an index of `plan` lies outside `values`
  // or element_bytes is 0.
  void refresh_ghosts(const GhostPlan& plan, std::span<std::byte> values,
                      size_t element_bytes) const;
  // Every rank's `values` (any number per rank), one after another in rank order, on every
  // rank.
  std::vector<double> all_gather(std::span<const double> values) const;
  // Each rank's owned entries (element_bytes per element, values[i] for global[i], i < count
  // of `global`) put together on `root` into the whole array of `whole` elements; empty
  // elsewhere. Throws std::invalid_argument on root when the ranks' `global` do not name each
  // element of [0, whole) exactly once, and on any rank whose `values` are too short.
  std::vector<std::byte> gather_owned(std::span<const int32_t> global,
                                      std::span<const std::byte> values, size_t element_bytes,
                                      int32_t whole, int root = 0) const;
  // Each of `values` replaced by its least over the ranks (the same count on every rank).
  void least(std::vector<int64_t>& values) const;
  // Whether `flag` is true on any rank (on every rank).
  bool any(bool flag) const;
  // Ends every rank of the run with `status` (not collective: one rank's failure).
  [[noreturn]] void abort(int status) const;
  // Waits for another rank's abort to end this one (a rank that failed alone reports, the
  // others wait for it rather than race it with a message of their own).
  [[noreturn]] void wait_for_abort() const;

 private:
  int rank_ = 0, size_ = 1;
};

}  // namespace simit::dist::mpi
