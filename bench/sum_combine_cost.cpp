// The cost of a distributed reduction's arithmetic on one rank (dist/sum_terms.h): the
// combining of every rank's contribution, which every rank does after the MPI_Allgatherv, and
// one rank's own contribution, for bench/scaling_model.py's strong-scaling model. No MPI.
//
// Build and run (bench/scaling_model.py does both):
//   g++ -O3 -std=c++20 -I src bench/sum_combine_cost.cpp build/src/dist/libsimit_dist.a
//       build/src/runtime/libsimit_runtime.a -o sum_combine_cost
//   ./sum_combine_cost CHUNKS RANKS [TERMS]
// TERMS (default CHUNKS x kSumChunk) terms t_g of fixed values make up CHUNKS chunks. Up to
// CHUNKS ranks, rank r owns the whole chunks [r C / K, (r + 1) C / K), as
// dist::partition_in_chunks gives them; past that, each term goes to a rank drawn from its index
// (a fixed hash), so that no rank owns a whole chunk and every term travels, each rank's terms
// spread over the whole set. The K contributions are built with dist::sum_contribution and
// concatenated in rank order, as the allgather gives them. Prints CSV lines
// kind,chunks,terms,ranks,items,repeats,median_us,min_us: "combine" is one
// dist::combine_contributions over all (items: its pairs), "contribution" one sum_contribution
// of the rank owning the most terms (items: its terms). Each call is timed on its own after
// warm-ups (the buffers' first touches) and the median kept. Exits 1 if the combined sum
// differs from runtime::blocked_dot's bits.
#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "dist/sum_terms.h"
#include "runtime/blocked_sum.h"

namespace {

volatile double sink;

// The median and least of one call's time in us; the repeats fill about a fifth of a second.
template <class F>
void time_calls(const char* kind, long chunks, long terms, long ranks, size_t items, F call) {
  using clock = std::chrono::steady_clock;
  auto once = [&] {
    auto t0 = clock::now();
    call();
    return std::chrono::duration<double, std::micro>(clock::now() - t0).count();
  };
  double first = 0;
  for (int i = 0; i < 5; ++i) first = once();  // first touches, the allocator's pools
  const int repeats = static_cast<int>(std::clamp(2e5 / std::max(first, 0.01), 11.0, 20001.0));
  for (int i = 0; i < repeats / 10; ++i) once();
  std::vector<double> us(static_cast<size_t>(repeats));
  for (double& t : us) t = once();
  std::sort(us.begin(), us.end());
  std::printf("%s,%ld,%ld,%ld,%zu,%d,%.4f,%.4f\n", kind, chunks, terms, ranks, items, repeats,
              us[us.size() / 2], us[0]);
}

}  // namespace

int main(int argc, char** argv) {
  const long chunk = static_cast<long>(simit::runtime::kSumChunk);
  const long chunks = argc > 2 ? std::atol(argv[1]) : 0, ranks = argc > 2 ? std::atol(argv[2]) : 0;
  const long terms = argc > 3 ? std::atol(argv[3]) : chunks * chunk;
  if (chunks < 1 || ranks < 1 || terms <= (chunks - 1) * chunk || terms > chunks * chunk) {
    std::fprintf(stderr, "usage: %s CHUNKS RANKS [TERMS] (TERMS within the CHUNKS-th chunk)\n",
                 argv[0]);
    return 2;
  }
  std::vector<double> t(static_cast<size_t>(terms));
  for (long g = 0; g < terms; ++g)
    t[static_cast<size_t>(g)] = static_cast<double>((g * 2654435761L) % 1000003) / 1000003 - 0.5;
  // Each rank's term indices, ascending.
  std::vector<std::vector<int64_t>> owned(static_cast<size_t>(ranks));
  for (long g = 0; g < terms; ++g) {
    const long k = g / chunk;
    // Chunk k's owner is the last rank r with r C / K <= k.
    const long r =
        ranks <= chunks
            ? ((k + 1) * ranks - 1) / chunks
            : static_cast<long>((static_cast<uint64_t>(g) * 0x9E3779B97F4A7C15ULL >> 17) %
                                static_cast<uint64_t>(ranks));
    owned[static_cast<size_t>(r)].push_back(g);
  }
  auto values_of = [&](const std::vector<int64_t>& idx) {
    std::vector<double> v;
    for (int64_t g : idx) v.push_back(t[static_cast<size_t>(g)]);
    return v;
  };
  std::vector<double> all;
  for (const auto& idx : owned) {
    const std::vector<double> mine = simit::dist::sum_contribution(idx, values_of(idx), terms);
    all.insert(all.end(), mine.begin(), mine.end());
  }
  const std::vector<double> ones(t.size(), 1.0);
  if (simit::dist::combine_contributions(all) !=
      simit::runtime::blocked_dot(t.data(), ones.data(), t.size(), 1)) {
    std::fprintf(stderr, "the combined sum differs from blocked_dot's\n");
    return 1;
  }
  std::printf("kind,chunks,terms,ranks,items,repeats,median_us,min_us\n");
  time_calls("combine", chunks, terms, ranks, all.size() / 2,
             [&] { sink = simit::dist::combine_contributions(all); });
  const auto& busiest = *std::max_element(
      owned.begin(), owned.end(), [](const auto& a, const auto& b) { return a.size() < b.size(); });
  const std::vector<double> busiest_terms = values_of(busiest);
  time_calls("contribution", chunks, terms, ranks, busiest.size(),
             [&] { sink = simit::dist::sum_contribution(busiest, busiest_terms, terms).back(); });
  return 0;
}
