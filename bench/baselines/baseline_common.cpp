// Pieces shared by the hand-written Eigen baselines.
#include "baseline_common.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <fstream>
#include <numeric>

namespace simit::baseline {

namespace {

int threads_in_use = 1;  // --threads, read through thread_count()

// Prints the usage to stdout and exits 0 for --help, to stderr and exits 2 for bad arguments.
[[noreturn]] void usage(const std::string& name, bool has_sim_form, bool asked = false) {
  std::FILE* out = asked ? stdout : stderr;
#ifdef _OPENMP
  const char* threads_note = "";
#else
  const char* threads_note = ";\n               this build has no OpenMP, so only 1";
#endif
  std::fprintf(
      out,
      "usage: %s [--check] [--csv FILE] [--cg-tol T] [--cg-max N] [--cpu-clock] [--threads N]%s "
      "[INPUT] [FRAMES]\n"
      "  --csv FILE   write the final positions to FILE (x,y,z per vertex); without it\n"
      "               no positions are written\n"
      "  --check      exit nonzero when a final position is not finite\n"
      "  --cg-tol T   CG stops at r'r <= T (default: the example's)\n"
      "  --cg-max N   CG iteration cap (default: the example's)\n"
      "  --cpu-clock  time frames in thread CPU time instead of wall time (one thread only)\n"
      "  --threads N  run the frame loops on N OpenMP threads (default 1: the serial loops,\n"
      "               whose results and times compare with runs made before the option)%s\n"
      "%s"
      "  --help       print this and exit\n",
      name.c_str(), has_sim_form ? " [--sim-form]" : "", threads_note,
      has_sim_form ? "  --sim-form   evaluate element matrices as the .sim writes them\n" : "");
  std::exit(asked ? 0 : 2);
}

}  // namespace

Options parse_options(int argc, char** argv, const std::string& default_input, bool has_sim_form) {
  Options o;
  o.input = default_input;
  std::string name = argv[0];
  name = name.substr(name.find_last_of('/') + 1);
  std::vector<std::string> positional;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--help" || arg == "-h") {
      usage(name, has_sim_form, true);
    } else if (arg == "--check") {
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
    } else if (arg == "--cpu-clock") {
      o.cpu_clock = true;
    } else if (arg == "--threads" && i + 1 < argc) {
      const char* text = argv[++i];
      char* end = nullptr;
      const long threads = std::strtol(text, &end, 10);
      if (end == text || *end != '\0' || threads < 1 || threads > 4096) {
        std::fprintf(stderr, "%s: --threads needs a whole number from 1 to 4096, got '%s'\n",
                     name.c_str(), text);
        std::exit(2);
      }
      o.threads = static_cast<int>(threads);
    } else if (arg == "--sim-form" && has_sim_form) {
      o.sim_form = true;
    } else if (arg.starts_with("-")) {
      usage(name, has_sim_form);
    } else {
      positional.push_back(arg);
    }
  }
  if (positional.size() > 0) o.input = positional[0];
  if (positional.size() > 1) o.frames = std::atoi(positional[1].c_str());
  if (positional.size() > 2 || o.frames < 0) usage(name, has_sim_form);
#ifndef _OPENMP
  if (o.threads > 1) {
    std::fprintf(stderr,
                 "%s: --threads %d is unavailable: this build has no OpenMP (CMake found none "
                 "for the compiler), so the baselines run on one thread only\n",
                 name.c_str(), o.threads);
    std::exit(2);
  }
#endif
  if (o.cpu_clock && o.threads > 1) {
    std::fprintf(stderr,
                 "%s: --cpu-clock cannot go with --threads %d: it times the main thread's CPU "
                 "time, which leaves out the other threads' work; time threaded runs in wall "
                 "time (without --cpu-clock)\n",
                 name.c_str(), o.threads);
    std::exit(2);
  }
  Stopwatch::use_cpu_clock(o.cpu_clock);
  threads_in_use = o.threads;
  return o;
}

int thread_count() { return threads_in_use; }

void PartitionedLoop::reserve(int threads) {
  // Allocated once, zeroed here and kept zero by merge(); the first thread needs none.
  while (static_cast<int>(private_f_.size()) < threads - 1) {
    private_f_.emplace_back(n_, Vec3::Zero());
    private_blocks_.emplace_back(blocks_, Mat3::Zero());
  }
}

void PartitionedLoop::merge(int threads, Vec3* force, Mat3* block) {
#ifdef _OPENMP
#pragma omp for schedule(static) nowait
  for (int k = 0; k < blocks_; ++k)
    for (int t = 1; t < threads; ++t) {
      block[k] += private_blocks_[t - 1][k];
      private_blocks_[t - 1][k].setZero();
    }
#pragma omp for schedule(static)
  for (int i = 0; i < n_; ++i)
    for (int t = 1; t < threads; ++t) {
      force[i] += private_f_[t - 1][i];
      private_f_[t - 1][i].setZero();
    }
#else
  (void)threads, (void)force, (void)block;
#endif
}

BlockPatternBuilder::BlockPatternBuilder(int block_rows) : rows_(block_rows) {
  pairs_.reserve(block_rows);
  for (int i = 0; i < block_rows; ++i) pairs_.push_back({i, i});
}

std::vector<std::pair<int, int>> BlockPatternBuilder::finish() && {
  std::sort(pairs_.begin(), pairs_.end());
  pairs_.erase(std::unique(pairs_.begin(), pairs_.end()), pairs_.end());
  return std::move(pairs_);
}

BlockCsr::BlockCsr(BlockPatternBuilder&& pattern) {
  const int n = pattern.block_rows();
  const std::vector<std::pair<int, int>> pairs = std::move(pattern).finish();
  row_start_.assign(n + 1, 0);
  columns_.reserve(pairs.size());
  for (const auto& [i, j] : pairs) {
    ++row_start_[i + 1];
    columns_.push_back(j);
  }
  for (int i = 0; i < n; ++i) row_start_[i + 1] += row_start_[i];
  diagonal_.resize(n);
  for (int i = 0; i < n; ++i) diagonal_[i] = find(i, i);
  blocks_.assign(columns_.size(), Mat3::Zero());
}

int BlockCsr::find(int i, int j) const {
  const auto begin = columns_.begin() + row_start_[i], end = columns_.begin() + row_start_[i + 1];
  const auto it = std::lower_bound(begin, end, j);
  return it == end || *it != j ? -1 : static_cast<int>(it - columns_.begin());
}

void BlockCsr::set_zero() {
  parallel_for(static_cast<int>(blocks_.size()), [&](int k) { blocks_[k].setZero(); });
}

// The product reads blocks and vectors as plain double arrays, with three scalar row sums:
// a few percent faster here than Eigen's fixed-size 3x3 product on a 160k-tet mesh.
static_assert(sizeof(Mat3) == 9 * sizeof(double) && sizeof(Vec3) == 3 * sizeof(double));

double BlockCsr::multiply_dot(const Vec3s& p, Vec3s& y) const {
  const int n = block_rows();
  const int* start = row_start_.data();
  const int* cols = columns_.data();
  const double* blocks = blocks_.data()->data();  // column-major 3x3, 9 doubles apart
  const double* pv = p.data()->data();
  double* yv = y.data()->data();
  // By rows: each thread writes only its own rows of y.
  return parallel_sum(n, 0.0, [=](int i) {
    double y0 = 0.0, y1 = 0.0, y2 = 0.0;
    for (int k = start[i]; k < start[i + 1]; ++k) {
      const double* b = blocks + 9 * static_cast<size_t>(k);
      const double* q = pv + 3 * static_cast<size_t>(cols[k]);
      y0 += b[0] * q[0] + b[3] * q[1] + b[6] * q[2];
      y1 += b[1] * q[0] + b[4] * q[1] + b[7] * q[2];
      y2 += b[2] * q[0] + b[5] * q[1] + b[8] * q[2];
    }
    yv[3 * i] = y0, yv[3 * i + 1] = y1, yv[3 * i + 2] = y2;
    return pv[3 * i] * y0 + pv[3 * i + 1] * y1 + pv[3 * i + 2] * y2;
  });
}

double BlockCsr::residual(const Vec3s& b, const Vec3s& x, Vec3s& r, Vec3s& p) const {
  return parallel_sum(block_rows(), 0.0, [&](int i) {
    Vec3 acc = b[i];
    for (int k = row_start_[i]; k < row_start_[i + 1]; ++k)
      acc.noalias() -= blocks_[k] * x[columns_[k]];
    r[i] = acc;
    p[i] = acc;
    return acc.squaredNorm();
  });
}

double BlockCsr::cg_bytes_per_iteration() const {
  const double n = block_rows(), blocks = static_cast<double>(block_count());
  const double matrix = blocks * (sizeof(Mat3) + sizeof(int)) + (n + 1) * sizeof(int);
  // A p: p in, Ap out; x, r: x, p, r, Ap in, x, r out; p: r, p in, p out.
  const double vectors = (2 + 6 + 3) * n * sizeof(Vec3);
  return matrix + vectors;
}

CgResult ConjugateGradient::solve(const BlockCsr& a, const Vec3s& b, Vec3s& x, double tol,
                                  int max_iterations) {
  const int n = a.block_rows();
  double rr = a.residual(b, x, r_, p_);
  CgResult result;
  while (rr > tol && result.iterations < max_iterations) {
    const double alpha = rr / a.multiply_dot(p_, ap_);
    const double rr_new = parallel_sum(n, 0.0, [&](int i) {
      x[i] += alpha * p_[i];
      r_[i] -= alpha * ap_[i];
      return r_[i].squaredNorm();
    });
    const double beta = rr_new / rr;
    parallel_for(n, [&](int i) { p_[i] = r_[i] + beta * p_[i]; });
    rr = rr_new;
    ++result.iterations;
  }
  const double bb = parallel_sum(n, 0.0, [&](int i) { return b[i].squaredNorm(); });
  result.residual = std::sqrt(rr / bb);
  return result;
}

namespace {
clockid_t stopwatch_clock = CLOCK_MONOTONIC;
}

void Stopwatch::use_cpu_clock(bool on) {
  stopwatch_clock = on ? CLOCK_THREAD_CPUTIME_ID : CLOCK_MONOTONIC;
}

double Stopwatch::now_ms() {
  timespec t;
  clock_gettime(stopwatch_clock, &t);
  return 1e3 * static_cast<double>(t.tv_sec) + 1e-6 * static_cast<double>(t.tv_nsec);
}

double Stopwatch::lap_ms() {
  const double now = now_ms();
  const double ms = now - start_ms_;
  start_ms_ = now;
  return ms;
}

void FrameLog::frame(int index, double first_ms, double second_ms, double energy,
                     std::optional<CgResult> cg) {
  ms.push_back({first_ms, second_ms});
  std::printf("frame %d: %s %.3f ms, %s %.3f ms", index, first_label.c_str(), first_ms,
              second_label.c_str(), second_ms);
  if (cg) std::printf(", cg %d iterations, residual %.3e", cg->iterations, cg->residual);
  std::printf(", energy %.17g\n", energy);
}

namespace {

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

}  // namespace

void FrameLog::summary() const {
  if (ms.empty()) return;
  std::vector<double> a, b, total;
  for (const auto& m : ms) a.push_back(m[0]), b.push_back(m[1]), total.push_back(m[0] + m[1]);
  const double n = static_cast<double>(ms.size());
  auto mean = [n](const std::vector<double>& v) {
    return std::accumulate(v.begin(), v.end(), 0.0) / n;
  };
  std::printf("median over %zu frames: %s %.3f ms, %s %.3f ms, total %.3f ms/frame\n", ms.size(),
              first_label.c_str(), median(a), second_label.c_str(), median(b), median(total));
  std::printf("mean over %zu frames: %s %.3f ms, %s %.3f ms, total %.3f ms/frame\n", ms.size(),
              first_label.c_str(), mean(a), second_label.c_str(), mean(b), mean(total));
}

bool finish(const Options& options, const Vec3s& x) {
  bool finite = true;
  for (const Vec3& p : x) finite = finite && p.allFinite();
  if (options.check && !finite) std::fprintf(stderr, "non-finite position\n");
  bool written = true;
  if (!options.csv.empty()) {  // positions only where --csv asks, never into the working folder
    std::ofstream out(options.csv);
    out.precision(17);
    out << "x,y,z\n";
    for (const Vec3& p : x) out << p.x() << ',' << p.y() << ',' << p.z() << '\n';
    written = bool(out);
    if (!written) std::fprintf(stderr, "cannot write %s\n", options.csv.c_str());
  }
  return written && (!options.check || finite);
}

}  // namespace simit::baseline
