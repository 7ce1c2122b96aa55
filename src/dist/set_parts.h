// A scene's sets cut into the ranks' parts on the rank that read them, and each part as the
// message that rank receives: every rank's part is encoded on rank 0 (which alone reads the
// meshes) and decoded by its rank into local sets, with the layout and the ghost plan that its
// reductions, refreshes and gathers need. No MPI here: the messages are plain bytes.
#pragma once

#include <cstddef>
#include <memory>
#include <span>
#include <vector>

#include "dist/overlap.h"
#include "runtime/set.h"

namespace simit::dist {

// One rank's part of every set of a scene, as decode_part builds it.
struct LocalSets {
  std::vector<std::unique_ptr<runtime::Set>> sets;  // in the whole sets' order
  std::vector<SetPart> layouts;                     // per set
  std::vector<GhostPlan> plans;                     // per set
  std::vector<int32_t> whole_sizes;                 // per set: its size in one process
};

// The message of each of `ranks` ranks: its part of every set of `whole` (vertex sets, and
// edge sets whose endpoints all lie in one of them, listed after or before it). A vertex set
// is cut in whole chunks of the blocked sums, by METIS over the graph of its edge sets, or in
// runs of chunks when no edge set joins its vertices (partition_in_chunks, dist/partition.h);
// each rank's part is its overlapping layout (dist/overlap.h), in the whole set's order. Throws
// std::runtime_error naming a set it cannot cut (a grid, an edge set whose endpoints lie in several
// sets).
std::vector<std::vector<std::byte>> encode_parts(const std::vector<const runtime::Set*>& whole,
                                                 int ranks);

// The local sets of one message of encode_parts: the same names, fields and field types;
// elements in the layout's order; mesh numbers kept. Throws std::runtime_error on a message
// that is cut short or does not hold together.
LocalSets decode_part(std::span<const std::byte> message);

}  // namespace simit::dist
