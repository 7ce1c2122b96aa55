// The ranks of an MPI run as the distributed layer uses them: one communicator (the world),
// and the few collective operations its set-up needs. Every call is collective unless it
// says otherwise; an MPI error throws CommError (MPI's error handler returns instead of
// aborting, so that the caller reports it).
#pragma once

#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

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
  // Every rank's `value`, in rank order, on `root` (empty elsewhere).
  std::vector<int64_t> gather(int64_t value, int root = 0) const;
  // `values` as `root` holds them, on every rank (resized there).
  void broadcast(std::vector<int32_t>& values, int root = 0) const;
  // Ends every rank of the run with `status` (not collective: one rank's failure).
  [[noreturn]] void abort(int status) const;

 private:
  int rank_ = 0, size_ = 1;
};

}  // namespace simit::dist::mpi
