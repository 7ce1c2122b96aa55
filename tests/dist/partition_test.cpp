// The partitioner of the distributed layer (dist/partition.h): what a given split makes of a
// mesh's elements (owned, ghosts, neighbours, cut), checked by hand on a small graph; METIS's
// parts of the bunny checked against counts the test makes itself; and the errors.
#include "dist/partition.h"

#include "dist/local_part.h"

#include <gtest/gtest.h>

#include <array>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "runtime/mesh/mesh_reader.h"

namespace simit::dist {
namespace {

using runtime::ElementList;

// A path 0 - 1 - 2 - 3 of three edges, split {0, 1} | {2, 3}: the edge (1, 2) is cut and
// belongs to part 0 (its lowest vertex is 1), so part 0 reaches vertex 2, its one ghost.
TEST(Partition, AGivenSplitsOwnersGhostsAndCutByHand) {
  const std::vector<int32_t> path = {0, 1, 1, 2, 2, 3};
  const std::vector<ElementList> lists = {{path, 2}};
  const runtime::VertexGraph g = runtime::vertex_graph(4, lists);
  const std::vector<int32_t> owner = {0, 0, 1, 1};
  const PartitionStats s = partition_stats(g, lists, owner, 2);
  EXPECT_EQ(s.graph_edges, 3);
  EXPECT_EQ(s.cut_edges, 1);
  ASSERT_EQ(s.per_part.size(), 2u);
  EXPECT_EQ(s.per_part[0].vertices, 2);
  EXPECT_EQ(s.per_part[0].elements, 2);
  EXPECT_EQ(s.per_part[0].ghosts, 1);
  EXPECT_EQ(s.per_part[0].neighbours, 1);
  EXPECT_EQ(s.per_part[1].vertices, 2);
  EXPECT_EQ(s.per_part[1].elements, 1);
  EXPECT_EQ(s.per_part[1].ghosts, 0);
  EXPECT_EQ(s.per_part[1].neighbours, 0);
  EXPECT_EQ(s.total_ghosts(), 1);
  EXPECT_EQ(s.most_neighbours(), 1);
  EXPECT_DOUBLE_EQ(s.vertex_imbalance(), 1.0);
  EXPECT_DOUBLE_EQ(s.element_imbalance(), 2.0 * 2.0 / 3.0);
}

// The same split as a rank takes it: its vertices, its elements, its ghosts, in the mesh's
// numbers.
TEST(Partition, ARanksPartHoldsItsVerticesElementsAndGhostsInMeshNumbers) {
  const std::vector<int32_t> path = {0, 1, 1, 2, 2, 3};
  const std::vector<ElementList> lists = {{path, 2}};
  const std::vector<int32_t> owner = {0, 0, 1, 1};
  const LocalPart p0 = local_part(lists, owner, 0), p1 = local_part(lists, owner, 1);
  EXPECT_EQ(p0.owned_vertices, (std::vector<int32_t>{0, 1}));
  EXPECT_EQ(p0.owned_elements, (std::vector<std::vector<int32_t>>{{0, 1}}));
  EXPECT_EQ(p0.ghost_vertices, (std::vector<int32_t>{2}));
  EXPECT_EQ(p1.owned_vertices, (std::vector<int32_t>{2, 3}));
  EXPECT_EQ(p1.owned_elements, (std::vector<std::vector<int32_t>>{{2}}));
  EXPECT_TRUE(p1.ghost_vertices.empty());
}

// The bunny's tets cut into 2, 3 and 7 parts: every part owns vertices and elements, both
// balanced, the owned counts add up to the mesh's, the cut is what the test counts from the tets'
// vertex pairs, ghosts exist, and the same call gives the same parts.
TEST(Partition, TheBunnysPartsAddUpAndTheCutIsTheTetsCrossingPairs) {
  const runtime::Mesh mesh = runtime::read_mesh(SIMIT_SOURCE_DIR "/examples/data/bunny.1.ele");
  ASSERT_FALSE(mesh.tets.empty());
  std::vector<int32_t> tets;
  for (const auto& t : mesh.tets) tets.insert(tets.end(), t.begin(), t.end());
  const std::vector<ElementList> lists = {{tets, 4}};
  const auto n = static_cast<int32_t>(mesh.points.size());
  const runtime::VertexGraph g = runtime::vertex_graph(n, lists);
  for (int parts : {2, 3, 7}) {
    const std::vector<int32_t> owner = partition_vertices(g, parts, lists);
    EXPECT_EQ(partition_vertices(g, parts, lists), owner) << parts;
    const PartitionStats s = partition_stats(g, lists, owner, parts);
    int64_t vertices = 0, elements = 0;
    for (const PartStats& p : s.per_part) {
      EXPECT_GT(p.vertices, 0) << parts;
      EXPECT_GT(p.elements, 0) << parts;
      vertices += p.vertices;
      elements += p.elements;
    }
    EXPECT_EQ(vertices, n);
    EXPECT_EQ(elements, static_cast<int64_t>(mesh.tets.size()));
    std::set<std::pair<int32_t, int32_t>> pairs, cut;
    for (const auto& t : mesh.tets)
      for (int i = 0; i < 4; ++i)
        for (int j = i + 1; j < 4; ++j) {
          const auto pair = std::minmax(t[static_cast<size_t>(i)], t[static_cast<size_t>(j)]);
          pairs.insert(pair);
          if (owner[static_cast<size_t>(pair.first)] != owner[static_cast<size_t>(pair.second)])
            cut.insert(pair);
        }
    EXPECT_EQ(s.graph_edges, static_cast<int64_t>(pairs.size()));
    EXPECT_EQ(s.cut_edges, static_cast<int64_t>(cut.size())) << parts;
    EXPECT_GT(s.cut_edges, 0);
    EXPECT_LT(s.cut_edges, s.graph_edges / 4) << parts;  // a partitioner, not a scatter
    EXPECT_GT(s.total_ghosts(), 0);
    EXPECT_LT(s.vertex_imbalance(), 1.1) << parts;
    EXPECT_LT(s.element_imbalance(), 1.1) << parts;  // the second weight
  }
}

// Parts in whole chunks (the run's partition): the bunny, renumbered as a scene does (RCM),
// cut into 2, 3 and 7 parts of whole chunks of 256 vertices, every chunk one part's; every
// part owns vertices and elements, the parts stay balanced within a chunk's share, and with
// a few chunks a part the cut stays a partitioner's. Without elements, runs of chunks; with fewer
// chunks than parts, vertex by vertex.
TEST(Partition, PartsInChunksOwnWholeChunks) {
  const runtime::Mesh mesh = runtime::read_mesh(SIMIT_SOURCE_DIR "/examples/data/bunny.1.ele");
  const auto n = static_cast<int32_t>(mesh.points.size());
  const std::vector<int32_t> position =
      runtime::invert_permutation(runtime::locality_order(mesh, false));
  std::vector<int32_t> tets;
  for (const auto& t : mesh.tets)
    for (int32_t v : t) tets.push_back(position[static_cast<size_t>(v)]);
  const std::vector<ElementList> lists = {{tets, 4}};
  const runtime::VertexGraph g = runtime::vertex_graph(n, lists);
  const int32_t chunk = 256;
  for (int parts : {2, 3, 7}) {
    SCOPED_TRACE(std::to_string(parts) + " parts");
    const std::vector<int32_t> owner = partition_in_chunks(n, lists, parts, chunk);
    ASSERT_EQ(owner.size(), static_cast<size_t>(n));
    for (int32_t v = 0; v < n; ++v)
      ASSERT_EQ(owner[static_cast<size_t>(v)], owner[static_cast<size_t>(v / chunk * chunk)]) << v;
    const PartitionStats s = partition_stats(g, lists, owner, parts);
    for (const PartStats& p : s.per_part) {
      EXPECT_GT(p.vertices, 0);
      EXPECT_GT(p.elements, 0);
    }
    // A chunk is 1/15 of the bunny's 3,607 vertices: a part may be a chunk over its share.
    EXPECT_LT(s.vertex_imbalance(), 1.0 + 1.5 * chunk * parts / static_cast<double>(n));
    // With ~5 chunks a part, a partitioner's cut; at 7 parts of 15 chunks a part is two slabs
    // of the RCM order, and a third of the edges cross (docs/distributed.md, "Partition").
    if (parts <= 3) {
      EXPECT_LT(s.cut_edges, s.graph_edges / 4);
    }
    EXPECT_EQ(partition_in_chunks(n, lists, parts, chunk), owner);
  }
  // No elements: runs of consecutive chunks, in order.
  const std::vector<int32_t> runs = partition_in_chunks(1000, {}, 2, chunk);
  for (int32_t v = 0; v < 1000; ++v)
    EXPECT_EQ(runs[static_cast<size_t>(v)], v < 512 ? 0 : 1) << v;  // chunks 0-1 | 2-3
  // Fewer chunks (2) than parts (3): vertex by vertex; fewer vertices than parts: some none.
  const std::vector<int32_t> fine = partition_in_chunks(300, {}, 3, chunk);
  EXPECT_EQ(fine[0], 0);
  EXPECT_EQ(fine[100], 1);
  EXPECT_EQ(fine[299], 2);
  EXPECT_EQ(partition_in_chunks(2, {}, 3, chunk), (std::vector<int32_t>{0, 1}));
  EXPECT_THROW(partition_in_chunks(10, {}, 0, chunk), PartitionError);
  EXPECT_THROW(partition_in_chunks(10, {}, 2, 0), PartitionError);
}

TEST(Partition, OnePartOwnsEverythingAndTooManyPartsAreAnError) {
  const std::vector<int32_t> path = {0, 1, 1, 2};
  const std::vector<ElementList> lists = {{path, 2}};
  const runtime::VertexGraph g = runtime::vertex_graph(3, lists);
  EXPECT_EQ(partition_vertices(g, 1), (std::vector<int32_t>{0, 0, 0}));
  const PartitionStats s = partition_stats(g, lists, partition_vertices(g, 1), 1);
  EXPECT_EQ(s.cut_edges, 0);
  EXPECT_EQ(s.total_ghosts(), 0);
  try {
    partition_vertices(g, 4);
    ADD_FAILURE() << "4 parts of 3 vertices";
  } catch (const PartitionError& e) {
    EXPECT_STREQ(e.what(), "cannot cut 3 vertices into 4 parts: each part needs a vertex");
  }
  EXPECT_THROW(partition_vertices(g, 0), PartitionError);
}

}  // namespace
}  // namespace simit::dist
