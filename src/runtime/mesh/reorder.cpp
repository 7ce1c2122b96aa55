// Vertex and element orders for locality: reverse Cuthill-McKee, a Hilbert curve, and the
// elements by their smallest vertex.
#include "runtime/mesh/reorder.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <string>

namespace simit::runtime {

namespace {

void check_vertex(int32_t v, int32_t vertices, size_t element) {
  if (v < 0 || v >= vertices)
    throw MeshError("element " + std::to_string(element) + " has the vertex index " +
                    std::to_string(v) + ", outside [0, " + std::to_string(vertices) + ")");
}

void check_arity(const ElementList& list) {
  if (list.arity < 1 || list.indices.size() % static_cast<size_t>(list.arity) != 0)
    throw MeshError("an element list of arity " + std::to_string(list.arity) + " holds " +
                    std::to_string(list.indices.size()) + " indices");
}

// A breadth-first search over the vertices not yet numbered, from `root`: the vertices it
// reaches in visiting order, in levels.
struct LevelStructure {
  std::vector<int32_t> vertices;
  size_t last_level_begin = 0;  // where the deepest level starts in `vertices`
  int depth = 0;                // levels - 1: the root's eccentricity in its component
};

class Searcher {
 public:
  explicit Searcher(const VertexGraph& g) : g_(g), mark_(static_cast<size_t>(g.vertices()), 0) {}

  // Levels from `root` through the vertices with numbered[v] == 0.
  const LevelStructure& levels(int32_t root, const std::vector<char>& numbered) {
    ++stamp_;
    out_.vertices.clear();
    out_.vertices.push_back(root);
    mark_[root] = stamp_;
    out_.depth = 0;
    size_t begin = 0;
    while (true) {
      const size_t end = out_.vertices.size();
      out_.last_level_begin = begin;
      for (size_t i = begin; i < end; ++i) {
        const int32_t v = out_.vertices[i];
        for (int64_t k = g_.offsets[v]; k < g_.offsets[v + 1]; ++k) {
          const int32_t u = g_.neighbours[k];
          if (mark_[u] == stamp_ || numbered[u]) continue;
          mark_[u] = stamp_;
          out_.vertices.push_back(u);
        }
      }
      if (out_.vertices.size() == end) break;
      begin = end;
      ++out_.depth;
    }
    return out_;
  }

 private:
  const VertexGraph& g_;
  std::vector<uint32_t> mark_;
  uint32_t stamp_ = 0;
  LevelStructure out_;
};

// The vertex of least degree (then least index) among `candidates`.
int32_t least_degree(const VertexGraph& g, std::span<const int32_t> candidates) {
  int32_t best = candidates[0];
  for (int32_t v : candidates)
    if (g.degree(v) < g.degree(best) || (g.degree(v) == g.degree(best) && v < best)) best = v;
  return best;
}

// George and Liu's pseudo-peripheral vertex of the component holding `seed`: from the vertex
// of least degree, move to the least-degree vertex of the deepest level while that deepens
// the level structure.
int32_t pseudo_peripheral(const VertexGraph& g, Searcher& search, int32_t seed,
                          const std::vector<char>& numbered) {
  int32_t root = least_degree(g, search.levels(seed, numbered).vertices);
  const LevelStructure* ls = &search.levels(root, numbered);
  int depth = ls->depth;
  while (true) {
    const int32_t next =
        least_degree(g, std::span<const int32_t>(ls->vertices).subspan(ls->last_level_begin));
    ls = &search.levels(next, numbered);
    if (ls->depth <= depth) return root;
    root = next;
    depth = ls->depth;
  }
}

// One axis-interleaved 3-D Hilbert index of lattice coordinates of `bits` bits each (John
// Skilling, "Programming the Hilbert curve", AIP Conf. Proc. 707, 2004: axes to transpose,
// then the transpose's bits read out).
uint64_t hilbert_index(std::array<uint32_t, 3> x, int bits) {
  const uint32_t top = 1u << (bits - 1);
  for (uint32_t q = top; q > 1; q >>= 1) {
    const uint32_t p = q - 1;
    for (int i = 0; i < 3; ++i) {
      if (x[i] & q) {
        x[0] ^= p;
      } else {
        const uint32_t t = (x[0] ^ x[i]) & p;
        x[0] ^= t;
        x[i] ^= t;
      }
    }
  }
  for (int i = 1; i < 3; ++i) x[i] ^= x[i - 1];
  uint32_t t = 0;
  for (uint32_t q = top; q > 1; q >>= 1)
    if (x[2] & q) t ^= q - 1;
  for (int i = 0; i < 3; ++i) x[i] ^= t;
  uint64_t key = 0;
  for (int b = bits - 1; b >= 0; --b)
    for (int i = 0; i < 3; ++i) key = (key << 1) | ((x[i] >> b) & 1u);
  return key;
}

}  // namespace

VertexGraph vertex_graph(int32_t vertices, std::span<const ElementList> lists) {
  VertexGraph g;
  g.offsets.assign(static_cast<size_t>(vertices) + 1, 0);
  // Counted with repeats first, then filled, then each vertex's list sorted and compacted.
  for (const ElementList& list : lists) {
    check_arity(list);
    const size_t a = static_cast<size_t>(list.arity);
    for (size_t i = 0; i < list.indices.size(); ++i) {
      check_vertex(list.indices[i], vertices, i / a);
      g.offsets[static_cast<size_t>(list.indices[i]) + 1] += list.arity - 1;
    }
  }
  std::partial_sum(g.offsets.begin(), g.offsets.end(), g.offsets.begin());
  std::vector<int64_t> fill(g.offsets.begin(), g.offsets.end() - 1);
  g.neighbours.resize(static_cast<size_t>(g.offsets.back()));
  for (const ElementList& list : lists) {
    const size_t a = static_cast<size_t>(list.arity);
    for (size_t e = 0; e < list.indices.size(); e += a)
      for (size_t i = 0; i < a; ++i)
        for (size_t j = 0; j < a; ++j)
          if (i != j) g.neighbours[fill[list.indices[e + i]]++] = list.indices[e + j];
  }
  int64_t kept = 0;
  for (int32_t v = 0; v < vertices; ++v) {
    auto first = g.neighbours.begin() + g.offsets[v],
         last = g.neighbours.begin() + g.offsets[v + 1];
    std::sort(first, last);
    last = std::unique(first, last);
    g.offsets[v] = kept;
    for (auto it = first; it != last; ++it)
      if (*it != v) g.neighbours[kept++] = *it;  // an element repeating a vertex: no loop
  }
  g.offsets[vertices] = kept;
  g.neighbours.resize(static_cast<size_t>(kept));
  g.neighbours.shrink_to_fit();
  return g;
}

std::vector<int32_t> reverse_cuthill_mckee(const VertexGraph& g) {
  const int32_t n = g.vertices();
  std::vector<int32_t> order(static_cast<size_t>(n));
  if (g.neighbours.empty()) {
    std::iota(order.begin(), order.end(), 0);
    return order;
  }
  order.clear();
  std::vector<char> numbered(static_cast<size_t>(n), 0);
  Searcher search(g);
  std::vector<int32_t> next;
  for (int32_t seed = 0; seed < n; ++seed) {
    if (numbered[seed]) continue;
    const int32_t start = pseudo_peripheral(g, search, seed, numbered);
    size_t head = order.size();
    order.push_back(start);
    numbered[start] = 1;
    while (head < order.size()) {
      const int32_t v = order[head++];
      next.clear();
      for (int64_t k = g.offsets[v]; k < g.offsets[v + 1]; ++k)
        if (!numbered[g.neighbours[k]]) next.push_back(g.neighbours[k]);
      std::sort(next.begin(), next.end(), [&](int32_t a, int32_t b) {
        return g.degree(a) != g.degree(b) ? g.degree(a) < g.degree(b) : a < b;
      });
      for (int32_t u : next) {
        numbered[u] = 1;
        order.push_back(u);
      }
    }
  }
  std::reverse(order.begin(), order.end());
  return order;
}

std::vector<int32_t> hilbert_order(std::span<const Point> points) {
  constexpr int kBits = 21;  // 3 x 21 bits: one 63-bit key
  const size_t n = points.size();
  std::vector<int32_t> order(n);
  std::iota(order.begin(), order.end(), 0);
  if (n == 0) return order;
  Point lo = points[0], hi = points[0];
  for (const Point& p : points)
    for (int d = 0; d < 3; ++d) {
      lo[d] = std::min(lo[d], p[d]);
      hi[d] = std::max(hi[d], p[d]);
    }
  const double extent = std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]});
  if (!(extent > 0) || !std::isfinite(extent)) return order;
  const double scale = double((1u << kBits) - 1) / extent;
  std::vector<uint64_t> key(n);
  for (size_t i = 0; i < n; ++i) {
    std::array<uint32_t, 3> x{};
    for (int d = 0; d < 3; ++d) {
      const double q = std::floor((points[i][d] - lo[d]) * scale);
      x[d] = static_cast<uint32_t>(std::clamp(q, 0.0, double((1u << kBits) - 1)));
    }
    key[i] = hilbert_index(x, kBits);
  }
  std::stable_sort(order.begin(), order.end(),
                   [&](int32_t a, int32_t b) { return key[a] < key[b]; });
  return order;
}

std::vector<int32_t> invert_permutation(std::span<const int32_t> order) {
  const int32_t n = static_cast<int32_t>(order.size());
  std::vector<int32_t> position(order.size(), -1);
  for (int32_t i = 0; i < n; ++i) {
    const int32_t v = order[i];
    if (v < 0 || v >= n || position[v] >= 0)
      throw MeshError("not a permutation of 0.." + std::to_string(n - 1) + ": entry " +
                      std::to_string(i) + " is " + std::to_string(v) +
                      (v >= 0 && v < n ? ", which an earlier entry is too" : ""));
    position[v] = i;
  }
  return position;
}

int64_t bandwidth(const VertexGraph& g, std::span<const int32_t> position) {
  int64_t width = 0;
  for (int32_t v = 0; v < g.vertices(); ++v)
    for (int64_t k = g.offsets[v]; k < g.offsets[v + 1]; ++k)
      width = std::max<int64_t>(
          width, std::abs(int64_t(position[v]) - int64_t(position[g.neighbours[k]])));
  return width;
}

std::vector<int32_t> element_order(const ElementList& list, std::span<const int32_t> position) {
  check_arity(list);
  const int32_t vertices = static_cast<int32_t>(position.size());
  const size_t a = static_cast<size_t>(list.arity), count = list.indices.size() / a;
  // A counting sort on the smallest new vertex: stable, and linear in the elements.
  std::vector<int32_t> key(count);
  std::vector<size_t> start(static_cast<size_t>(vertices) + 1, 0);
  for (size_t e = 0; e < count; ++e) {
    int32_t least = vertices;
    for (size_t k = 0; k < a; ++k) {
      const int32_t v = list.indices[e * a + k];
      check_vertex(v, vertices, e);
      least = std::min(least, position[v]);
    }
    key[e] = least;
    ++start[static_cast<size_t>(least) + 1];
  }
  std::partial_sum(start.begin(), start.end(), start.begin());
  std::vector<int32_t> order(count);
  for (size_t e = 0; e < count; ++e) order[start[key[e]]++] = static_cast<int32_t>(e);
  return order;
}

std::vector<int32_t> renumber_elements(const ElementList& list, std::span<const int32_t> order,
                                       std::span<const int32_t> position) {
  check_arity(list);
  const size_t a = static_cast<size_t>(list.arity);
  const size_t count = list.indices.size() / a;
  if (order.size() != count)
    throw MeshError("an element order of " + std::to_string(order.size()) + " entries for " +
                    std::to_string(count) + " elements");
  const int32_t vertices = static_cast<int32_t>(position.size());
  std::vector<int32_t> out(count * a);
  for (size_t e = 0; e < count; ++e) {
    if (order[e] < 0 || static_cast<size_t>(order[e]) >= count)
      throw MeshError("the element order names element " + std::to_string(order[e]) + " of " +
                      std::to_string(count));
    for (size_t k = 0; k < a; ++k) {
      const int32_t v = list.indices[static_cast<size_t>(order[e]) * a + k];
      check_vertex(v, vertices, static_cast<size_t>(order[e]));
      out[e * a + k] = position[v];
    }
  }
  return out;
}

std::vector<int32_t> locality_order(const Mesh& m, bool hilbert) {
  if (m.tets.empty() && m.triangles.empty() && m.edges.empty()) return {};
  const auto n = static_cast<int32_t>(m.points.size());
  std::vector<int32_t> order;
  if (hilbert) {
    order = hilbert_order(m.points);
  } else {
    static_assert(sizeof(Tet) == 4 * sizeof(int32_t) && sizeof(Edge) == 2 * sizeof(int32_t));
    auto flat = [](const auto& list) {
      return std::span<const int32_t>(list.empty() ? nullptr : list.front().data(),
                                      list.size() * (list.empty() ? 0 : list.front().size()));
    };
    const ElementList lists[] = {{flat(m.tets), 4}, {flat(m.triangles), 3}, {flat(m.edges), 2}};
    order = reverse_cuthill_mckee(vertex_graph(n, lists));
  }
  bool identity = true;
  for (int32_t i = 0; i < n && identity; ++i) identity = order[static_cast<size_t>(i)] == i;
  if (identity) order.clear();
  return order;
}

}  // namespace simit::runtime
