// Pieces shared by the hand-written Eigen baselines: command line, block sparse pattern, CG,
// timing and output.
#pragma once

#include <Eigen/Dense>
#include <Eigen/Sparse>

#include <array>
#include <chrono>
#include <string>
#include <vector>

namespace simit::baseline {

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;
using SparseMatrix = Eigen::SparseMatrix<double, Eigen::RowMajor>;

struct Options {
  std::string input;       // mesh path (or, for cloth, the grid size)
  int frames = 10;
  std::string csv;         // final positions go here
  bool check = false;      // exit nonzero when a position is not finite
  double cg_tol = -1.0;    // --cg-tol: CG stops at r'r <= cg_tol (< 0: the example's default)
  int cg_max = -1;         // --cg-max: CG iteration cap (< 0: the example's default)
};

// NAME [--check] [--csv FILE] [--cg-tol T] [--cg-max N] INPUT [FRAMES]; prints usage and exits on bad arguments.
Options parse_options(int argc, char** argv, const std::string& default_input);

// A 3n x 3n scalar CSR matrix made of 3x3 blocks, whose pattern (the diagonal plus every
// pair of vertices that share an element) is built once; assembly then adds into the values
// in place. The three scalar rows of a block row have the same columns, so block (i, j) is
// found by its slot (the rank of j among i's neighbours): entry (3i+r, 3j+c) is value
// outer[3i+r] + 3*slot + c.
class BlockPattern {
 public:
  // `elements` lists each element's vertices, `arity` per element.
  BlockPattern(int vertex_count, const std::vector<int>& elements, int arity);

  SparseMatrix& matrix() { return a_; }
  const SparseMatrix& matrix() const { return a_; }
  int slot(int i, int j) const;  // j must be a neighbour of i (or i itself)
  int diagonal_slot(int i) const { return diagonal_slot_[i]; }
  void set_zero() { std::fill_n(a_.valuePtr(), a_.nonZeros(), 0.0); }
  // Adds s * block at slot `slot` of block row i.
  void add(int i, int slot, const Mat3& block, double s = 1.0);

 private:
  SparseMatrix a_;
  std::vector<int> first_;   // start of each vertex's neighbour list in neighbours_
  std::vector<int> neighbours_;
  std::vector<int> diagonal_slot_;
};

struct CgResult {
  int iterations = 0;
  double residual = 0.0;  // |r| / |b| at exit
};

// Unpreconditioned CG from the initial guess in x, stopping at r'r <= tol or after
// max_iterations: the rule of the .sim programs, so iteration counts compare.
CgResult conjugate_gradient(const SparseMatrix& a, const Eigen::VectorXd& b, Eigen::VectorXd& x,
                            double tol, int max_iterations);

class Stopwatch {
 public:
  Stopwatch() : start_(std::chrono::steady_clock::now()) {}
  double lap_ms();  // since construction or the previous lap

 private:
  std::chrono::steady_clock::time_point start_;
};

// One line per frame and a mean at the end.
struct FrameLog {
  std::string first_label, second_label;  // what the two timings measure
  std::vector<std::array<double, 2>> ms;
  void frame(int index, double first_ms, double second_ms, int iterations = -1,
             double residual = 0.0);
  void summary() const;
};

// Writes "x,y,z" per vertex (17 significant digits) and, with options.check, returns false
// when a coordinate is not finite.
bool finish(const Options& options, const std::vector<Vec3>& x);

}  // namespace simit::baseline
