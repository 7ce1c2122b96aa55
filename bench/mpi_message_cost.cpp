// The cost of one MPI message between two ranks, and of an MPI_Allgather of one double: the
// per-message figures bench/scaling_model.py's strong-scaling model starts from.
//
// Build and run (bench/scaling_model.py does both):
//   mpicxx -O2 -std=c++20 bench/mpi_message_cost.cpp -o mpi_message_cost
//   mpirun -np 2 ./mpi_message_cost
// Rank 0 prints CSV lines: kind,bytes,repeats,median_us,min_us. "pingpong" is half a round
// trip of MPI_Send/MPI_Recv (rank 0 sends, rank 1 sends the same bytes back), "allgather" one
// MPI_Allgather of a double over the ranks. Each repeat is timed on its own and the median
// kept, so that a descheduled repeat on a loaded machine moves the figure little.
// OpenMPI's C++ bindings (not used here) do not compile cleanly under -Wextra.
#define OMPI_SKIP_MPICXX 1
#include <mpi.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <vector>

namespace {

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// Fewer repeats for large messages: each costs more, and their spread is smaller.
int repeats_for(size_t bytes) {
  if (bytes <= 4096) return 20000;
  if (bytes <= 65536) return 4000;
  return 400;
}

void report(const char* kind, size_t bytes, const std::vector<double>& seconds) {
  double lo = *std::min_element(seconds.begin(), seconds.end());
  std::printf("%s,%zu,%zu,%.4f,%.4f\n", kind, bytes, seconds.size(), median(seconds) * 1e6,
              lo * 1e6);
  std::fflush(stdout);
}

void ping_pong(int rank, size_t bytes) {
  std::vector<char> buffer(bytes, 1);
  int repeats = repeats_for(bytes);
  int warm = repeats / 10 + 10;  // first touches, and the transport's set-up
  std::vector<double> half_trips;
  half_trips.reserve(repeats);
  int count = static_cast<int>(bytes);
  for (int i = 0; i < warm + repeats; ++i) {
    MPI_Barrier(MPI_COMM_WORLD);
    double t0 = MPI_Wtime();
    if (rank == 0) {
      MPI_Send(buffer.data(), count, MPI_BYTE, 1, 0, MPI_COMM_WORLD);
      MPI_Recv(buffer.data(), count, MPI_BYTE, 1, 0, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
    } else if (rank == 1) {
      MPI_Recv(buffer.data(), count, MPI_BYTE, 0, 0, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
      MPI_Send(buffer.data(), count, MPI_BYTE, 0, 0, MPI_COMM_WORLD);
    }
    double t = MPI_Wtime() - t0;
    if (i >= warm) half_trips.push_back(0.5 * t);
  }
  if (rank == 0) report("pingpong", bytes, half_trips);
}

void allgather_double(int rank, int size) {
  const int repeats = 20000, warm = 2000;
  std::vector<double> all(size);
  std::vector<double> times;
  times.reserve(repeats);
  double mine = rank + 0.5;
  for (int i = 0; i < warm + repeats; ++i) {
    MPI_Barrier(MPI_COMM_WORLD);
    double t0 = MPI_Wtime();
    MPI_Allgather(&mine, 1, MPI_DOUBLE, all.data(), 1, MPI_DOUBLE, MPI_COMM_WORLD);
    double t = MPI_Wtime() - t0;
    if (i >= warm) times.push_back(t);
  }
  if (all[size - 1] != size - 0.5) {
    std::fprintf(stderr, "mpi_message_cost: MPI_Allgather returned a wrong value\n");
    MPI_Abort(MPI_COMM_WORLD, 1);
  }
  if (rank == 0) report("allgather", sizeof(double), times);
}

}  // namespace

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  int rank = 0, size = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  if (size < 2) {
    if (rank == 0) std::fprintf(stderr, "mpi_message_cost: run it on 2 ranks (mpirun -np 2)\n");
    MPI_Finalize();
    return 2;
  }
  if (rank == 0) std::printf("kind,bytes,repeats,median_us,min_us\n");
  for (size_t bytes = 8; bytes <= (size_t{1} << 20); bytes *= 2) ping_pong(rank, bytes);
  allgather_double(rank, size);
  MPI_Finalize();
  return 0;
}
