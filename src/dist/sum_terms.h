// A reduction over a split set with one process's bits: what each rank contributes to the
// contract's blocked sum over the whole set (docs/arithmetic.md, "Distributed runs"), and the
// sum every rank computes from all of the contributions. No MPI here: the contributions are
// plain doubles, which the ranks gather (dist/mpi/scene_distribution.cpp).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

namespace simit::dist {

// This rank's contribution to the blocked sum of the terms t_0 .. t_{whole-1} of a whole
// set: `global` lists the indices of the terms it owns, ascending, and `terms` their values
// (same length). For a chunk whose every term it owns (runtime::kSumChunk consecutive terms,
// the last chunk shorter), the pair (k, P_k) of the chunk's index and partial; for each owned
// term of another chunk, the pair (-1 - g, t_g). Doubles hold the indices exactly (below 2^53).
// Throws std::invalid_argument when `global` is not ascending within [0, whole) or the lengths
// differ.
std::vector<double> sum_contribution(std::span<const int64_t> global, std::span<const double> terms,
                                     int64_t whole);

// The blocked sum from every rank's contribution, concatenated in any order: each shared
// chunk's partial from its terms in index order, then +0.0 + P_0 + P_1 + ... in chunk order
// (the chunks up to the last one named). The bits of runtime::blocked_dot over the whole set
// when the contributions cover every term once. Time linear in the chunks and the shared
// terms' sort. Throws std::invalid_argument on an odd length, a negative index, or a chunk
// below the last one that no contribution gives.
double combine_contributions(std::span<const double> all);

}  // namespace simit::dist
