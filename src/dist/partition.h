// A mesh's vertices split into parts (one per MPI rank), and what each part then owns and
// must see of the others: the partition the distributed executor will run on, and the
// figures its cost model starts from (docs/distributed.md).
//
// The vertex graph every element implies (runtime/mesh/reorder.h) is cut into `parts` by
// METIS's multilevel k-way partitioner (fixed seed: the same parts every run), balancing
// vertices and the elements they will own. A vertex
// belongs to one part; an element to the part of its lowest-numbered vertex; a part's ghosts
// are the vertices its elements reach that another part owns (one layer: what an assembly
// over its elements reads and writes that is not its own).
#pragma once

#include <cstdint>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "runtime/mesh/reorder.h"

namespace simit::dist {

class PartitionError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The part of each vertex of `graph`, in [0, parts). With `lists`, the parts balance the
// elements each will own as well as the vertices (two weights per vertex). `sizes` (one per
// vertex, or empty for 1 each) weighs a vertex that stands for several. One part: all zero.
// Throws PartitionError when parts < 1, parts exceeds the vertices, or METIS fails.
std::vector<int32_t> partition_vertices(const runtime::VertexGraph& graph, int parts,
                                        std::span<const runtime::ElementList> lists = {},
                                        std::span<const int32_t> sizes = {});

// The part of each of `vertices` vertices, every part owning whole chunks of `chunk`
// consecutive vertices: the chunks of the contract's blocked sums (runtime::kSumChunk), so that
// a reduction over the set needs one partial per chunk, from its one owner
// (docs/arithmetic.md, "Distributed runs"). METIS cuts the graph `lists` imply between the
// chunks, balancing vertices and the elements each part will own; without lists, each part
// takes a run of consecutive chunks, as it does when there are no more chunks than parts. With
// fewer chunks than parts it does the same vertex by vertex (chunk 1), and with fewer vertices
// than parts some parts own none. Throws PartitionError for parts or chunk below 1, or when
// METIS fails.
std::vector<int32_t> partition_in_chunks(int32_t vertices,
                                         std::span<const runtime::ElementList> lists, int parts,
                                         int32_t chunk);

struct PartStats {
  int64_t vertices = 0;    // owned
  int64_t elements = 0;    // owned (all lists)
  int64_t ghosts = 0;      // vertices its elements reach that other parts own
  int64_t neighbours = 0;  // other parts that own one of its ghosts (messages per exchange)
};

struct PartitionStats {
  int parts = 0;
  int64_t graph_edges = 0;  // edges of the vertex graph (each counted once)
  int64_t cut_edges = 0;    // of which between two parts
  std::vector<PartStats> per_part;
  int64_t total_ghosts() const;
  // The largest part's over the mean: 1 is perfect balance.
  double vertex_imbalance() const;
  double element_imbalance() const;
  int64_t most_ghosts() const;
  int64_t most_neighbours() const;
};

// What `owner` (a part per vertex of `graph`, as partition_vertices gives) makes of the
// elements of `lists`.
PartitionStats partition_stats(const runtime::VertexGraph& graph,
                               std::span<const runtime::ElementList> lists,
                               std::span<const int32_t> owner, int parts);

}  // namespace simit::dist
