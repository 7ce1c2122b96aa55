// STREAM-like triad a = b + s c on one thread or several, for the memory bandwidth that the
// bytes a solver loop moves (`--jit-stats`: "an iteration moves ... at ... GB/s") are
// compared against; several array sizes, from cache-resident to DRAM.
// Usage: stream_triad [MB_TOTAL...] [--repeats N] [--threads N]
//        (default sizes 1 8 24 96 768 MB, 3 arrays together; 1 thread)
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <thread>
#include <vector>

namespace {

struct Result {
  double best_gbs, median_gbs;
};

// Triad over three arrays of `total_mb` together, each thread on its own slice of them (which
// it touches first, so that its pages lie near it); bytes counted as STREAM does (read b and
// c, write a: 24 bytes per element, no write-allocate traffic).
Result triad(double total_mb, int repeats, int threads) {
  const size_t n = static_cast<size_t>(total_mb * 1e6 / (3 * sizeof(double)));
  std::unique_ptr<double[]> a(new double[n]), b(new double[n]), c(new double[n]);
  const double s = 3.0;
  // Enough passes per timing that each lasts about 20 ms, for the clock's resolution.
  const int passes = std::max(1, static_cast<int>(20e6 * threads / std::max<size_t>(n, 1) / 4));
  auto slice = [&](int t) {
    return std::pair<size_t, size_t>{n * static_cast<size_t>(t) / static_cast<size_t>(threads),
                                     n * static_cast<size_t>(t + 1) / static_cast<size_t>(threads)};
  };
  auto work = [&](int t, int count) {
    const auto [lo, hi] = slice(t);
    double* __restrict pa = a.get();
    double* __restrict pb = b.get();
    const double* __restrict pc = c.get();
    for (int p = 0; p < count; ++p) {
      for (size_t i = lo; i < hi; ++i) pa[i] = pb[i] + s * pc[i];
      if (hi > lo) pb[lo + static_cast<size_t>(p) % (hi - lo)] += 1e-300;  // no pass elided
    }
  };
  // Runs work(t, count) on every thread at once; returns the seconds from the start signal
  // to the last thread's end.
  auto run = [&](auto&& body) {
    std::atomic<int> ready{0};
    std::atomic<bool> go{false};
    std::vector<std::thread> pool;
    for (int t = 1; t < threads; ++t)
      pool.emplace_back([&, t] {
        ready.fetch_add(1);
        while (!go.load()) std::this_thread::yield();
        body(t);
      });
    while (ready.load() < threads - 1) std::this_thread::yield();
    const auto start = std::chrono::steady_clock::now();
    go.store(true);
    body(0);
    for (std::thread& th : pool) th.join();
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  };
  run([&](int t) {
    const auto [lo, hi] = slice(t);
    for (size_t i = lo; i < hi; ++i) {
      a[i] = 0.0;
      b[i] = 1.0;
      c[i] = 2.0;
    }
  });
  std::vector<double> gbs;
  for (int r = 0; r < repeats; ++r) {
    const double seconds = run([&](int t) { work(t, passes); });
    gbs.push_back(3.0 * sizeof(double) * static_cast<double>(n) * passes / seconds / 1e9);
  }
  // a = b + s c holds where b was not bumped after a was last written.
  if (n > 2 && a[n / 2 + 1] != b[n / 2 + 1] + s * c[n / 2 + 1] && b[n / 2 + 1] == 1.0)
    std::printf("(check failed)\n");
  std::sort(gbs.begin(), gbs.end());
  return {gbs.back(), gbs[gbs.size() / 2]};
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<double> sizes;
  int repeats = 11, threads = 1;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--repeats" && i + 1 < argc) {
      repeats = std::atoi(argv[++i]);
    } else if (arg == "--threads" && i + 1 < argc) {
      threads = std::atoi(argv[++i]);
    } else if (!arg.empty() && arg[0] != '-' && std::atof(arg.c_str()) > 0) {
      sizes.push_back(std::atof(arg.c_str()));
    } else {
      std::fprintf(stderr, "usage: stream_triad [MB_TOTAL...] [--repeats N] [--threads N]\n");
      return 2;
    }
  }
  if (repeats < 1) repeats = 1;
  if (threads < 1) {
    std::fprintf(stderr, "stream_triad: --threads must be at least 1\n");
    return 2;
  }
  if (sizes.empty()) sizes = {1, 8, 24, 96, 768};
  std::printf("triad a = b + s c, %d thread%s, %d timings per size (24 bytes per element)\n",
              threads, threads == 1 ? "" : "s", repeats);
  for (const double mb : sizes) {
    const Result r = triad(mb, repeats, threads);
    std::printf("%8.1f MB: best %6.1f GB/s, median %6.1f GB/s\n", mb, r.best_gbs, r.median_gbs);
  }
  return 0;
}
