// Pieces shared by the hand-written Eigen baselines: command line, the OpenMP loops
// (--threads), a block-CSR matrix of 3x3 blocks, CG with fused vector passes, timing and output.
#pragma once

#include <Eigen/Dense>

#ifdef _OPENMP
#include <omp.h>
#endif

#include <algorithm>
#include <array>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace simit::baseline {

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;
using Vec3s = std::vector<Vec3>;

struct Options {
  std::string input;  // mesh path (or, for cloth, the grid size)
  int frames = 10;
  std::string csv;         // --csv: final positions go here (empty: not written)
  bool check = false;      // exit nonzero when a position is not finite
  double cg_tol = -1.0;    // --cg-tol: CG stops at r'r <= cg_tol (< 0: the example's default)
  int cg_max = -1;         // --cg-max: CG iteration cap (< 0: the example's default)
  bool sim_form = false;   // --sim-form: element matrices evaluated as the .sim writes them
  bool cpu_clock = false;  // --cpu-clock: frames timed in thread CPU time, not wall time
  int threads = 1;         // --threads: OpenMP threads of the frame loops (1: serial)
};

// NAME [--check] [--csv FILE] [--cg-tol T] [--cg-max N] [--cpu-clock] [--threads N]
// [--sim-form] INPUT [FRAMES]; prints usage and exits on bad arguments or --help (--sim-form
// only where has_sim_form). Sets the thread count of the loops below (thread_count()).
Options parse_options(int argc, char** argv, const std::string& default_input,
                      bool has_sim_form = false);

// The threads the loops below use: --threads, 1 unless given (and always 1 in a build
// without OpenMP, where parse_options refuses more).
int thread_count();

// Iterations a thread takes at least: a loop of n runs on min(thread_count(), n / 256)
// threads (at least 1). A fork and join costs microseconds, more than a few hundred
// iterations of the light loops; the count depends only on n, so the partial sums below
// (and so the results) stay fixed for a given --threads.
inline constexpr int kMinChunk = 256;
inline int threads_for(int n) { return std::max(1, std::min(thread_count(), n / kMinChunk)); }

// body(i) for i in [0, n). One thread runs the plain loop in order (the serial baseline,
// unchanged); more split it into contiguous static chunks, so body must write only data
// of its own i.
template <class Body>
void parallel_for(int n, Body&& body) {
#ifdef _OPENMP
  if (const int threads = threads_for(n); threads > 1) {
#pragma omp parallel for num_threads(threads) schedule(static)
    for (int i = 0; i < n; ++i) body(i);
    return;
  }
#endif
  for (int i = 0; i < n; ++i) body(i);
}

// start + term(0) + ... + term(n - 1), with term free to write data of its own i (the CG
// passes fuse their vector updates into their sums). One thread adds in order from start,
// exactly the serial loop. More each sum one contiguous chunk (the first from start, the
// others from 0) and the partial sums are added in chunk order: a fixed order, so a given
// thread count gives the same bits every run, unlike reduction(+:), whose combining order
// may vary.
template <class Term>
double parallel_sum(int n, double start, Term&& term) {
#ifdef _OPENMP
  if (const int threads = threads_for(n); threads > 1) {
    std::vector<double> partial(threads, 0.0);
#pragma omp parallel num_threads(threads)
    {
      const int t = omp_get_thread_num(), count = omp_get_num_threads();
      const int begin = static_cast<int>(static_cast<long long>(n) * t / count);
      const int end = static_cast<int>(static_cast<long long>(n) * (t + 1) / count);
      double sum = t == 0 ? start : 0.0;
      for (int i = begin; i < end; ++i) sum += term(i);
      partial[t] = sum;
    }
    double total = partial[0];
    for (int t = 1; t < threads; ++t) total += partial[t];
    return total;
  }
#endif
  double sum = start;
  for (int i = 0; i < n; ++i) sum += term(i);
  return sum;
}

// The element loops that add into their corners' forces and matrix blocks, partitioned:
// each thread takes one contiguous range of elements in mesh order and adds into its own
// copy of the forces and blocks (the first thread into the real ones); then the threads
// add the copies into the real ones, split by rows, in thread order, clearing the copies
// for the next call in the same pass.
// Chosen over a coloured loop (elements greedily coloured so that no two of a colour share
// a vertex, one colour at a time) by measuring fem's tet loop run on one thread in each
// order (thread CPU time, least of 4 or 5 runs on a shared, loaded 2-core machine): mesh
// order 1.9-2.8 ms on the bunny, 13-17 ms on dragon40k; colour order 5.3-5.8 ms and
// 31-37 ms (62 and 72 colours: consecutive tets of a colour share no vertex, so none finds
// the previous one's blocks in cache); two halves plus clearing and merging the second's
// copy 2.7-3.1 ms and 15-17.5 ms. Colouring groups of consecutive tets instead does not
// help: TetGen's numbering is local only at short range (groups of 64 tets nearly all
// conflict). The price of the partition is memory (a copy of the blocks per thread beyond
// the first) and a merge that costs each thread about one pass over the blocks however
// many threads there are. One thread runs the plain loop.
class PartitionedLoop {
 public:
  // Outputs of vertex_count forces and block_count blocks (0: forces only).
  PartitionedLoop(int vertex_count, int block_count) : n_(vertex_count), blocks_(block_count) {}

  // body(e, f, blocks) for e in [0, element_count): adds element e's terms into f[vertex] and
  // blocks[block index]. On return force and block hold the sums.
  template <class Body>
  void run(int element_count, Vec3* force, Mat3* block, Body&& body) {
#ifdef _OPENMP
    if (const int threads = threads_for(element_count); threads > 1) {
      reserve(threads);
#pragma omp parallel num_threads(threads)
      {
        // The team may be smaller than asked for: ranges follow its actual size.
        const int t = omp_get_thread_num(), count = omp_get_num_threads();
        Vec3* f = t == 0 ? force : private_f_[t - 1].data();
        Mat3* b = t == 0 ? block : private_blocks_[t - 1].data();
        const int begin = static_cast<int>(static_cast<long long>(element_count) * t / count);
        const int end = static_cast<int>(static_cast<long long>(element_count) * (t + 1) / count);
        for (int e = begin; e < end; ++e) body(e, f, b);
#pragma omp barrier
        merge(count, force, block);
      }
      return;
    }
#endif
    for (int e = 0; e < element_count; ++e) body(e, force, block);
  }

 private:
  void reserve(int threads);  // private copies (zero) for threads 1 .. threads - 1
  // force += copies, block += copies, each row in thread order; the copies are zeroed. Runs
  // inside the parallel region, splitting the rows over its threads.
  void merge(int threads, Vec3* force, Mat3* block);

  int n_, blocks_;
  std::vector<Vec3s> private_f_;
  std::vector<std::vector<Mat3>> private_blocks_;
};

// The blocks an assembly writes, collected before the matrix is built: the diagonal (every
// row keeps one, for the mass) plus each (row, column) pair added.
class BlockPatternBuilder {
 public:
  explicit BlockPatternBuilder(int block_rows);
  void add(int i, int j) { pairs_.push_back({i, j}); }
  int block_rows() const { return rows_; }
  // Sorted, duplicate-free pairs, diagonal included.
  std::vector<std::pair<int, int>> finish() &&;

 private:
  int rows_;
  std::vector<std::pair<int, int>> pairs_;
};

// A square matrix of 3x3 blocks in block-CSR order, its pattern fixed at construction; the
// assembly refills the values in place each frame through block indices it looks up once.
class BlockCsr {
 public:
  explicit BlockCsr(BlockPatternBuilder&& pattern);

  int block_rows() const { return static_cast<int>(row_start_.size()) - 1; }
  size_t block_count() const { return columns_.size(); }
  // Index of block (i, j) in blocks(), or -1 when the pattern does not hold it.
  int find(int i, int j) const;
  int diagonal(int i) const { return diagonal_[i]; }
  Mat3& block(int k) { return blocks_[k]; }
  Mat3* block_data() { return blocks_.data(); }  // block(k) is block_data()[k]
  void set_zero();
  // The products and the residual split the block rows over the threads (parallel_sum).
  // y = A p; returns p'y, summed in the same pass.
  double multiply_dot(const Vec3s& p, Vec3s& y) const;
  // r = b - A x and p = r; returns r'r, summed in the same pass.
  double residual(const Vec3s& b, const Vec3s& x, Vec3s& r, Vec3s& p) const;
  // Bytes one CG iteration streams at least: the blocks, their column indices and row
  // starts once, and every vector read or written by the three passes once.
  double cg_bytes_per_iteration() const;

 private:
  std::vector<int> row_start_;  // block row i holds blocks row_start_[i] .. row_start_[i+1]-1
  std::vector<int> columns_;
  std::vector<int> diagonal_;
  std::vector<Mat3> blocks_;
};

struct CgResult {
  int iterations = 0;
  double residual = 0.0;  // |r| / |b| at exit
};

// Unpreconditioned CG from the initial guess in x, stopping at r'r <= tol or after
// max_iterations: the rule of the .sim programs, so iteration counts compare. One
// iteration is three passes over the vectors: A p with p'Ap; x and r with r'r; p. Each
// pass splits the rows over the threads. The work vectors are allocated once.
class ConjugateGradient {
 public:
  explicit ConjugateGradient(int block_rows) : r_(block_rows), p_(block_rows), ap_(block_rows) {}
  CgResult solve(const BlockCsr& a, const Vec3s& b, Vec3s& x, double tol, int max_iterations);

 private:
  Vec3s r_, p_, ap_;
};

// Wall time, or with --cpu-clock this thread's CPU time (on a busy machine wall time also
// counts the time the thread waits for a core). The CPU clock counts the calling thread
// only, so parse_options refuses it with --threads above 1.
class Stopwatch {
 public:
  Stopwatch() : start_ms_(now_ms()) {}
  double lap_ms();  // since construction or the previous lap
  static void use_cpu_clock(bool on);

 private:
  static double now_ms();
  double start_ms_;
};

// One line per frame and, at the end, the median and mean (the machine's load shows in
// single frames; the median damps it). The line ends with the frame's total energy, printed
// to round-trip precision so that tests can compare it with the .sim program's.
struct FrameLog {
  std::string first_label, second_label;  // what the two timings measure
  std::vector<std::array<double, 2>> ms;
  // "frame N: FIRST a ms, SECOND b ms[, cg K iterations, residual R], energy E"
  void frame(int index, double first_ms, double second_ms, double energy,
             std::optional<CgResult> cg = std::nullopt);
  void summary() const;
};

// With --csv, writes "x,y,z" per vertex (17 significant digits) to that file; returns false
// when it cannot be written or, with options.check, when a coordinate is not finite.
bool finish(const Options& options, const Vec3s& x);

}  // namespace simit::baseline
