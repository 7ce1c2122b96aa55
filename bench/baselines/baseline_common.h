// Pieces shared by the hand-written Eigen baselines: command line, a block-CSR matrix of 3x3
// blocks, CG with fused vector passes, timing and output.
#pragma once

#include <Eigen/Dense>

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
};

// NAME [--check] [--csv FILE] [--cg-tol T] [--cg-max N] [--cpu-clock] [--sim-form] INPUT
// [FRAMES]; prints usage and exits on bad arguments or --help (--sim-form only where
// has_sim_form).
Options parse_options(int argc, char** argv, const std::string& default_input,
                      bool has_sim_form = false);

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
// iteration is three passes over the vectors: A p with p'Ap; x and r with r'r; p. The
// work vectors are allocated once.
class ConjugateGradient {
 public:
  explicit ConjugateGradient(int block_rows) : r_(block_rows), p_(block_rows), ap_(block_rows) {}
  CgResult solve(const BlockCsr& a, const Vec3s& b, Vec3s& x, double tol, int max_iterations);

 private:
  Vec3s r_, p_, ap_;
};

// Wall time, or with --cpu-clock this thread's CPU time (on a busy machine wall time also
// counts the time the thread waits for a core; the baselines run on one thread).
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
