// The distributed system matrix, two ways: the project's own block CSR over each rank's
// overlapping part (dist/overlap.h: owned rows assembled completely on their rank from every tet
// touching them, ghost tets computed on each rank holding them) against PETSc's MATMPIBAIJ (block
// size 3, each tet assembled once by its owner, other ranks' rows sent through PETSc's stash).
// Measures assembly (values only, the pattern reused), y = A x with its ghost exchange, the
// memory of each matrix, and whether the two agree bit for bit (bench/results/dist_matrix.md).
//
//   mpirun -np K --bind-to core ./dist_matrix_bench [MESH.ele] [--repeats N] [--subset]
//
// --subset tells PETSc that every assembly sends to the same rows (MAT_SUBSET_OFF_PROC_ENTRIES).
#define OMPI_SKIP_MPICXX 1
#include <malloc.h>
#include <mpi.h>
#include <petscmat.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <numeric>
#include <stdexcept>
#include <string>
#include <tuple>
#include <vector>

#include "dist/mpi/comm.h"
#include "dist/overlap.h"
#include "dist/partition.h"
#include "runtime/mesh/mesh_reader.h"
#include "runtime/mesh/reorder.h"
#include "runtime/system_matrix.h"
#include "runtime/system_ops.h"

namespace {

using namespace simit;

#ifndef SIMIT_SOURCE_DIR
#define SIMIT_SOURCE_DIR "."
#endif
using ElementMatrix = std::array<double, 144>;  // 12 x 12, row-major: 4 x 4 blocks of 3 x 3

void petsc_check(PetscErrorCode code, const char* what) {
  if (code)
    throw std::runtime_error(std::string(what) + " failed: PETSc error " + std::to_string(code));
}

// The mesh as a scene holds it: vertices in reverse Cuthill-McKee order, tets renumbered and
// sorted by their smallest new vertex (scene/mesh_binding.cpp), so that the partition's
// chunks and the rows' column order are those of a distributed run.
runtime::Mesh read_renumbered(const std::string& path) {
  runtime::Mesh mesh = runtime::read_mesh(path);
  if (mesh.tets.empty()) throw std::runtime_error(path + ": no tets");
  const auto n = static_cast<int32_t>(mesh.points.size());
  const runtime::ElementList list{{mesh.tets.front().data(), mesh.tets.size() * 4}, 4};
  const std::vector<int32_t> order =
      runtime::reverse_cuthill_mckee(runtime::vertex_graph(n, {&list, 1}));
  const std::vector<int32_t> position = runtime::invert_permutation(order);
  const std::vector<runtime::Point> points = mesh.points;
  for (int32_t i = 0; i < n; ++i) mesh.points[i] = points[order[i]];
  const std::vector<int32_t> tets =
      runtime::renumber_elements(list, runtime::element_order(list, position), position);
  std::memcpy(mesh.tets.data(), tets.data(), tets.size() * sizeof(int32_t));
  return mesh;
}

// A linear tet's elasticity stiffness (Lame 1.0 and 0.5): dense, deterministic, and about the
// arithmetic of a FEM example's element function, so that computing a ghost tet twice costs
// what it would in a simulation.
void element_matrix(const std::array<const runtime::Point*, 4>& x, ElementMatrix& ke) {
  using V = std::array<double, 3>;
  auto cross = [](const V& u, const V& v) -> V {
    return {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
  };
  auto dot = [](const V& u, const V& v) { return u[0] * v[0] + u[1] * v[1] + u[2] * v[2]; };
  V e[3];  // the edges from vertex 0
  for (size_t k = 0; k < 3; ++k)
    for (size_t c = 0; c < 3; ++c) e[k][c] = (*x[k + 1])[c] - (*x[0])[c];
  // The barycentric gradients: the rows of the inverse of [e0 e1 e2], and minus their sum.
  V g[4] = {{}, cross(e[1], e[2]), cross(e[2], e[0]), cross(e[0], e[1])};
  const double det = dot(e[0], g[1]), volume = std::fabs(det) / 6.0, lambda = 1.0, mu = 0.5;
  for (size_t k = 1; k < 4; ++k)
    for (size_t c = 0; c < 3; ++c) g[k][c] /= det;
  for (size_t c = 0; c < 3; ++c) g[0][c] = -(g[1][c] + g[2][c] + g[3][c]);
  for (size_t a = 0; a < 4; ++a)
    for (size_t b = 0; b < 4; ++b)
      for (size_t r = 0; r < 3; ++r)
        for (size_t c = 0; c < 3; ++c)
          ke[(3 * a + r) * 12 + 3 * b + c] =
              volume * (lambda * g[a][r] * g[b][c] + mu * g[b][r] * g[a][c] +
                        (r == c ? mu * dot(g[a], g[b]) : 0.0));
}

// Bytes the heap holds now (small blocks and mmapped ones): a matrix's footprint as the
// difference across its construction, PETSc's included (its MatInfo no longer counts memory).
double heap_bytes() {
  const struct mallinfo2 m = mallinfo2();
  return static_cast<double>(m.uordblks + m.hblkhd);
}

double over_ranks(double v, MPI_Op op) {
  MPI_Allreduce(MPI_IN_PLACE, &v, 1, MPI_DOUBLE, op, MPI_COMM_WORLD);
  return v;
}

double median(std::vector<double> v) {  // the upper middle one of an even count
  std::nth_element(v.begin(), v.begin() + static_cast<ptrdiff_t>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

// A step's time (ms), split into the time of its exchange between ranks (which the step returns,
// waiting for slower ranks included) and the rest, its local work: each the median over
// repetitions of the slowest rank's, since a step is as slow as its slowest rank and the median
// keeps a descheduled repetition on a shared machine from moving it much.
struct Timing {
  double whole = 0, local = 0, exchange = 0;
};
template <class F>
Timing median_of_slowest(int repeats, F&& step) {
  for (int w = 0; w < 3; ++w) step();  // warm-ups: caches, PETSc's first messages
  std::vector<double> whole, local, exchange;
  for (int r = 0; r < repeats; ++r) {
    MPI_Barrier(MPI_COMM_WORLD);
    const double start = MPI_Wtime();
    const double part = step(), mine = (MPI_Wtime() - start) * 1e3;
    whole.push_back(over_ranks(mine, MPI_MAX));
    local.push_back(over_ranks(mine - part, MPI_MAX));
    exchange.push_back(over_ranks(part, MPI_MAX));
  }
  return {median(whole), median(local), median(exchange)};
}

// How far two results are apart: entries that differ in any bit, and the largest difference
// relative to the larger magnitude.
struct Agreement {
  double differing = 0, max_relative = 0;
  void add(double a, double b) {
    if (std::memcmp(&a, &b, sizeof a) == 0) return;
    ++differing;
    max_relative = std::max(max_relative, std::fabs(a - b) / std::max(std::fabs(a), std::fabs(b)));
  }
  void reduce() {
    differing = over_ranks(differing, MPI_SUM);
    max_relative = over_ranks(max_relative, MPI_MAX);
  }
};

// The project's block CSR over a rank's local vertices: owned rows only (its owner's refresh
// would overwrite a ghost row), columns ascending in local (= whole mesh) order, and where each
// local tet's 16 blocks go (-1 in a ghost row), built once like a scene's assembly index.
struct OwnMatrix {
  runtime::SystemMatrix a;
  std::vector<int32_t> position;
};

OwnMatrix own_matrix(int32_t local, const std::vector<int32_t>& conn,
                     const std::vector<uint8_t>& mine) {
  const size_t tets = conn.size() / 4;
  std::vector<std::vector<int32_t>> row_cols(local);
  for (size_t e = 0; e < 4 * tets; ++e)
    if (mine[conn[e]])
      row_cols[conn[e]].insert(row_cols[conn[e]].end(), &conn[e / 4 * 4], &conn[e / 4 * 4 + 4]);
  std::vector<int32_t> row_ptr{0}, col_idx;
  for (std::vector<int32_t>& cols : row_cols) {
    std::sort(cols.begin(), cols.end());
    col_idx.insert(col_idx.end(), cols.begin(), std::unique(cols.begin(), cols.end()));
    row_ptr.push_back(static_cast<int32_t>(col_idx.size()));
    std::vector<int32_t>().swap(cols);
  }
  OwnMatrix m{{}, std::vector<int32_t>(16 * tets, -1)};
  for (size_t t = 0; t < tets; ++t)
    for (size_t a = 0; a < 4; ++a) {
      const auto r = static_cast<size_t>(conn[4 * t + a]);
      if (!mine[r]) continue;
      const auto begin = col_idx.begin() + row_ptr[r], end = col_idx.begin() + row_ptr[r + 1];
      for (size_t b = 0; b < 4; ++b)
        m.position[16 * t + 4 * a + b] =
            static_cast<int32_t>(std::lower_bound(begin, end, conn[4 * t + b]) - col_idx.begin());
    }
  m.a = runtime::SystemMatrix(
      runtime::MatrixPattern::from_csr(local, local, std::move(row_ptr), std::move(col_idx)), 3, 3);
  return m;
}

// PETSc's matrix: owned rows numbered rank after rank (`number`: per local vertex, a ghost's
// from its owner), preallocated exactly from the own pattern, which has the same blocks.
Mat petsc_matrix(const runtime::MatrixPattern& own, const dist::SetPart& part,
                 const std::vector<uint8_t>& mine, bool subset) {
  std::vector<PetscInt> d_nnz, o_nnz;
  for (int32_t r : part.owned) {
    d_nnz.push_back(0), o_nnz.push_back(0);
    for (int32_t k = own.row_ptr()[r]; k < own.row_ptr()[r + 1]; ++k)
      ++(mine[own.col_idx()[k]] ? d_nnz : o_nnz).back();
  }
  Mat m = nullptr;
  const auto rows = static_cast<PetscInt>(3 * part.owned.size());
  petsc_check(MatCreate(PETSC_COMM_WORLD, &m), "MatCreate");
  petsc_check(MatSetSizes(m, rows, rows, PETSC_DETERMINE, PETSC_DETERMINE), "MatSetSizes");
  // MPIBAIJ even on one rank (MATBAIJ would be SeqBAIJ there), so that every K measures one code.
  petsc_check(MatSetType(m, MATMPIBAIJ), "MatSetType");
  petsc_check(MatMPIBAIJSetPreallocation(m, 3, 0, d_nnz.data(), 0, o_nnz.data()), "preallocate");
  petsc_check(MatSetOption(m, MAT_NEW_NONZERO_ALLOCATION_ERR, PETSC_TRUE), "MatSetOption");
  if (subset) petsc_check(MatSetOption(m, MAT_SUBSET_OFF_PROC_ENTRIES, PETSC_TRUE), "MatSetOption");
  return m;
}

}  // namespace

int main(int argc, char** argv) {
  dist::mpi::Session session(&argc, &argv);
  std::string path = SIMIT_SOURCE_DIR "/examples/data/dragon160k.ele";
  int repeats = 31;
  bool subset = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--subset") subset = true;
    if (a == "--repeats" && i + 1 < argc) repeats = std::max(1, std::atoi(argv[++i]));
    if (a[0] != '-') path = a;
  }
  // PETSc inside the session's MPI, which it then leaves to the session to finalize; options
  // from PETSC_OPTIONS only (-log_view, say), not from this command line.
  petsc_check(PetscInitialize(nullptr, nullptr, nullptr, nullptr), "PetscInitialize");
  const int ranks = session.size(), rank = session.rank();
  try {
    // Every rank reads, renumbers and partitions alike: the same parts without a message.
    const runtime::Mesh mesh = read_renumbered(path);
    const auto vertices = static_cast<int32_t>(mesh.points.size());
    const runtime::ElementList list{{mesh.tets.front().data(), 4 * mesh.tets.size()}, 4};
    const std::vector<int32_t> owner = dist::partition_in_chunks(vertices, {&list, 1}, ranks, 256);
    const dist::RankLayout layout = dist::overlap_layout(owner, {&list, 1}, ranks, rank);
    const dist::SetPart& part = layout.vertices;
    const std::vector<int32_t>& conn = layout.local_connectivity[0];
    const std::vector<int32_t>& owned_tets = layout.edge_sets[0].owned;
    const auto local = static_cast<int32_t>(part.global.size());
    const size_t local_tets = conn.size() / 4;
    std::vector<uint8_t> mine(local, 0);
    for (int32_t v : part.owned) mine[v] = 1;
    auto vertex = [&](size_t t, size_t a) { return conn[4 * t + a]; };
    ElementMatrix ke;
    auto compute = [&](size_t t) {
      std::array<const runtime::Point*, 4> x;
      for (size_t a = 0; a < 4; ++a) x[a] = &mesh.points[part.global[vertex(t, a)]];
      element_matrix(x, ke);
    };

    const double heap_before_own = heap_bytes();
    OwnMatrix own = own_matrix(local, conn, mine);
    const double own_heap = over_ranks(heap_bytes() - heap_before_own, MPI_SUM);
    const double own_formula =
        over_ranks(static_cast<double>(own.a.value_bytes() + own.a.pattern().bytes() +
                                       4 * own.position.size()),
                   MPI_SUM);
    // Every local tet, ghost tets too: an owned row gets all its terms without a message.
    auto assemble_own = [&] {
      own.a.set_zero();
      for (size_t t = 0; t < local_tets; ++t) {
        compute(t);
        for (size_t a = 0; a < 4; ++a) {
          if (own.position[16 * t + 4 * a] < 0) continue;
          for (size_t b = 0; b < 4; ++b) {
            double* block = own.a.block(own.position[16 * t + 4 * a + b]);
            for (size_t r = 0; r < 3; ++r)
              for (size_t c = 0; c < 3; ++c) block[3 * r + c] += ke[(3 * a + r) * 12 + 3 * b + c];
          }
        }
      }
      return 0.0;
    };

    std::vector<int32_t> number(local, -1);
    auto next = static_cast<int32_t>(session.sum_below(static_cast<int64_t>(part.owned.size())));
    for (int32_t v : part.owned) number[v] = next++;
    session.refresh_ghosts(layout.vertex_plan, std::as_writable_bytes(std::span<int32_t>(number)),
                           sizeof(int32_t));
    const double heap_before_petsc = heap_bytes();
    Mat m = petsc_matrix(own.a.pattern(), part, mine, subset);
    // Owned tets only; their blocks in other ranks' rows go through PETSc's stash.
    auto assemble_petsc = [&] {
      petsc_check(MatZeroEntries(m), "MatZeroEntries");
      for (int32_t t : owned_tets) {
        compute(t);
        PetscInt idx[4];
        for (size_t a = 0; a < 4; ++a) idx[a] = number[vertex(t, a)];
        petsc_check(MatSetValuesBlocked(m, 4, idx, 4, idx, ke.data(), ADD_VALUES),
                    "MatSetValuesBlocked");
      }
      const double start = MPI_Wtime();
      petsc_check(MatAssemblyBegin(m, MAT_FINAL_ASSEMBLY), "MatAssemblyBegin");
      petsc_check(MatAssemblyEnd(m, MAT_FINAL_ASSEMBLY), "MatAssemblyEnd");
      return (MPI_Wtime() - start) * 1e3;
    };
    assemble_petsc();  // the first assembly builds PETSc's off-diagonal column map and scatter
    const double petsc_heap = over_ranks(heap_bytes() - heap_before_petsc, MPI_SUM);
    Vec px = nullptr, py = nullptr;
    petsc_check(MatCreateVecs(m, &px, &py), "MatCreateVecs");
    MatInfo info;
    petsc_check(MatGetInfo(m, MAT_GLOBAL_SUM, &info), "MatGetInfo");
    size_t stash_blocks = 0;  // what owned tets add into other ranks' rows per assembly
    for (int32_t t : owned_tets)
      for (size_t a = 0; a < 4; ++a) stash_blocks += mine[vertex(t, a)] ? 0 : 4;

    // x: deterministic from the whole mesh's vertex numbers, the same on every rank.
    std::vector<double> x(3 * static_cast<size_t>(local)), y(x.size());
    for (size_t e = 0; e < x.size(); ++e)
      x[e] = std::sin(0.001 * part.global[e / 3] + (e % 3)) + 0.25 * (e % 3);
    PetscScalar* p = nullptr;
    petsc_check(VecGetArray(px, &p), "VecGetArray");
    for (size_t n = 0; n < part.owned.size(); ++n)
      std::memcpy(p + 3 * n, &x[3 * part.owned[n]], 3 * sizeof(double));
    petsc_check(VecRestoreArray(px, &p), "VecRestoreArray");
    auto multiply_own = [&] {
      runtime::multiply(own.a, x, y);
      const double start = MPI_Wtime();
      session.refresh_ghosts(layout.vertex_plan, std::as_writable_bytes(std::span<double>(y)),
                             3 * sizeof(double));
      return (MPI_Wtime() - start) * 1e3;
    };
    // MatMult scatters the ghost entries of x itself, overlapped with the diagonal part's product.
    auto multiply_petsc = [&] { return petsc_check(MatMult(m, px, py), "MatMult"), 0.0; };
    // The element function alone, over the tets each way computes: the overlap's extra work.
    double sink = 0;
    std::vector<int32_t> local_list(local_tets);
    std::iota(local_list.begin(), local_list.end(), 0);
    auto kernel = [&](const std::vector<int32_t>& tets) {
      return [&, list = &tets] {
        for (int32_t t : *list) compute(t), sink += ke[0];
        return 0.0;
      };
    };

    const Timing own_assembly = median_of_slowest(repeats, assemble_own);
    const Timing petsc_assembly = median_of_slowest(repeats, assemble_petsc);
    const Timing own_product = median_of_slowest(repeats, multiply_own);
    const Timing petsc_product = median_of_slowest(repeats, multiply_petsc);
    const Timing kernel_local = median_of_slowest(repeats, kernel(local_list));
    const Timing kernel_owned = median_of_slowest(repeats, kernel(owned_tets));

    // The matrices entry by entry (the same terms, perhaps summed in other orders), then the
    // products' owned entries.
    Agreement matrix, product;
    const runtime::MatrixPattern& pattern = own.a.pattern();
    for (int32_t r : part.owned)
      for (int32_t k = pattern.row_ptr()[r]; k < pattern.row_ptr()[r + 1]; ++k) {
        const PetscInt row = 3 * number[r], ri[3] = {row, row + 1, row + 2};
        const PetscInt c = 3 * number[pattern.col_idx()[k]];
        const PetscInt ci[3] = {c, c + 1, c + 2};
        double values[9];
        petsc_check(MatGetValues(m, 3, ri, 3, ci, values), "MatGetValues");
        for (int e = 0; e < 9; ++e) matrix.add(own.a.block(k)[e], values[e]);
      }
    const PetscScalar* q = nullptr;
    petsc_check(VecGetArrayRead(py, &q), "VecGetArrayRead");
    for (size_t n = 0; n < part.owned.size(); ++n)
      for (size_t i = 0; i < 3; ++i) product.add(y[3 * part.owned[n] + i], q[3 * n + i]);
    petsc_check(VecRestoreArrayRead(py, &q), "VecRestoreArrayRead");
    matrix.reduce(), product.reduce();
    auto most = [](size_t v) { return over_ranks(static_cast<double>(v), MPI_MAX); };
    const double most_local = most(local_tets), most_owned = most(owned_tets.size());
    const double most_ghosts = most(part.ghosts.size()), most_stash = most(stash_blocks);
    const double ghost_tets = over_ranks(1.0 * local_tets, MPI_SUM) - mesh.tets.size();
    const double blocks = over_ranks(static_cast<double>(pattern.nnz()), MPI_SUM);
    if (rank == 0) {
      std::printf("%s: %d vertices, %zu tets; K = %d%s; median of %d (slowest rank)\n",
                  path.c_str(), vertices, mesh.tets.size(), ranks,
                  subset ? ", PETSc told MAT_SUBSET_OFF_PROC_ENTRIES" : "", repeats);
      std::printf(
          "per rank at most: %.0f local tets, %.0f owned tets, %.0f ghost vertices, %.0f blocks "
          "into the stash; ghost tets (all ranks): %.0f\n",
          most_local, most_owned, most_ghosts, most_stash, ghost_tets);
      auto row = [](const char* what, double own_value, double petsc_value = NAN) {
        if (std::isnan(petsc_value))
          return void(std::printf("%-40s %10.3f %10s\n", what, own_value, "-"));
        std::printf("%-40s %10.3f %10.3f\n", what, own_value, petsc_value);
      };
      std::printf("%-40s %10s %10s\n", "", "own", "PETSc");
      row("assembly ms", own_assembly.whole, petsc_assembly.whole);
      row("  element matrices alone ms", kernel_local.whole, kernel_owned.whole);
      row("  local work, slowest rank ms", own_assembly.local, petsc_assembly.local);
      row("  exchange, slowest rank ms", own_assembly.exchange, petsc_assembly.exchange);
      row("SpMV with ghost exchange ms", own_product.whole, petsc_product.whole);
      row("  refresh_ghosts, slowest rank ms", own_product.exchange);
      row("heap MB (all ranks)", own_heap / 1e6, petsc_heap / 1e6);
      row("  own: values + index + table MB", own_formula / 1e6);
      std::printf("%-40s %10.0f %10.0f\n", "blocks (all ranks)", blocks, info.nz_used / 9);
      for (auto [what, agreement, of] : {std::tuple("matrix", matrix, blocks * 9),
                                         std::tuple("product", product, 3.0 * vertices)})
        std::printf("%s entries differing: %.0f of %.0f (max relative %.3g)\n", what,
                    agreement.differing, of, agreement.max_relative);
    }
    if (sink == 42.0) std::printf(" ");  // keeps the element-function timing loops alive
    VecDestroy(&px), VecDestroy(&py), MatDestroy(&m);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "rank %d: %s\n", rank, e.what());
    session.abort(1);
  }
  PetscFinalize();
  return 0;
}
