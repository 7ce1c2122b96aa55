// The vertex partition by METIS and what it makes of a mesh's elements (dist/partition.h).
#include "dist/partition.h"

#include "dist/local_part.h"

#include <metis.h>

#include <algorithm>
#include <limits>
#include <string>

namespace simit::dist {

std::vector<int32_t> partition_vertices(const runtime::VertexGraph& graph, int parts,
                                        std::span<const runtime::ElementList> lists,
                                        std::span<const int32_t> sizes) {
  const int32_t n = graph.vertices();
  if (parts < 1)
    throw PartitionError("the number of parts must be at least 1, not " + std::to_string(parts));
  if (parts > n)
    throw PartitionError("cannot cut " + std::to_string(n) + " vertices into " +
                         std::to_string(parts) + " parts: each part needs a vertex");
  std::vector<int32_t> owner(static_cast<size_t>(n), 0);
  if (parts == 1) return owner;
  // METIS's index type is 32 bits in Debian's build (IDXTYPEWIDTH); the graph's offsets must
  // fit it.
  if (graph.offsets.back() > std::numeric_limits<idx_t>::max())
    throw PartitionError("the vertex graph has too many edges for METIS's 32-bit indices");
  std::vector<idx_t> xadj(graph.offsets.begin(), graph.offsets.end());
  std::vector<idx_t> adjncy(graph.neighbours.begin(), graph.neighbours.end());
  // A vertex weighs its size (1, or what `sizes` says: the vertices a chunk stands for); with
  // elements, also the elements whose lowest vertex it is (the ones its part will own), and
  // METIS balances both weights.
  if (!sizes.empty() && sizes.size() != static_cast<size_t>(n))
    throw PartitionError(std::to_string(sizes.size()) + " vertex sizes for " + std::to_string(n) +
                         " vertices");
  auto size_of = [&](size_t v) { return sizes.empty() ? idx_t{1} : idx_t{sizes[v]}; };
  std::vector<idx_t> weights;
  idx_t constraints = 1;
  if (!sizes.empty()) {
    weights.resize(static_cast<size_t>(n));
    for (size_t v = 0; v < static_cast<size_t>(n); ++v) weights[v] = size_of(v);
  }
  if (!lists.empty()) {
    constraints = 2;
    weights.assign(2 * static_cast<size_t>(n), 0);
    for (size_t v = 0; v < static_cast<size_t>(n); ++v) weights[2 * v] = size_of(v);
    for (const runtime::ElementList& list : lists) {
      const auto arity = static_cast<size_t>(list.arity);
      for (size_t e = 0; e + arity <= list.indices.size(); e += arity) {
        const auto vs = list.indices.subspan(e, arity);
        ++weights[2 * static_cast<size_t>(*std::min_element(vs.begin(), vs.end())) + 1];
      }
    }
  }
  idx_t vertices = n, nparts = parts, cut = 0;
  idx_t options[METIS_NOPTIONS];
  METIS_SetDefaultOptions(options);
  options[METIS_OPTION_SEED] = 1;  // the same parts on every run
  options[METIS_OPTION_NUMBERING] = 0;
  std::vector<idx_t> part(static_cast<size_t>(n), 0);
  const int status =
      METIS_PartGraphKway(&vertices, &constraints, xadj.data(), adjncy.data(),
                          weights.empty() ? nullptr : weights.data(), nullptr, nullptr, &nparts,
                          nullptr, nullptr, options, &cut, part.data());
  if (status != METIS_OK)
    throw PartitionError(
        std::string("METIS could not partition the graph (") +
        (status == METIS_ERROR_MEMORY ? "out of memory" : "error " + std::to_string(status)) + ")");
  std::copy(part.begin(), part.end(), owner.begin());
  return owner;
}

std::vector<int32_t> partition_in_chunks(int32_t vertices,
                                         std::span<const runtime::ElementList> lists, int parts,
                                         int32_t chunk) {
  if (parts < 1)
    throw PartitionError("the number of parts must be at least 1, not " + std::to_string(parts));
  if (chunk < 1) throw PartitionError("chunks of " + std::to_string(chunk) + " vertices");
  const int32_t chunks = vertices / chunk + (vertices % chunk != 0 ? 1 : 0);
  const int32_t unit = chunks >= parts ? chunk : 1;
  const int32_t units = unit == 1 ? vertices : chunks;
  std::vector<int32_t> unit_part(static_cast<size_t>(units));
  if (lists.empty() || units <= parts || parts == 1) {
    // (With fewer vertices than parts, some parts own none.)
    for (int32_t u = 0; u < units; ++u)
      unit_part[static_cast<size_t>(u)] =
          static_cast<int32_t>(static_cast<int64_t>(u) * parts / std::max<int32_t>(units, 1));
  } else {
    // The elements with each endpoint replaced by its chunk: an element's lowest chunk holds
    // its lowest vertex, so the elements each chunk's part will own are weighed right.
    std::vector<std::vector<int32_t>> coarse(lists.size());
    std::vector<runtime::ElementList> unit_lists;
    for (size_t l = 0; l < lists.size(); ++l) {
      coarse[l].reserve(lists[l].indices.size());
      for (int32_t v : lists[l].indices) coarse[l].push_back(v / unit);
      unit_lists.push_back({coarse[l], lists[l].arity});
    }
    std::vector<int32_t> sizes(static_cast<size_t>(units), unit);
    if (units > 0) sizes.back() = vertices - (units - 1) * unit;
    unit_part =
        partition_vertices(runtime::vertex_graph(units, unit_lists), parts, unit_lists, sizes);
  }
  std::vector<int32_t> part(static_cast<size_t>(vertices));
  for (int32_t v = 0; v < vertices; ++v)
    part[static_cast<size_t>(v)] = unit_part[static_cast<size_t>(v / unit)];
  return part;
}

PartitionStats partition_stats(const runtime::VertexGraph& graph,
                               std::span<const runtime::ElementList> lists,
                               std::span<const int32_t> owner, int parts) {
  PartitionStats s;
  s.parts = parts;
  s.per_part.resize(static_cast<size_t>(parts));
  const int32_t n = graph.vertices();
  for (int32_t v = 0; v < n; ++v) {
    ++s.per_part[static_cast<size_t>(owner[static_cast<size_t>(v)])].vertices;
    for (int64_t k = graph.offsets[v]; k < graph.offsets[v + 1]; ++k) {
      const int32_t w = graph.neighbours[static_cast<size_t>(k)];
      if (w <= v) continue;  // each edge once
      ++s.graph_edges;
      if (owner[static_cast<size_t>(v)] != owner[static_cast<size_t>(w)]) ++s.cut_edges;
    }
  }
  // Per part, the vertices its elements reach (a mark per vertex: the last part that
  // reached it), and among them the ghosts and the parts that own them.
  std::vector<int32_t> reached(static_cast<size_t>(n), -1);
  std::vector<std::vector<int32_t>> elements_of(static_cast<size_t>(parts));
  for (size_t l = 0; l < lists.size(); ++l) {
    const runtime::ElementList& list = lists[l];
    const size_t count = list.indices.size() / static_cast<size_t>(list.arity);
    for (size_t e = 0; e < count; ++e) {
      const auto vs = list.indices.subspan(e * static_cast<size_t>(list.arity),
                                           static_cast<size_t>(list.arity));
      const int32_t p = element_owner(vs, owner);
      ++s.per_part[static_cast<size_t>(p)].elements;
      elements_of[static_cast<size_t>(p)].insert(elements_of[static_cast<size_t>(p)].end(),
                                                 vs.begin(), vs.end());
    }
  }
  std::vector<int32_t> seen_part(static_cast<size_t>(parts), -1);
  for (int32_t p = 0; p < parts; ++p) {
    PartStats& ps = s.per_part[static_cast<size_t>(p)];
    for (int32_t v : elements_of[static_cast<size_t>(p)]) {
      if (reached[static_cast<size_t>(v)] == p) continue;
      reached[static_cast<size_t>(v)] = p;
      const int32_t o = owner[static_cast<size_t>(v)];
      if (o == p) continue;
      ++ps.ghosts;
      if (seen_part[static_cast<size_t>(o)] != p) {
        seen_part[static_cast<size_t>(o)] = p;
        ++ps.neighbours;
      }
    }
  }
  return s;
}

int64_t PartitionStats::total_ghosts() const {
  int64_t t = 0;
  for (const PartStats& p : per_part) t += p.ghosts;
  return t;
}

namespace {

template <class F>
double imbalance(const std::vector<PartStats>& parts, F of) {
  if (parts.empty()) return 1.0;
  int64_t most = 0, total = 0;
  for (const PartStats& p : parts) {
    most = std::max(most, of(p));
    total += of(p);
  }
  return total == 0 ? 1.0
                    : static_cast<double>(most) * static_cast<double>(parts.size()) /
                          static_cast<double>(total);
}

}  // namespace

double PartitionStats::vertex_imbalance() const {
  return imbalance(per_part, [](const PartStats& p) { return p.vertices; });
}

double PartitionStats::element_imbalance() const {
  return imbalance(per_part, [](const PartStats& p) { return p.elements; });
}

int64_t PartitionStats::most_ghosts() const {
  int64_t m = 0;
  for (const PartStats& p : per_part) m = std::max(m, p.ghosts);
  return m;
}

int64_t PartitionStats::most_neighbours() const {
  int64_t m = 0;
  for (const PartStats& p : per_part) m = std::max(m, p.neighbours);
  return m;
}

}  // namespace simit::dist
