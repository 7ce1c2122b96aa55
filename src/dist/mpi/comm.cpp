// The distributed layer's use of MPI (dist/mpi/comm.h).
#include "dist/mpi/comm.h"

#include <mpi.h>

#include <algorithm>
#include <cstdlib>

namespace simit::dist::mpi {

namespace {

void check(int status, const char* what) {
  if (status == MPI_SUCCESS) return;
  char text[MPI_MAX_ERROR_STRING];
  int length = 0;
  MPI_Error_string(status, text, &length);
  throw CommError(std::string(what) + " failed: " + std::string(text, static_cast<size_t>(length)));
}

}  // namespace

Session::Session(int* argc, char*** argv) {
  check(MPI_Init(argc, argv), "MPI_Init");
  MPI_Comm_set_errhandler(MPI_COMM_WORLD, MPI_ERRORS_RETURN);
  check(MPI_Comm_rank(MPI_COMM_WORLD, &rank_), "MPI_Comm_rank");
  check(MPI_Comm_size(MPI_COMM_WORLD, &size_), "MPI_Comm_size");
}

Session::~Session() { MPI_Finalize(); }

int64_t Session::sum(int64_t value) const {
  int64_t total = 0;
  check(MPI_Allreduce(&value, &total, 1, MPI_INT64_T, MPI_SUM, MPI_COMM_WORLD), "MPI_Allreduce");
  return total;
}

std::vector<int64_t> Session::gather(int64_t value, int root) const {
  std::vector<int64_t> all(rank_ == root ? static_cast<size_t>(size_) : 0);
  check(MPI_Gather(&value, 1, MPI_INT64_T, all.data(), 1, MPI_INT64_T, root, MPI_COMM_WORLD),
        "MPI_Gather");
  return all;
}

void Session::broadcast(std::vector<int32_t>& values, int root) const {
  int64_t n = static_cast<int64_t>(values.size());
  check(MPI_Bcast(&n, 1, MPI_INT64_T, root, MPI_COMM_WORLD), "MPI_Bcast");
  values.resize(static_cast<size_t>(n));
  // In pieces that an int counts.
  constexpr int64_t kPiece = int64_t{1} << 30;
  for (int64_t at = 0; at < n; at += kPiece)
    check(MPI_Bcast(values.data() + at, static_cast<int>(std::min(kPiece, n - at)), MPI_INT32_T,
                    root, MPI_COMM_WORLD),
          "MPI_Bcast");
}

void Session::abort(int status) const {
  MPI_Abort(MPI_COMM_WORLD, status);
  std::abort();  // MPI_Abort does not return; the compiler is told so
}

}  // namespace simit::dist::mpi
