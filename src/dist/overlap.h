// The sets a rank holds in a distributed run ("overlap"): every element of an edge set with an
// endpoint the rank owns, so that each row an owned vertex has in an assembled matrix or vector
// is complete on its rank, and what the ranks exchange to refresh the copies of each other's
// elements (ghosts). Every rank computes its own layout from the same inputs, without asking
// the others, and the layouts agree: what one rank sends another is what that one receives.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "runtime/mesh/reorder.h"

namespace simit::dist {

// One set's part on one rank.
// Its elements keep the whole set's order (global is ascending), owned and ghosts interleaved:
// so a block of an owned vertex sums its elements' contributions in the order one process
// does, and a row of an assembled matrix lists its columns in the same order.
struct SetPart {
  std::vector<int32_t> global;       // local index -> index in the whole set, ascending
  std::vector<int32_t> owned;        // local indices of this rank's own elements, ascending
  std::vector<int32_t> ghosts;       // local indices of the others' elements, ascending
  std::vector<int32_t> ghost_owner;  // per ghost: the rank owning it
};

// What this rank sends to and receives from one other rank when it refreshes a set's ghosts.
struct GhostLink {
  int rank = 0;
  std::vector<int32_t> send;  // local indices of owned elements `rank` holds as ghosts,
                              // ascending by global index
  std::vector<int32_t> recv;  // local indices of this rank's ghosts that `rank` owns,
                              // ascending by global index
};

struct GhostPlan {
  std::vector<GhostLink> links;  // ascending rank; only ranks with something to send or receive
};

// One vertex set and the edge sets whose endpoints are all in it, as rank `rank` of `ranks`
// holds them.
struct RankLayout {
  SetPart vertices;
  GhostPlan vertex_plan;
  std::vector<SetPart> edge_sets;                        // one per list given
  std::vector<GhostPlan> edge_plans;                     // one per list given
  std::vector<std::vector<int32_t>> local_connectivity;  // per list: arity LOCAL vertex
                                                         // indices per local element
};

// The layout of rank `rank`. vertex_owner: the rank of each vertex (size = vertex count;
// values in [0, ranks)). lists: the edge sets over those vertices (endpoints as vertex
// indices). An element belongs to the owner of its lowest vertex (element_owner of
// dist/local_part.h) and is held by every rank owning one of its endpoints; a rank holds the
// vertices it owns and every endpoint of the elements it holds. Time O(elements x arity^2 +
// vertices), whatever the number of ranks. Throws std::invalid_argument for ranks < 1, a rank
// or vertex owner out of [0, ranks), an arity below 1, a list whose length the arity does not
// divide, or an endpoint out of range.
RankLayout overlap_layout(std::span<const int32_t> vertex_owner,
                          std::span<const runtime::ElementList> lists, int ranks, int rank);

}  // namespace simit::dist
