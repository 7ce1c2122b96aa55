// Pieces shared by the hand-written Eigen baselines: command line, the OpenMP loops
// (--threads), a block-CSR matrix of 3x3 blocks, CG with fused vector passes, timing and output.
#pragma once

#include <Eigen/Dense>

#ifdef _OPENMP
#include <omp.h>
#endif

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

// body(i) for i in [0, n). One thread runs the plain loop in order (the serial baseline,
// unchanged); more split it into contiguous static chunks, so body must write only data
// of its own i.
template <class Body>
void parallel_for(int n, Body&& body) {
#ifdef _OPENMP
  if (const int threads = thread_count(); threads > 1) {
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
  if (const int threads = thread_count(); threads > 1) {
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

// The schedule of an element loop that scatters into its corners' entries (forces, matrix
// blocks): a greedy colouring of the elements, in mesh order, so that no two elements of a
// colour share a vertex; the threads split each colour and wait for each other between
// colours. Chosen over a partitioned loop (contiguous ranges, each thread adding into a
// private copy of the forces and blocks, merged after) because the matrix is the large
// output: the private copies cost memory per thread and a zeroing and merging pass over
// all the blocks every frame, a pass that does not shrink as threads are added while the
// element work does. The colouring costs a barrier per colour and some locality. The sums
// it gives are the same for every thread count above 1. One thread visits the elements in
// mesh order without colouring: the serial baseline, unchanged.
class ElementColouring {
 public:
  // Elements given by their corners' vertex indices, all below vertex_count. Colours only
  // when thread_count() > 1 (call parse_options first).
  template <size_t Corners>
  ElementColouring(const std::vector<std::array<int, Corners>>& elements, int vertex_count)
      : element_count_(static_cast<int>(elements.size())) {
    std::vector<int> corners;
    if (thread_count() > 1) {
      corners.reserve(elements.size() * Corners);
      for (const auto& element : elements)
        corners.insert(corners.end(), element.begin(), element.end());
    }
    colour(corners, static_cast<int>(Corners), vertex_count);
  }

  int colour_count() const { return static_cast<int>(colour_start_.size()) - 1; }
  // body(e) for every element e: in mesh order on one thread, else colour by colour.
  template <class Body>
  void for_each(Body&& body) const {
#ifdef _OPENMP
    if (const int threads = thread_count(); threads > 1) {
#pragma omp parallel num_threads(threads)
      for (int c = 0; c < colour_count(); ++c) {
#pragma omp for schedule(static)
        for (int k = colour_start_[c]; k < colour_start_[c + 1]; ++k) body(order_[k]);
      }
      return;
    }
#endif
    for (int e = 0; e < element_count_; ++e) body(e);
  }

 private:
  // Fills order_ and colour_start_ from the elements' corners, corner_count per element.
  void colour(const std::vector<int>& corners, int corner_count, int vertex_count);

  int element_count_;
  std::vector<int> order_;            // the elements colour by colour, mesh order within one
  std::vector<int> colour_start_{0};  // colour c: order_[colour_start_[c] .. colour_start_[c+1])
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
