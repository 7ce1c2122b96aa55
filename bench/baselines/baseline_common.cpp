// Pieces shared by the hand-written Eigen baselines.
#include "baseline_common.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <stdexcept>

namespace simit::baseline {

Options parse_options(int argc, char** argv, const std::string& default_input) {
  Options o;
  o.input = default_input;
  std::string name = argv[0];
  name = name.substr(name.find_last_of('/') + 1);
  o.csv = name + "_positions.csv";
  std::vector<std::string> positional;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--check") {
      o.check = true;
    } else if (arg == "--csv" && i + 1 < argc) {
      o.csv = argv[++i];
    } else if (arg == "--cg-tol" && i + 1 < argc) {
      o.cg_tol = std::atof(argv[++i]);
      if (!(o.cg_tol >= 0)) {
        std::fprintf(stderr, "%s: --cg-tol needs a number >= 0\n", name.c_str());
        std::exit(2);
      }
    } else if (arg == "--cg-max" && i + 1 < argc) {
      o.cg_max = std::atoi(argv[++i]);
      if (o.cg_max < 0) {
        std::fprintf(stderr, "%s: --cg-max needs a whole number >= 0\n", name.c_str());
        std::exit(2);
      }
    } else if (arg.starts_with("-")) {
      std::fprintf(stderr, "usage: %s [--check] [--csv FILE] [--cg-tol T] [--cg-max N] [INPUT] [FRAMES]\n", name.c_str());
      std::exit(2);
    } else {
      positional.push_back(arg);
    }
  }
  if (positional.size() > 0) o.input = positional[0];
  if (positional.size() > 1) o.frames = std::atoi(positional[1].c_str());
  if (positional.size() > 2 || o.frames < 0) {
    std::fprintf(stderr, "usage: %s [--check] [--csv FILE] [--cg-tol T] [--cg-max N] [INPUT] [FRAMES]\n", name.c_str());
    std::exit(2);
  }
  return o;
}

BlockPattern::BlockPattern(int vertex_count, const std::vector<int>& elements, int arity) {
  std::vector<std::vector<int>> adjacent(vertex_count);
  for (int v = 0; v < vertex_count; ++v) adjacent[v].push_back(v);
  for (size_t e = 0; e + arity <= elements.size(); e += arity)
    for (int a = 0; a < arity; ++a)
      for (int b = 0; b < arity; ++b) adjacent[elements[e + a]].push_back(elements[e + b]);
  first_.assign(vertex_count + 1, 0);
  diagonal_slot_.resize(vertex_count);
  for (int v = 0; v < vertex_count; ++v) {
    auto& n = adjacent[v];
    std::sort(n.begin(), n.end());
    n.erase(std::unique(n.begin(), n.end()), n.end());
    first_[v + 1] = first_[v] + static_cast<int>(n.size());
    neighbours_.insert(neighbours_.end(), n.begin(), n.end());
    diagonal_slot_[v] = static_cast<int>(std::lower_bound(n.begin(), n.end(), v) - n.begin());
  }
  // The CSR arrays are written directly: every scalar row of block row v lists the three
  // columns of each neighbour in order.
  const int n3 = 3 * vertex_count;
  a_.resize(n3, n3);
  a_.resizeNonZeros(9 * static_cast<Eigen::Index>(neighbours_.size()));
  int* outer = a_.outerIndexPtr();
  int* inner = a_.innerIndexPtr();
  int k = 0;
  for (int v = 0; v < vertex_count; ++v)
    for (int r = 0; r < 3; ++r) {
      outer[3 * v + r] = k;
      for (int s = first_[v]; s < first_[v + 1]; ++s)
        for (int c = 0; c < 3; ++c) inner[k++] = 3 * neighbours_[s] + c;
    }
  outer[n3] = k;
  set_zero();
}

int BlockPattern::slot(int i, int j) const {
  const auto begin = neighbours_.begin() + first_[i], end = neighbours_.begin() + first_[i + 1];
  const auto it = std::lower_bound(begin, end, j);
  if (it == end || *it != j) throw std::logic_error("block outside the pattern");
  return static_cast<int>(it - begin);
}

void BlockPattern::add(int i, int slot, const Mat3& block, double s) {
  const int* outer = a_.outerIndexPtr();
  double* values = a_.valuePtr();
  for (int r = 0; r < 3; ++r) {
    double* row = values + outer[3 * i + r] + 3 * slot;
    for (int c = 0; c < 3; ++c) row[c] += s * block(r, c);
  }
}

CgResult conjugate_gradient(const SparseMatrix& a, const Eigen::VectorXd& b, Eigen::VectorXd& x,
                            double tol, int max_iterations) {
  Eigen::VectorXd r = b - a * x;
  Eigen::VectorXd p = r;
  Eigen::VectorXd ap(b.size());
  double rr = r.dot(r);
  CgResult result;
  while (rr > tol && result.iterations < max_iterations) {
    ap.noalias() = a * p;
    const double alpha = rr / p.dot(ap);
    x += alpha * p;
    r -= alpha * ap;
    const double rr_new = r.dot(r);
    p = r + (rr_new / rr) * p;
    rr = rr_new;
    ++result.iterations;
  }
  result.residual = std::sqrt(rr / b.dot(b));
  return result;
}

double Stopwatch::lap_ms() {
  const auto now = std::chrono::steady_clock::now();
  const double ms = std::chrono::duration<double, std::milli>(now - start_).count();
  start_ = now;
  return ms;
}

void FrameLog::frame(int index, double first_ms, double second_ms, int iterations,
                     double residual) {
  ms.push_back({first_ms, second_ms});
  std::printf("frame %d: %s %.3f ms, %s %.3f ms", index, first_label.c_str(), first_ms,
              second_label.c_str(), second_ms);
  if (iterations >= 0) std::printf(", cg %d iterations, residual %.3e", iterations, residual);
  std::printf("\n");
}

void FrameLog::summary() const {
  if (ms.empty()) return;
  double a = 0, b = 0;
  for (const auto& m : ms) a += m[0], b += m[1];
  const double n = static_cast<double>(ms.size());
  std::printf("mean over %zu frames: %s %.3f ms, %s %.3f ms, total %.3f ms/frame\n", ms.size(),
              first_label.c_str(), a / n, second_label.c_str(), b / n, (a + b) / n);
}

bool finish(const Options& options, const std::vector<Vec3>& x) {
  std::ofstream out(options.csv);
  out.precision(17);
  out << "x,y,z\n";
  bool finite = true;
  for (const Vec3& p : x) {
    out << p.x() << ',' << p.y() << ',' << p.z() << '\n';
    finite = finite && p.allFinite();
  }
  if (!out) std::fprintf(stderr, "cannot write %s\n", options.csv.c_str());
  if (options.check && !finite) std::fprintf(stderr, "non-finite position\n");
  return bool(out) && (!options.check || finite);
}

}  // namespace simit::baseline
