// Measures the sparsity pattern of a tetrahedral mesh: build time, blocks, and the bytes of
// a 3x3-blocked vertex x vertex matrix assembled through the tets versus its shared pattern.
// Usage: pattern_memory mesh.ele   (TetGen .ele: a header line, then "index v0 v1 v2 v3")
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

#include "runtime/set.h"
#include "runtime/system_matrix.h"

using namespace simit::runtime;

namespace {

// The tet corner indices, 4 per tet, shifted so that the smallest index is 0.
std::vector<int32_t> read_ele(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot read " + path);
  long count = 0, corners = 0, attributes = 0;
  in >> count >> corners >> attributes;
  if (corners != 4) throw std::runtime_error(path + ": expected 4 corners per element");
  std::vector<int32_t> tets;
  tets.reserve(static_cast<size_t>(count) * 4);
  for (long t = 0; t < count; ++t) {
    long index = 0;
    int32_t v[4];
    double attribute = 0;
    if (!(in >> index >> v[0] >> v[1] >> v[2] >> v[3]))
      throw std::runtime_error(path + ": truncated at element " + std::to_string(t));
    for (long a = 0; a < attributes; ++a) in >> attribute;
    tets.insert(tets.end(), v, v + 4);
  }
  const int32_t base = tets.empty() ? 0 : *std::min_element(tets.begin(), tets.end());
  for (int32_t& v : tets) v -= base;
  return tets;
}

// Wall and CPU time: on a shared machine the CPU time is the steadier figure.
struct Stopwatch {
  std::chrono::steady_clock::time_point wall = std::chrono::steady_clock::now();
  std::clock_t cpu = std::clock();
  double wall_ms() const {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - wall)
        .count();
  }
  double cpu_ms() const {
    return 1000.0 * static_cast<double>(std::clock() - cpu) / CLOCKS_PER_SEC;
  }
};

// Adds a constant to every block of every tet through the assembly index (no search).
void assemble_ones(SystemMatrix& m, const Set& tets) {
  m.set_zero();
  const AssemblyIndex& ix = m.pattern().assembly();
  const size_t pairs = ix.pairs();
  for (int e = 0; e < tets.size(); ++e) {
    const int32_t* at = ix.of(e);
    for (size_t k = 0; k < pairs; ++k) {
      double* blk = m.block(at[k]);
      for (int i = 0; i < 9; ++i) blk[i] += 1.0;
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::cerr << "usage: pattern_memory mesh.ele\n";
    return 2;
  }
  try {
    const std::vector<int32_t> corners = read_ele(argv[1]);
    const int32_t vertex_count =
        corners.empty() ? 0 : *std::max_element(corners.begin(), corners.end()) + 1;
    Set verts("verts");
    verts.add_many(vertex_count);
    Set tets("tets", {&verts, &verts, &verts, &verts});
    tets.add_edges(corners);

    PatternRegistry registry;
    const Stopwatch start;
    PatternPtr pattern = registry.assembled(tets, verts, verts);
    const double build_wall = start.wall_ms(), build_cpu = start.cpu_ms();
    SystemMatrix stiffness(registry.assembled(tets, verts, verts), 3, 3);
    SystemMatrix damping(registry.assembled(tets, verts, verts), 3, 3);
    const Stopwatch assembly;
    assemble_ones(stiffness, tets);
    const double assembly_wall = assembly.wall_ms(), assembly_cpu = assembly.cpu_ms();

    const size_t rows = static_cast<size_t>(pattern->rows());
    const size_t nnz = static_cast<size_t>(pattern->nnz());
    const size_t budget = nnz * 9 * sizeof(double) + (nnz + rows) * sizeof(int32_t);
    const SystemMatrix* both[] = {&stiffness, &damping};
    std::printf("tets %d, vertices %d\n", tets.size(), verts.size());
    std::printf(
        "pattern build          %10.1f ms wall, %.1f ms CPU (patterns built: %d for 2 "
        "matrices)\n",
        build_wall, build_cpu, registry.builds());
    std::printf("in-place assembly pass %10.1f ms wall, %.1f ms CPU (16 blocks per tet)\n",
                assembly_wall, assembly_cpu);
    std::printf("nnz blocks             %10zu (%.2f per row)\n", nnz,
                static_cast<double>(nnz) / static_cast<double>(rows));
    std::printf("bytes per matrix       %10zu (values only)\n", stiffness.value_bytes());
    std::printf("bytes of CSR index     %10zu (row pointers + column indices, shared)\n",
                pattern->index_bytes());
    std::printf("bytes of assembly index%10zu (16 positions per tet, shared)\n",
                pattern->assembly_bytes());
    std::printf("values + CSR index     %10zu vs budget values + 1 int/block + 1 int/row %zu\n",
                stiffness.value_bytes() + pattern->index_bytes(), budget);
    std::printf("two matrices in all    %10zu (pattern counted once)\n", memory_bytes(both));
    std::printf("same pattern object    %10s\n",
                &stiffness.pattern() == &damping.pattern() ? "yes" : "no");
  } catch (const std::exception& e) {
    std::cerr << "pattern_memory: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
