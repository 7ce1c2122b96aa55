// `simit partition MESH --parts K,...`: the mesh's vertex graph cut into K parts as
// `simit run --distributed` cuts it (dist/partition.h: whole chunks of the blocked sums), and
// what each cut leaves to exchange.
#include <chrono>
#include <cstdio>
#include <span>
#include <string>
#include <vector>

#include "runtime/blocked_sum.h"
#include "runtime/mesh/mesh_reader.h"
#include "runtime/mesh/reorder.h"
#include "simit/commands.h"
#ifdef SIMIT_HAVE_DIST
#include "dist/partition.h"
#endif

namespace simit::tools {

#ifdef SIMIT_HAVE_DIST
namespace {

template <size_t N>
runtime::ElementList list_of(const std::vector<std::array<int, N>>& elements) {
  static_assert(sizeof(std::array<int, N>) == N * sizeof(int32_t), "packed vertex indices");
  return {std::span<const int32_t>(reinterpret_cast<const int32_t*>(elements.data()),
                                   elements.size() * N),
          static_cast<int>(N)};
}

}  // namespace

int run_partition(const PartitionOptions& options, std::ostream& out, std::ostream& err) {
  try {
    const runtime::Mesh mesh = runtime::read_mesh(options.mesh);
    std::vector<runtime::ElementList> lists;
    if (!mesh.tets.empty()) lists.push_back(list_of(mesh.tets));
    if (!mesh.triangles.empty()) lists.push_back(list_of(mesh.triangles));
    if (!mesh.edges.empty()) lists.push_back(list_of(mesh.edges));
    const auto vertices = static_cast<int32_t>(mesh.points.size());
    // The scene's renumbering first: the chunks the parts own are runs of its numbers.
    const std::vector<int32_t> order =
        options.reorder == "off" ? std::vector<int32_t>()
                                 : runtime::locality_order(mesh, options.reorder == "hilbert");
    std::vector<std::vector<int32_t>> renumbered;
    renumbered.reserve(lists.size());
    if (!order.empty()) {
      const std::vector<int32_t> position = runtime::invert_permutation(order);
      for (runtime::ElementList& list : lists) {
        std::vector<int32_t>& to = renumbered.emplace_back();
        to.reserve(list.indices.size());
        for (int32_t v : list.indices) to.push_back(position[static_cast<size_t>(v)]);
        list.indices = to;
      }
    }
    const runtime::VertexGraph graph = runtime::vertex_graph(vertices, lists);
    char line[256];
    std::snprintf(line, sizeof line, "%s: %d vertices, %zu tets, %zu triangles, %zu edges\n",
                  options.mesh.c_str(), vertices, mesh.tets.size(), mesh.triangles.size(),
                  mesh.edges.size());
    out << line;
    const char* header =
        options.csv ? "parts,cut_edges,cut_percent,vertex_imbalance,element_imbalance,ghosts,"
                      "most_ghosts,most_neighbours,ms\n"
                    : "parts  cut edges  cut %  vertex imb.  element imb.    ghosts  most ghosts  "
                      "most neighbours       ms\n";
    out << header;
    for (int parts : options.parts) {
      if (parts > vertices)
        throw dist::PartitionError("cannot cut " + std::to_string(vertices) + " vertices into " +
                                   std::to_string(parts) + " parts: each part needs a vertex");
      const auto start = std::chrono::steady_clock::now();
      const std::vector<int32_t> owner = dist::partition_in_chunks(
          vertices, lists, parts, static_cast<int32_t>(runtime::kSumChunk));
      const double ms =
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
              .count();
      const dist::PartitionStats s = dist::partition_stats(graph, lists, owner, parts);
      const double cut = s.graph_edges ? 100.0 * static_cast<double>(s.cut_edges) /
                                             static_cast<double>(s.graph_edges)
                                       : 0.0;
      std::snprintf(
          line, sizeof line,
          options.csv ? "%d,%lld,%.3f,%.3f,%.3f,%lld,%lld,%lld,%.1f\n"
                      : "%5d  %9lld  %5.2f  %11.3f  %12.3f  %8lld  %11lld  %15lld  %7.1f\n",
          parts, static_cast<long long>(s.cut_edges), cut, s.vertex_imbalance(),
          s.element_imbalance(), static_cast<long long>(s.total_ghosts()),
          static_cast<long long>(s.most_ghosts()), static_cast<long long>(s.most_neighbours()), ms);
      out << line;
    }
    return 0;
  } catch (const runtime::MeshError& e) {
    err << "simit partition: " << e.what() << "\n";
  } catch (const dist::PartitionError& e) {
    err << "simit partition: " << options.mesh << ": " << e.what() << "\n";
  }
  return 1;
}
#else
int run_partition(const PartitionOptions&, std::ostream&, std::ostream& err) {
  err << "simit partition: this build has no partitioner: METIS was not found when it was "
         "configured (Debian's libmetis-dev; scripts/install_deps.sh installs it)\n";
  return 1;
}
#endif

}  // namespace simit::tools
