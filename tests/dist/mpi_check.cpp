// Checks of the distributed layer run under `mpirun -np 2` (ctest label mpi):
//   dist_mpi_check preflight   the ranks see each other (an environment failure, told apart)
//   dist_mpi_check parts MESH  rank 0 reads the mesh and partitions it into one part per
//                              rank; every rank takes its part (dist/local_part.h) from what
//                              rank 0 broadcast, and rank 0 checks that every rank owns
//                              vertices and elements, has ghosts, and that the owned counts
//                              add up to the mesh's
// Exit status 0 on every rank when the check holds, else 1 with the reason from rank 0.
#include <cstdio>
#include <exception>
#include <string>
#include <vector>

#include "dist/local_part.h"
#include "dist/mpi/comm.h"
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

int parts(const Session& mpi, const std::string& path) {
  // Rank 0 reads and partitions; the others receive {ok, vertices}, the tets and the owners.
  std::vector<int32_t> head = {0, 0}, tets, owner;
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
      std::fprintf(stderr, "parts: %s\n", e.what());
    }
  }
  mpi.broadcast(head);
  if (head[0] == 0) return 1;
  mpi.broadcast(tets);
  mpi.broadcast(owner);
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
    if (vertices != head[1] || elements * 4 != static_cast<int64_t>(tets.size()) || wrong != 0)
      failed = 1;
    std::printf(
        "%s: %lld of %d vertices and %lld of %zu tets owned, %lld ghosts owned by "
        "their own rank\n",
        failed ? "FAILED" : "ok", static_cast<long long>(vertices), head[1],
        static_cast<long long>(elements), tets.size() / 4, static_cast<long long>(wrong));
  }
  return mpi.sum(failed) == 0 ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  Session mpi(&argc, &argv);
  const std::string mode = argc > 1 ? argv[1] : "";
  if (mode == "preflight") return preflight(mpi);
  if (mode == "parts" && argc > 2) return parts(mpi, argv[2]);
  if (mpi.rank() == 0) std::fprintf(stderr, "usage: dist_mpi_check preflight | parts MESH\n");
  return 2;
}
