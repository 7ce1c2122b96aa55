// The overlapping layout of the distributed layer (dist/overlap.h): a small mesh worked out
// by hand, the bunny's tets (and their edges) cut into 2, 3 and 7 parts checked against a
// brute-force reference and the layout's own invariants, and the errors.
#include "dist/overlap.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <set>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "dist/partition.h"
#include "runtime/mesh/mesh_reader.h"

namespace simit::dist {
namespace {

using runtime::ElementList;
using Ints = std::vector<int32_t>;

// The link to `q` in `plan`, or null.
const GhostLink* link_to(const GhostPlan& plan, int q) {
  for (const GhostLink& link : plan.links)
    if (link.rank == q) return &link;
  return nullptr;
}

Ints to_global(const SetPart& part, const Ints& local) {
  Ints out;
  for (int32_t i : local) out.push_back(part.global.at(static_cast<size_t>(i)));
  return out;
}

// The small mesh: five vertices owned {0, 1, 0, 1, 2} by three ranks; five edges
// e0 (0,1), e1 (1,2), e2 (2,3), e3 (3,4), e4 (0,4) and one triangle t0 (4,1,3).
// Element owners (owner of the lowest vertex): e0 0, e1 1, e2 0, e3 1, e4 0, t0 1.
// Endpoint owners: e0 {0,1}, e1 {1,0}, e2 {0,1}, e3 {1,2}, e4 {0,2}, t0 {2,1}.
struct SmallMesh {
  Ints owner = {0, 1, 0, 1, 2};
  Ints edges = {0, 1, 1, 2, 2, 3, 3, 4, 0, 4};
  Ints triangles = {4, 1, 3};
  std::vector<ElementList> lists() const { return {{edges, 2}, {triangles, 3}}; }
};

// Rank 0 holds e0, e1, e2, e4 (not e3, whose endpoints ranks 1 and 2 own) and no triangle;
// so vertices 0, 2 (its own) and 1, 3, 4 (ghosts), all in the whole set's order.
TEST(Overlap, RankZeroOfTheSmallMeshByHand) {
  const SmallMesh m;
  const RankLayout r = overlap_layout(m.owner, m.lists(), 3, 0);
  EXPECT_EQ(r.vertices.global, (Ints{0, 1, 2, 3, 4}));
  EXPECT_EQ(r.vertices.owned, (Ints{0, 2}));
  EXPECT_EQ(r.vertices.ghosts, (Ints{1, 3, 4}));
  EXPECT_EQ(r.vertices.ghost_owner, (Ints{1, 1, 2}));
  ASSERT_EQ(r.vertex_plan.links.size(), 2u);
  // Rank 1 holds 0 and 2 (through e0, e1, e2); rank 2 holds 0 (through e4).
  EXPECT_EQ(r.vertex_plan.links[0].rank, 1);
  EXPECT_EQ(r.vertex_plan.links[0].send, (Ints{0, 2}));
  EXPECT_EQ(r.vertex_plan.links[0].recv, (Ints{1, 3}));
  EXPECT_EQ(r.vertex_plan.links[1].rank, 2);
  EXPECT_EQ(r.vertex_plan.links[1].send, (Ints{0}));
  EXPECT_EQ(r.vertex_plan.links[1].recv, (Ints{4}));
  ASSERT_EQ(r.edge_sets.size(), 2u);
  EXPECT_EQ(r.edge_sets[0].global, (Ints{0, 1, 2, 4}));
  EXPECT_EQ(r.edge_sets[0].owned, (Ints{0, 2, 3}));  // e0, e2, e4
  EXPECT_EQ(r.edge_sets[0].ghosts, (Ints{1}));       // e1
  EXPECT_EQ(r.edge_sets[0].ghost_owner, (Ints{1}));
  ASSERT_EQ(r.edge_plans[0].links.size(), 2u);
  EXPECT_EQ(r.edge_plans[0].links[0].rank, 1);
  EXPECT_EQ(r.edge_plans[0].links[0].send, (Ints{0, 2}));  // e0, e2
  EXPECT_EQ(r.edge_plans[0].links[0].recv, (Ints{1}));     // e1
  EXPECT_EQ(r.edge_plans[0].links[1].rank, 2);
  EXPECT_EQ(r.edge_plans[0].links[1].send, (Ints{3}));  // e4
  EXPECT_TRUE(r.edge_plans[0].links[1].recv.empty());
  EXPECT_EQ(r.local_connectivity[0], (Ints{0, 1, 1, 2, 2, 3, 0, 4}));
  EXPECT_TRUE(r.edge_sets[1].global.empty());
  EXPECT_TRUE(r.edge_sets[1].owned.empty());
  EXPECT_TRUE(r.edge_plans[1].links.empty());
  EXPECT_TRUE(r.local_connectivity[1].empty());
}

// Rank 1 owns vertices 1, 3 and holds every edge but e4, and the triangle it owns.
TEST(Overlap, RankOneOfTheSmallMeshByHand) {
  const SmallMesh m;
  const RankLayout r = overlap_layout(m.owner, m.lists(), 3, 1);
  EXPECT_EQ(r.vertices.global, (Ints{0, 1, 2, 3, 4}));
  EXPECT_EQ(r.vertices.owned, (Ints{1, 3}));
  EXPECT_EQ(r.vertices.ghosts, (Ints{0, 2, 4}));
  EXPECT_EQ(r.vertices.ghost_owner, (Ints{0, 0, 2}));
  ASSERT_EQ(r.vertex_plan.links.size(), 2u);
  EXPECT_EQ(r.vertex_plan.links[0].rank, 0);
  EXPECT_EQ(r.vertex_plan.links[0].send, (Ints{1, 3}));
  EXPECT_EQ(r.vertex_plan.links[0].recv, (Ints{0, 2}));
  // Rank 2 holds 3 through e3 and 1 through the triangle.
  EXPECT_EQ(r.vertex_plan.links[1].rank, 2);
  EXPECT_EQ(r.vertex_plan.links[1].send, (Ints{1, 3}));
  EXPECT_EQ(r.vertex_plan.links[1].recv, (Ints{4}));
  EXPECT_EQ(r.edge_sets[0].global, (Ints{0, 1, 2, 3}));
  EXPECT_EQ(r.edge_sets[0].owned, (Ints{1, 3}));   // e1, e3
  EXPECT_EQ(r.edge_sets[0].ghosts, (Ints{0, 2}));  // e0, e2
  EXPECT_EQ(r.edge_sets[0].ghost_owner, (Ints{0, 0}));
  EXPECT_EQ(r.edge_sets[1].global, (Ints{0}));
  EXPECT_EQ(r.edge_sets[1].owned, (Ints{0}));
  ASSERT_EQ(r.edge_plans[1].links.size(), 1u);
  EXPECT_EQ(r.edge_plans[1].links[0].rank, 2);
  EXPECT_EQ(r.edge_plans[1].links[0].send, (Ints{0}));
  EXPECT_TRUE(r.edge_plans[1].links[0].recv.empty());
  EXPECT_EQ(r.local_connectivity[1], (Ints{4, 1, 3}));
}

// Rank 2 owns vertex 4 only and no element: it holds e3 (rank 1's), e4 (rank 0's) and the
// triangle (rank 1's) as ghosts, and vertices 0, 1, 3 as ghosts: locally 0 1 3 4 are 0 1 2 3.
TEST(Overlap, RankTwoOfTheSmallMeshByHand) {
  const SmallMesh m;
  const RankLayout r = overlap_layout(m.owner, m.lists(), 3, 2);
  EXPECT_EQ(r.vertices.global, (Ints{0, 1, 3, 4}));
  EXPECT_EQ(r.vertices.owned, (Ints{3}));
  EXPECT_EQ(r.vertices.ghosts, (Ints{0, 1, 2}));
  EXPECT_EQ(r.vertices.ghost_owner, (Ints{0, 1, 1}));
  ASSERT_EQ(r.vertex_plan.links.size(), 2u);
  EXPECT_EQ(r.vertex_plan.links[0].rank, 0);
  EXPECT_EQ(r.vertex_plan.links[0].send, (Ints{3}));
  EXPECT_EQ(r.vertex_plan.links[0].recv, (Ints{0}));
  EXPECT_EQ(r.vertex_plan.links[1].rank, 1);
  EXPECT_EQ(r.vertex_plan.links[1].send, (Ints{3}));
  EXPECT_EQ(r.vertex_plan.links[1].recv, (Ints{1, 2}));
  EXPECT_EQ(r.edge_sets[0].global, (Ints{3, 4}));
  EXPECT_TRUE(r.edge_sets[0].owned.empty());
  EXPECT_EQ(r.edge_sets[0].ghosts, (Ints{0, 1}));
  EXPECT_EQ(r.edge_sets[0].ghost_owner, (Ints{1, 0}));
  ASSERT_EQ(r.edge_plans[0].links.size(), 2u);
  EXPECT_EQ(r.edge_plans[0].links[0].rank, 0);
  EXPECT_TRUE(r.edge_plans[0].links[0].send.empty());
  EXPECT_EQ(r.edge_plans[0].links[0].recv, (Ints{1}));
  EXPECT_EQ(r.edge_plans[0].links[1].rank, 1);
  EXPECT_EQ(r.edge_plans[0].links[1].recv, (Ints{0}));
  EXPECT_EQ(r.local_connectivity[0], (Ints{2, 3, 0, 3}));
  EXPECT_EQ(r.edge_sets[1].global, (Ints{0}));
  EXPECT_EQ(r.edge_sets[1].ghost_owner, (Ints{1}));
  EXPECT_EQ(r.local_connectivity[1], (Ints{3, 1, 2}));
}

// A rank that owns no vertex holds nothing and exchanges nothing; one rank holds everything.
TEST(Overlap, ARankOwningNothingHoldsNothingAndASingleRankHoldsAll) {
  const SmallMesh m;
  const RankLayout empty = overlap_layout(m.owner, m.lists(), 4, 3);
  EXPECT_TRUE(empty.vertices.global.empty());
  EXPECT_TRUE(empty.vertex_plan.links.empty());
  ASSERT_EQ(empty.edge_sets.size(), 2u);
  EXPECT_TRUE(empty.edge_sets[0].global.empty());
  EXPECT_TRUE(empty.edge_sets[1].global.empty());
  const Ints zero(5, 0);
  const RankLayout all = overlap_layout(zero, m.lists(), 1, 0);
  EXPECT_EQ(all.vertices.global, (Ints{0, 1, 2, 3, 4}));
  EXPECT_EQ(all.vertices.owned, (Ints{0, 1, 2, 3, 4}));
  EXPECT_TRUE(all.vertices.ghosts.empty());
  EXPECT_TRUE(all.vertex_plan.links.empty());
  EXPECT_EQ(all.edge_sets[0].owned.size(), 5u);
  EXPECT_EQ(all.local_connectivity[0], m.edges);
  EXPECT_EQ(all.local_connectivity[1], m.triangles);
}

// The slow way: which elements and vertices rank r holds, straight from the rule.
struct Reference {
  std::vector<std::set<int32_t>> vertices;            // per rank
  std::vector<std::vector<std::set<int32_t>>> lists;  // per list, per rank
};

Reference reference(const Ints& owner, const std::vector<ElementList>& lists, int ranks) {
  Reference ref;
  ref.vertices.resize(static_cast<size_t>(ranks));
  for (size_t v = 0; v < owner.size(); ++v)
    ref.vertices[static_cast<size_t>(owner[v])].insert(static_cast<int32_t>(v));
  for (const ElementList& list : lists) {
    auto& sets = ref.lists.emplace_back(static_cast<size_t>(ranks));
    const auto arity = static_cast<size_t>(list.arity);
    for (int r = 0; r < ranks; ++r)
      for (size_t e = 0; e < list.indices.size() / arity; ++e) {
        bool local = false;
        for (size_t i = 0; i < arity; ++i)
          local = local || owner[static_cast<size_t>(list.indices[e * arity + i])] == r;
        if (!local) continue;
        sets[static_cast<size_t>(r)].insert(static_cast<int32_t>(e));
        for (size_t i = 0; i < arity; ++i)
          ref.vertices[static_cast<size_t>(r)].insert(list.indices[e * arity + i]);
      }
  }
  return ref;
}

int32_t lowest_owner(const ElementList& list, const Ints& owner, int32_t e) {
  const auto arity = static_cast<size_t>(list.arity);
  int32_t lowest = list.indices[static_cast<size_t>(e) * arity];
  for (size_t i = 1; i < arity; ++i)
    lowest = std::min(lowest, list.indices[static_cast<size_t>(e) * arity + i]);
  return owner[static_cast<size_t>(lowest)];
}

// A set's part on rank r against the reference's set of its items on every rank: all of
// them ascending, the owned and the ghosts each ascending among them, the ghosts' owners right, and
// the plan's lists what the reference says each pair of ranks share.
void check_part(const SetPart& part, const GhostPlan& plan,
                const std::vector<std::set<int32_t>>& held, const std::vector<int32_t>& item_owner,
                int r, const std::string& what) {
  SCOPED_TRACE(what + " on rank " + std::to_string(r));
  Ints owned, ghosts, ghost_owner;
  for (int32_t x : held[static_cast<size_t>(r)]) {
    if (item_owner[static_cast<size_t>(x)] == r) {
      owned.push_back(x);
    } else {
      ghosts.push_back(x);
      ghost_owner.push_back(item_owner[static_cast<size_t>(x)]);
    }
  }
  const Ints expected(held[static_cast<size_t>(r)].begin(), held[static_cast<size_t>(r)].end());
  EXPECT_EQ(part.global, expected);
  EXPECT_EQ(to_global(part, part.owned), owned);
  EXPECT_EQ(to_global(part, part.ghosts), ghosts);
  EXPECT_TRUE(std::is_sorted(part.owned.begin(), part.owned.end()));
  EXPECT_TRUE(std::is_sorted(part.ghosts.begin(), part.ghosts.end()));
  EXPECT_EQ(part.ghost_owner, ghost_owner);
  const int ranks = static_cast<int>(held.size());
  size_t links = 0;
  int previous = -1;
  for (const GhostLink& link : plan.links) {
    EXPECT_GT(link.rank, previous);
    previous = link.rank;
  }
  for (int q = 0; q < ranks; ++q) {
    if (q == r) continue;
    Ints send, recv;
    for (int32_t x : owned)
      if (held[static_cast<size_t>(q)].count(x)) send.push_back(x);
    for (int32_t x : ghosts)
      if (item_owner[static_cast<size_t>(x)] == q) recv.push_back(x);
    const GhostLink* link = link_to(plan, q);
    if (send.empty() && recv.empty()) {
      EXPECT_EQ(link, nullptr) << q;
      continue;
    }
    ++links;
    ASSERT_NE(link, nullptr) << q;
    EXPECT_EQ(to_global(part, link->send), send) << q;
    EXPECT_EQ(to_global(part, link->recv), recv) << q;
  }
  EXPECT_EQ(plan.links.size(), links);
  EXPECT_EQ(link_to(plan, r), nullptr);
}

// Every invariant of a whole run's layouts, and the reference's agreement.
void check_layouts(const Ints& owner, const std::vector<ElementList>& lists, int ranks) {
  std::vector<RankLayout> layouts;
  for (int r = 0; r < ranks; ++r) layouts.push_back(overlap_layout(owner, lists, ranks, r));
  const Reference ref = reference(owner, lists, ranks);
  int64_t owned_vertices = 0;
  for (int r = 0; r < ranks; ++r) {
    const RankLayout& layout = layouts[static_cast<size_t>(r)];
    owned_vertices += static_cast<int64_t>(layout.vertices.owned.size());
    check_part(layout.vertices, layout.vertex_plan, ref.vertices, owner, r, "vertices");
    ASSERT_EQ(layout.edge_sets.size(), lists.size());
    ASSERT_EQ(layout.edge_plans.size(), lists.size());
    ASSERT_EQ(layout.local_connectivity.size(), lists.size());
  }
  EXPECT_EQ(owned_vertices, static_cast<int64_t>(owner.size()));
  for (size_t l = 0; l < lists.size(); ++l) {
    const ElementList& list = lists[l];
    const auto arity = static_cast<size_t>(list.arity);
    const auto count = static_cast<int32_t>(list.indices.size() / arity);
    Ints element_owner_of(static_cast<size_t>(count));
    for (int32_t e = 0; e < count; ++e)
      element_owner_of[static_cast<size_t>(e)] = lowest_owner(list, owner, e);
    int64_t owned_elements = 0;
    for (int r = 0; r < ranks; ++r) {
      const RankLayout& layout = layouts[static_cast<size_t>(r)];
      const SetPart& set = layout.edge_sets[l];
      owned_elements += static_cast<int64_t>(set.owned.size());
      check_part(set, layout.edge_plans[l], ref.lists[l], element_owner_of, r,
                 "list " + std::to_string(l));
      // Local connectivity names, through the local vertices, the element's own endpoints.
      const Ints& local = layout.local_connectivity[l];
      ASSERT_EQ(local.size(), set.global.size() * arity);
      for (size_t i = 0; i < set.global.size(); ++i)
        for (size_t k = 0; k < arity; ++k) {
          const int32_t v = local[i * arity + k];
          ASSERT_GE(v, 0);
          ASSERT_LT(static_cast<size_t>(v), layout.vertices.global.size());
          EXPECT_EQ(layout.vertices.global[static_cast<size_t>(v)],
                    list.indices[static_cast<size_t>(set.global[i]) * arity + k]);
        }
    }
    EXPECT_EQ(owned_elements, count) << "list " << l;
  }
  // What r sends q is, in global indices, what q receives from r (for every set).
  auto pairs_agree = [&](auto part_of, auto plan_of, const std::string& what) {
    for (int r = 0; r < ranks; ++r)
      for (const GhostLink& link : plan_of(layouts[static_cast<size_t>(r)]).links) {
        const RankLayout& other = layouts[static_cast<size_t>(link.rank)];
        const GhostLink* back = link_to(plan_of(other), r);
        ASSERT_NE(back, nullptr) << what << " " << r << " -> " << link.rank;
        EXPECT_EQ(to_global(part_of(layouts[static_cast<size_t>(r)]), link.send),
                  to_global(part_of(other), back->recv))
            << what << " " << r << " -> " << link.rank;
        EXPECT_EQ(to_global(part_of(layouts[static_cast<size_t>(r)]), link.recv),
                  to_global(part_of(other), back->send))
            << what << " " << r << " <- " << link.rank;
      }
  };
  pairs_agree([](const RankLayout& x) -> const SetPart& { return x.vertices; },
              [](const RankLayout& x) -> const GhostPlan& { return x.vertex_plan; }, "vertices");
  for (size_t l = 0; l < lists.size(); ++l)
    pairs_agree([l](const RankLayout& x) -> const SetPart& { return x.edge_sets[l]; },
                [l](const RankLayout& x) -> const GhostPlan& { return x.edge_plans[l]; },
                "list " + std::to_string(l));
}

TEST(Overlap, TheSmallMeshAgreesWithTheReferenceOnEveryRank) {
  const SmallMesh m;
  check_layouts(m.owner, m.lists(), 3);
  check_layouts(m.owner, m.lists(), 4);  // rank 3 owns nothing
}

// The bunny's tets, and the edges of its tets as a second list, cut by METIS.
TEST(Overlap, TheBunnysPartsAgreeWithTheReference) {
  const runtime::Mesh mesh = runtime::read_mesh(SIMIT_SOURCE_DIR "/examples/data/bunny.1.ele");
  ASSERT_FALSE(mesh.tets.empty());
  Ints tets;
  for (const auto& t : mesh.tets) tets.insert(tets.end(), t.begin(), t.end());
  std::set<std::pair<int32_t, int32_t>> pairs;
  for (const auto& t : mesh.tets)
    for (size_t i = 0; i < 4; ++i)
      for (size_t j = i + 1; j < 4; ++j) pairs.insert(std::minmax(t[i], t[j]));
  Ints edges;
  for (const auto& [a, b] : pairs) edges.insert(edges.end(), {b, a});  // highest first
  const auto n = static_cast<int32_t>(mesh.points.size());
  const std::vector<ElementList> tet_list = {{tets, 4}};
  const std::vector<ElementList> both = {{tets, 4}, {edges, 2}};
  const runtime::VertexGraph g = runtime::vertex_graph(n, tet_list);
  for (int parts : {2, 3, 7}) {
    SCOPED_TRACE(std::to_string(parts) + " parts");
    const Ints owner = partition_vertices(g, parts, tet_list);
    check_layouts(owner, both, parts);
    // A cut mesh has ghosts on every rank.
    for (int r = 0; r < parts; ++r) {
      const RankLayout layout = overlap_layout(owner, tet_list, parts, r);
      EXPECT_FALSE(layout.vertices.ghosts.empty());
      EXPECT_FALSE(layout.edge_sets[0].ghosts.empty());
    }
  }
}

// The message an invalid_argument from the layout carries.
std::string error_of(const Ints& owner, const std::vector<ElementList>& lists, int ranks,
                     int rank) {
  try {
    overlap_layout(owner, lists, ranks, rank);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(Overlap, BadInputIsAnErrorThatSaysWhy) {
  const SmallMesh m;
  EXPECT_EQ(error_of(m.owner, m.lists(), 0, 0),
            "overlap layout: 0 ranks; there must be at least one");
  EXPECT_EQ(error_of(m.owner, m.lists(), 3, 3),
            "overlap layout: rank 3 is not one of the ranks 0..2");
  EXPECT_EQ(error_of(m.owner, m.lists(), 3, -1),
            "overlap layout: rank -1 is not one of the ranks 0..2");
  EXPECT_EQ(error_of(m.owner, m.lists(), 2, 0),
            "overlap layout: vertex 4 has owner 2, not one of the ranks 0..1");
  EXPECT_EQ(error_of({0, -1, 0, 1, 2}, m.lists(), 3, 0),
            "overlap layout: vertex 1 has owner -1, not one of the ranks 0..2");
  const Ints bad_edges = {0, 1, 1, 5};
  EXPECT_EQ(error_of(m.owner, {{bad_edges, 2}}, 3, 0),
            "overlap layout: element 1 of list 0 has endpoint 5, not one of the 5 vertices");
  const Ints negative = {0, -2};
  EXPECT_EQ(error_of(m.owner, {{m.edges, 2}, {negative, 2}}, 3, 1),
            "overlap layout: element 0 of list 1 has endpoint -2, not one of the 5 vertices");
  EXPECT_EQ(error_of(m.owner, {{m.edges, 3}}, 3, 0),
            "overlap layout: element list 0 has 10 endpoints, not a multiple of its arity 3");
  EXPECT_EQ(error_of(m.owner, {{m.edges, 0}}, 3, 0),
            "overlap layout: element list 0 has arity 0; it must be at least 1");
}

}  // namespace
}  // namespace simit::dist
