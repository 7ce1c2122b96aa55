// The sets a rank holds in a distributed run and its ghost exchanges (dist/overlap.h).
#include "dist/overlap.h"

#include <algorithm>
#include <iterator>
#include <limits>
#include <map>
#include <stdexcept>
#include <string>
#include <utility>

#include "dist/local_part.h"

namespace simit::dist {

namespace {

using RankIndex = std::pair<int32_t, int32_t>;  // (other rank, local index)

[[noreturn]] void fail(const std::string& what) {
  throw std::invalid_argument("overlap layout: " + what);
}

// The plan of a set from its sends (other rank, local index of an owned item; repeats
// allowed) and its ghosts' owners. Local indices ascend with global ones, so ascending local
// indices within a link are ascending global ones, as the plan promises.
GhostPlan make_plan(std::vector<RankIndex> sends, const SetPart& part) {
  std::sort(sends.begin(), sends.end());
  sends.erase(std::unique(sends.begin(), sends.end()), sends.end());
  std::map<int32_t, GhostLink> links;
  for (const auto& [q, local] : sends) {
    GhostLink& link = links[q];
    link.rank = q;
    link.send.push_back(local);
  }
  for (size_t k = 0; k < part.ghost_owner.size(); ++k) {
    GhostLink& link = links[part.ghost_owner[k]];
    link.rank = part.ghost_owner[k];
    link.recv.push_back(part.ghosts[k]);
  }
  GhostPlan plan;
  plan.links.reserve(links.size());
  for (auto& entry : links) plan.links.push_back(std::move(entry.second));
  return plan;
}

// One list's elements on this rank, as the pass over the list finds them.
struct ListPart {
  std::vector<int32_t> owned, ghosts, ghost_owner;  // global indices, ascending
  std::vector<RankIndex> sends;                     // (other rank, GLOBAL element)
};

// `owned` and `ghosts` (global indices, each ascending, disjoint) merged into one part.
SetPart merge_part(const std::vector<int32_t>& owned, const std::vector<int32_t>& ghosts,
                   std::vector<int32_t> ghost_owner) {
  SetPart part;
  part.global.reserve(owned.size() + ghosts.size());
  std::merge(owned.begin(), owned.end(), ghosts.begin(), ghosts.end(),
             std::back_inserter(part.global));
  part.owned.reserve(owned.size());
  part.ghosts.reserve(ghosts.size());
  size_t o = 0;
  for (size_t i = 0; i < part.global.size(); ++i) {
    const bool mine = o < owned.size() && owned[o] == part.global[i];
    (mine ? part.owned : part.ghosts).push_back(static_cast<int32_t>(i));
    o += mine ? 1 : 0;
  }
  part.ghost_owner = std::move(ghost_owner);
  return part;
}

// The local index of each global one of `part` (binary search: global ascends).
int32_t local_index(const SetPart& part, int32_t global) {
  const auto it = std::lower_bound(part.global.begin(), part.global.end(), global);
  return static_cast<int32_t>(it - part.global.begin());
}

}  // namespace

RankLayout overlap_layout(std::span<const int32_t> vertex_owner,
                          std::span<const runtime::ElementList> lists, int ranks, int rank) {
  if (ranks < 1) fail(std::to_string(ranks) + " ranks; there must be at least one");
  if (rank < 0 || rank >= ranks)
    fail("rank " + std::to_string(rank) + " is not one of the ranks 0.." +
         std::to_string(ranks - 1));
  const size_t n = vertex_owner.size();
  if (n > static_cast<size_t>(std::numeric_limits<int32_t>::max()))
    fail(std::to_string(n) + " vertices are more than an int32 index counts");
  for (size_t v = 0; v < n; ++v)
    if (vertex_owner[v] < 0 || vertex_owner[v] >= ranks)
      fail("vertex " + std::to_string(v) + " has owner " + std::to_string(vertex_owner[v]) +
           ", not one of the ranks 0.." + std::to_string(ranks - 1));

  // One pass over each list: an element's distinct endpoint owners say whether this rank
  // holds it, and which other ranks hold it (and its endpoints this rank owns) as ghosts.
  std::vector<uint8_t> ghost_vertex(n, 0);
  std::vector<RankIndex> vertex_sends;  // (other rank, GLOBAL vertex) until the local numbers
  std::vector<ListPart> parts(lists.size());
  std::vector<int32_t> owners;
  for (size_t l = 0; l < lists.size(); ++l) {
    const runtime::ElementList& list = lists[l];
    if (list.arity < 1)
      fail("element list " + std::to_string(l) + " has arity " + std::to_string(list.arity) +
           "; it must be at least 1");
    const auto arity = static_cast<size_t>(list.arity);
    if (list.indices.size() % arity != 0)
      fail("element list " + std::to_string(l) + " has " + std::to_string(list.indices.size()) +
           " endpoints, not a multiple of its arity " + std::to_string(arity));
    const size_t count = list.indices.size() / arity;
    if (count > static_cast<size_t>(std::numeric_limits<int32_t>::max()))
      fail("element list " + std::to_string(l) + " has more elements than an int32 counts");
    ListPart& part = parts[l];
    for (size_t e = 0; e < count; ++e) {
      const auto vs = list.indices.subspan(e * arity, arity);
      owners.clear();
      bool local = false;
      for (int32_t v : vs) {
        if (v < 0 || static_cast<size_t>(v) >= n)
          fail("element " + std::to_string(e) + " of list " + std::to_string(l) + " has endpoint " +
               std::to_string(v) + ", not one of the " + std::to_string(n) + " vertices");
        const int32_t q = vertex_owner[static_cast<size_t>(v)];
        local = local || q == rank;
        if (std::find(owners.begin(), owners.end(), q) == owners.end()) owners.push_back(q);
      }
      if (!local) continue;
      const int32_t owner = element_owner(vs, vertex_owner);
      if (owner == rank) {
        part.owned.push_back(static_cast<int32_t>(e));
        for (int32_t q : owners)
          if (q != rank) part.sends.emplace_back(q, static_cast<int32_t>(e));
      } else {
        part.ghosts.push_back(static_cast<int32_t>(e));
        part.ghost_owner.push_back(owner);
      }
      // Every rank owning an endpoint holds this element, and so all its endpoints.
      for (int32_t v : vs) {
        if (vertex_owner[static_cast<size_t>(v)] != rank) {
          ghost_vertex[static_cast<size_t>(v)] = 1;
          continue;
        }
        for (int32_t q : owners)
          if (q != rank) vertex_sends.emplace_back(q, v);
      }
    }
  }

  RankLayout layout;
  std::vector<int32_t> local_of(n, -1);
  SetPart& vertices = layout.vertices;
  for (size_t v = 0; v < n; ++v) {
    if (vertex_owner[v] != rank && !ghost_vertex[v]) continue;
    const auto local = static_cast<int32_t>(vertices.global.size());
    vertices.global.push_back(static_cast<int32_t>(v));
    if (vertex_owner[v] == rank) {
      vertices.owned.push_back(local);
    } else {
      vertices.ghosts.push_back(local);
      vertices.ghost_owner.push_back(vertex_owner[v]);
    }
  }
  for (size_t i = 0; i < vertices.global.size(); ++i)
    local_of[static_cast<size_t>(vertices.global[i])] = static_cast<int32_t>(i);
  for (auto& [q, v] : vertex_sends) v = local_of[static_cast<size_t>(v)];
  layout.vertex_plan = make_plan(std::move(vertex_sends), vertices);

  for (size_t l = 0; l < lists.size(); ++l) {
    ListPart& part = parts[l];
    SetPart set = merge_part(part.owned, part.ghosts, std::move(part.ghost_owner));
    for (auto& [q, e] : part.sends) e = local_index(set, e);
    layout.edge_plans.push_back(make_plan(std::move(part.sends), set));
    const auto arity = static_cast<size_t>(lists[l].arity);
    std::vector<int32_t>& connectivity = layout.local_connectivity.emplace_back();
    connectivity.reserve(set.global.size() * arity);
    for (int32_t e : set.global)
      for (int32_t v : lists[l].indices.subspan(static_cast<size_t>(e) * arity, arity))
        connectivity.push_back(local_of[static_cast<size_t>(v)]);
    layout.edge_sets.push_back(std::move(set));
  }
  return layout;
}

}  // namespace simit::dist
