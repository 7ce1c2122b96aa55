// Checks of the distributed layer run under `mpirun -np 2` (ctest label mpi):
//   dist_mpi_check preflight   the ranks see each other (an environment failure, told apart)
//   dist_mpi_check parts MESH  rank 0 reads the mesh and partitions it into one part per
//                              rank; every rank takes its part (dist/local_part.h) from what
//                              rank 0 broadcast, and rank 0 checks that every rank owns
//                              vertices and elements, has ghosts, and that the owned counts
//                              add up to the mesh's
//   dist_mpi_check exchange MESH  the same mesh and parts; every rank builds its overlapping
//                              layout (dist/overlap.h), fills its owned vertex (3 doubles)
//                              and tet (1 int32) entries from their global indices and its
//                              ghosts with NaN (or -1), refreshes the ghosts and checks each
//                              is its owner's entry; then the all-gather in rank order, the gather
//                              of the vertex entries on rank 0, and `any`
// Exit status 0 on every rank when the check holds, else 1 with the reason from rank 0.
#include <cmath>
#include <cstdio>
#include <cstring>
#include <exception>
#include <limits>
#include <span>
#include <string>
#include <vector>

#include "dist/local_part.h"
#include "dist/mpi/comm.h"
#include "dist/overlap.h"
#include "dist/partition.h"
#include "runtime/mesh/mesh_reader.h"

namespace {

using simit::dist::mpi::Session;

int preflight(const Session& mpi) {
  const int64_t n = mpi.size();
  const bool ok = n >= 2 && mpi.sum(mpi.rank() + 1) == n * (n + 1) / 2;
  if (mpi.rank() == 0) {
    if (ok)
      std::printf("preflight: %lld ranks see each other\n", static_cast<long long>(n));
    else
      std::fprintf(stderr, "preflight: %lld rank(s), and they do not all see each other\n",
                   static_cast<long long>(n));
  }
  return ok ? 0 : 1;
}

// Rank 0 reads the mesh at `path` and partitions its tets into one part per rank; every rank
// then holds the tets (4 vertices each), the owner of each vertex and {ok, vertex count}.
// False (on every rank) when rank 0 could not.
bool read_and_broadcast(const Session& mpi, const std::string& path, std::vector<int32_t>& tets,
                        std::vector<int32_t>& owner, int32_t& vertices) {
  std::vector<int32_t> head = {0, 0};
  if (mpi.rank() == 0) {
    try {
      const simit::runtime::Mesh mesh = simit::runtime::read_mesh(path);
      for (const auto& t : mesh.tets) tets.insert(tets.end(), t.begin(), t.end());
      const std::vector<simit::runtime::ElementList> lists = {{tets, 4}};
      const auto n = static_cast<int32_t>(mesh.points.size());
      owner = simit::dist::partition_vertices(simit::runtime::vertex_graph(n, lists), mpi.size(),
                                              lists);
      head = {1, n};
    } catch (const std::exception& e) {
      std::fprintf(stderr, "%s: %s\n", path.c_str(), e.what());
    }
  }
  mpi.broadcast(head);
  if (head[0] == 0) return false;
  mpi.broadcast(tets);
  mpi.broadcast(owner);
  vertices = head[1];
  return true;
}

int parts(const Session& mpi, const std::string& path) {
  std::vector<int32_t> tets, owner;
  int32_t n = 0;
  if (!read_and_broadcast(mpi, path, tets, owner, n)) return 1;
  const std::vector<simit::runtime::ElementList> lists = {{tets, 4}};
  const simit::dist::LocalPart mine = simit::dist::local_part(lists, owner, mpi.rank());
  const auto v = static_cast<int64_t>(mine.owned_vertices.size());
  const auto e = static_cast<int64_t>(mine.owned_elements[0].size());
  const auto g = static_cast<int64_t>(mine.ghost_vertices.size());
  // Every ghost is another rank's vertex.
  int64_t bad = 0;
  for (int32_t x : mine.ghost_vertices) bad += owner[static_cast<size_t>(x)] == mpi.rank();
  const std::vector<int64_t> vs = mpi.gather(v), es = mpi.gather(e), gs = mpi.gather(g);
  const int64_t wrong = mpi.sum(bad);
  int failed = 0;
  if (mpi.rank() == 0) {
    int64_t vertices = 0, elements = 0;
    for (int r = 0; r < mpi.size(); ++r) {
      const auto i = static_cast<size_t>(r);
      std::printf("rank %d: owns %lld vertices and %lld tets, %lld ghosts\n", r,
                  static_cast<long long>(vs[i]), static_cast<long long>(es[i]),
                  static_cast<long long>(gs[i]));
      vertices += vs[i];
      elements += es[i];
      if (vs[i] == 0 || es[i] == 0 || gs[i] == 0) failed = 1;
    }
    if (vertices != n || elements * 4 != static_cast<int64_t>(tets.size()) || wrong != 0)
      failed = 1;
    std::printf(
        "%s: %lld of %d vertices and %lld of %zu tets owned, %lld ghosts owned by "
        "their own rank\n",
        failed ? "FAILED" : "ok", static_cast<long long>(vertices), n,
        static_cast<long long>(elements), tets.size() / 4, static_cast<long long>(wrong));
  }
  return mpi.sum(failed) == 0 ? 0 : 1;
}

// The entries the exchange check gives global vertex v (3 doubles) and global tet e.
double vertex_entry(int32_t v, int k) { return 0.25 * v + 1000.0 * k + 1.0 / 3.0; }
int32_t tet_entry(int32_t e) { return 7 * e + 3; }

int exchange(const Session& mpi, const std::string& path) {
  std::vector<int32_t> tets, owner;
  int32_t n = 0;
  if (!read_and_broadcast(mpi, path, tets, owner, n)) return 1;
  const std::vector<simit::runtime::ElementList> lists = {{tets, 4}};
  const simit::dist::RankLayout layout =
      simit::dist::overlap_layout(owner, lists, mpi.size(), mpi.rank());
  const simit::dist::SetPart& vs = layout.vertices;
  const simit::dist::SetPart& ts = layout.edge_sets[0];
  int64_t bad = 0;  // failed checks on this rank

  // Vertices: 3 doubles each, the ghosts NaN until refreshed.
  std::vector<double> x(vs.global.size() * 3, std::numeric_limits<double>::quiet_NaN());
  for (int32_t i : vs.owned)
    for (int k = 0; k < 3; ++k)
      x[static_cast<size_t>(i) * 3 + static_cast<size_t>(k)] =
          vertex_entry(vs.global[static_cast<size_t>(i)], k);
  mpi.refresh_ghosts(layout.vertex_plan, std::as_writable_bytes(std::span(x)), 3 * sizeof(double));
  for (size_t i = 0; i < vs.global.size(); ++i)
    for (int k = 0; k < 3; ++k)
      bad += x[i * 3 + static_cast<size_t>(k)] != vertex_entry(vs.global[i], k);

  // Tets: one int32 each, the ghosts -1 until refreshed.
  std::vector<int32_t> t(ts.global.size(), -1);
  for (int32_t i : ts.owned)
    t[static_cast<size_t>(i)] = tet_entry(ts.global[static_cast<size_t>(i)]);
  mpi.refresh_ghosts(layout.edge_plans[0], std::as_writable_bytes(std::span(t)), sizeof(int32_t));
  for (size_t i = 0; i < ts.global.size(); ++i) bad += t[i] != tet_entry(ts.global[i]);
  const auto ghosts = static_cast<int64_t>(vs.ghosts.size() + ts.ghosts.size());

  // Every rank's values in rank order: rank r gives r + 1 values r + 0.5.
  const std::vector<double> gathered =
      mpi.all_gather(std::vector<double>(static_cast<size_t>(mpi.rank()) + 1, mpi.rank() + 0.5));
  std::vector<double> expected;
  for (int r = 0; r < mpi.size(); ++r) expected.insert(expected.end(), r + 1, r + 0.5);
  bad += gathered != expected;

  // The owned vertex entries gathered on rank 0: the whole array.
  std::vector<int32_t> owned_global;
  std::vector<double> owned_values;
  for (int32_t i : vs.owned) {
    owned_global.push_back(vs.global[static_cast<size_t>(i)]);
    for (int k = 0; k < 3; ++k)
      owned_values.push_back(x[static_cast<size_t>(i) * 3 + static_cast<size_t>(k)]);
  }
  const std::vector<std::byte> whole =
      mpi.gather_owned(owned_global, std::as_bytes(std::span(owned_values)), 3 * sizeof(double), n);
  if (mpi.rank() == 0) {
    if (whole.size() != static_cast<size_t>(n) * 3 * sizeof(double)) {
      ++bad;
    } else {
      std::vector<double> all(static_cast<size_t>(n) * 3);
      std::memcpy(all.data(), whole.data(), whole.size());
      for (int32_t v = 0; v < n; ++v)
        for (int k = 0; k < 3; ++k)
          bad += all[static_cast<size_t>(v) * 3 + static_cast<size_t>(k)] != vertex_entry(v, k);
    }
  } else {
    bad += !whole.empty();
  }

  bad += !mpi.any(mpi.rank() == 1);
  bad += mpi.any(false);

  const std::vector<int64_t> bads = mpi.gather(bad), ghost_counts = mpi.gather(ghosts);
  int failed = 0;
  if (mpi.rank() == 0) {
    for (int r = 0; r < mpi.size(); ++r) {
      const auto i = static_cast<size_t>(r);
      std::printf("rank %d: %lld ghost vertices and tets refreshed, %lld failed checks\n", r,
                  static_cast<long long>(ghost_counts[i]), static_cast<long long>(bads[i]));
      if (bads[i] != 0 || ghost_counts[i] == 0) failed = 1;
    }
    std::printf(
        "%s: ghosts refreshed, %zu values gathered from every rank, %d vertices "
        "gathered\n",
        failed ? "FAILED" : "ok", gathered.size(), n);
  }
  return mpi.sum(failed) == 0 ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  Session mpi(&argc, &argv);
  const std::string mode = argc > 1 ? argv[1] : "";
  if (mode == "preflight") return preflight(mpi);
  if (mode == "parts" && argc > 2) return parts(mpi, argv[2]);
  if (mode == "exchange" && argc > 2) {
    // An error on one rank ends them all (the others may be waiting on it).
    try {
      return exchange(mpi, argv[2]);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "rank %d: %s\n", mpi.rank(), e.what());
      mpi.abort(1);
    }
  }
  if (mpi.rank() == 0)
    std::fprintf(stderr, "usage: dist_mpi_check preflight | parts MESH | exchange MESH\n");
  return 2;
}
