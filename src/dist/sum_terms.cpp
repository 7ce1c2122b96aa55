// A distributed reduction's contributions and their blocked sum (dist/sum_terms.h).
#include "dist/sum_terms.h"

#include <algorithm>
#include <stdexcept>
#include <string>
#include <utility>

#include "runtime/blocked_sum.h"

namespace simit::dist {

using runtime::kSumChunk;

std::vector<double> sum_contribution(std::span<const int64_t> global, std::span<const double> terms,
                                     int64_t whole) {
  if (global.size() != terms.size())
    throw std::invalid_argument("a sum's contribution: " + std::to_string(global.size()) +
                                " indices for " + std::to_string(terms.size()) + " terms");
  const size_t n = global.size();
  for (size_t t = 0; t < n; ++t)
    if (global[t] < 0 || global[t] >= whole || (t > 0 && global[t] <= global[t - 1]))
      throw std::invalid_argument("a sum's contribution: term " + std::to_string(global[t]) +
                                  " is out of order or outside the " + std::to_string(whole));
  const auto chunk = static_cast<int64_t>(kSumChunk);
  std::vector<double> out;
  for (size_t i = 0; i < n;) {
    const int64_t g = global[i], k = g / chunk;
    const auto size = static_cast<size_t>(std::min(chunk, whole - k * chunk));
    // A whole chunk: its first term here and its last size - 1 places on (the indices ascend,
    // so every one between is there too). Its partial straight from the terms, uncopied.
    if (g == k * chunk && i + size <= n &&
        global[i + size - 1] == g + static_cast<int64_t>(size) - 1) {
      out.push_back(static_cast<double>(k));
      out.push_back(runtime::chunk_partial_of_sums(terms.data() + i, size));
      i += size;
      continue;
    }
    // A chunk other ranks share: this rank's terms of it, one by one.
    for (; i < n && global[i] / chunk == k; ++i) {
      out.push_back(-1.0 - static_cast<double>(global[i]));
      out.push_back(terms[i]);
    }
  }
  return out;
}

double combine_contributions(std::span<const double> all) {
  if (all.size() % 2 != 0)
    throw std::invalid_argument("a sum's contributions hold an odd number of doubles");
  const auto chunk = static_cast<int64_t>(kSumChunk);
  // Each pair's chunk; the last one fixes how many there are.
  auto chunk_of = [&](double key) {
    const auto index = static_cast<int64_t>(key >= 0 ? key : -1.0 - key);
    if (index < 0) throw std::invalid_argument("a sum's contribution names a negative index");
    return key >= 0 ? index : index / chunk;
  };
  int64_t chunks = 0;
  for (size_t p = 0; p < all.size(); p += 2) chunks = std::max(chunks, chunk_of(all[p]) + 1);
  // Each chunk's partial in its place (no sort: this runs on every rank for every reduction,
  // and its cost grows with the whole set, not the rank's part); the shared chunks' terms
  // apart.
  std::vector<double> partials(static_cast<size_t>(chunks), 0.0);
  std::vector<uint8_t> given(partials.size(), 0);
  std::vector<std::pair<int64_t, double>> shared;
  for (size_t p = 0; p < all.size(); p += 2) {
    if (all[p] >= 0) {
      const auto k = static_cast<size_t>(chunk_of(all[p]));
      partials[k] = all[p + 1];
      given[k] = 1;
    } else {
      shared.emplace_back(static_cast<int64_t>(-1.0 - all[p]), all[p + 1]);
    }
  }
  std::sort(shared.begin(), shared.end(),
            [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<double> terms;
  for (size_t a = 0; a < shared.size();) {
    const int64_t k = shared[a].first / chunk;
    terms.clear();
    for (; a < shared.size() && shared[a].first / chunk == k; ++a)
      terms.push_back(shared[a].second);
    partials[static_cast<size_t>(k)] = runtime::chunk_partial_of_sums(terms.data(), terms.size());
    given[static_cast<size_t>(k)] = 1;
  }
  if (std::find(given.begin(), given.end(), 0) != given.end())
    throw std::invalid_argument("a sum's contributions miss a chunk");
  return runtime::combine_partials(partials.data(), partials.size());
}

}  // namespace simit::dist
