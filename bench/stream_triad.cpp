// STREAM-like triad a = b + s c on one thread, for the memory bandwidth that bytes moved per
// CG iteration are compared against; several array sizes, from cache-resident to DRAM.
// Usage: stream_triad [MB_TOTAL...] [--repeats N]   (default sizes 1 8 24 96 768 MB, 3 arrays)
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

namespace {

struct Result {
  double best_gbs, median_gbs;
};

// Triad over three arrays of `total_mb` together; bytes counted as STREAM does (read b and c,
// write a: 24 bytes per element, no write-allocate traffic).
Result triad(double total_mb, int repeats) {
  const size_t n = static_cast<size_t>(total_mb * 1e6 / (3 * sizeof(double)));
  std::vector<double> a(n, 0.0), b(n, 1.0), c(n, 2.0);
  const double s = 3.0;
  // Enough passes per timing that each lasts about 20 ms, for the clock's resolution.
  const int passes = std::max(1, static_cast<int>(20e6 / std::max<size_t>(n, 1) / 4));
  std::vector<double> gbs;
  for (int r = 0; r < repeats; ++r) {
    const auto start = std::chrono::steady_clock::now();
    for (int p = 0; p < passes; ++p) {
      double* __restrict pa = a.data();
      const double* __restrict pb = b.data();
      const double* __restrict pc = c.data();
      for (size_t i = 0; i < n; ++i) pa[i] = pb[i] + s * pc[i];
      b[p % n] += 1e-300;  // a data dependence between passes, so none is elided
    }
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    gbs.push_back(3.0 * sizeof(double) * n * passes / seconds / 1e9);
  }
  if (a[n / 2] != b[n / 2] + s * c[n / 2]) std::printf("(check failed)\n");
  std::sort(gbs.begin(), gbs.end());
  return {gbs.back(), gbs[gbs.size() / 2]};
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<double> sizes;
  int repeats = 11;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--repeats" && i + 1 < argc) {
      repeats = std::atoi(argv[++i]);
    } else if (!arg.empty() && arg[0] != '-' && std::atof(arg.c_str()) > 0) {
      sizes.push_back(std::atof(arg.c_str()));
    } else {
      std::fprintf(stderr, "usage: stream_triad [MB_TOTAL...] [--repeats N]\n");
      return 2;
    }
  }
  if (repeats < 1) repeats = 1;
  if (sizes.empty()) sizes = {1, 8, 24, 96, 768};
  std::printf("triad a = b + s c, one thread, %d timings per size (24 bytes per element)\n",
              repeats);
  for (const double mb : sizes) {
    const Result r = triad(mb, repeats);
    std::printf("%8.1f MB: best %6.1f GB/s, median %6.1f GB/s\n", mb, r.best_gbs, r.median_gbs);
  }
  return 0;
}
