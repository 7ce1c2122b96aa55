// Hand-written Eigen version of examples/fem/fem.sim: Neo-Hookean tets, linearly-implicit
// backward Euler, unpreconditioned CG with the same stopping rule. The matrix is a block-CSR
// of 3x3 blocks holding only the blocks fem.sim writes: the diagonal, and the pairs of
// vertices that share a tet when neither is pinned.
// --threads N runs the frame on N OpenMP threads: the tets partitioned (each thread adding
// into its own copy of the forces and blocks), the vertex passes and CG by rows
// (baseline_common.h).
// Usage: fem_baseline [--check] [--csv FILE] [--cg-tol T] [--cg-max N] [--threads N] [--sim-form]
//                     [MESH] [FRAMES]
// Final positions are written only with --csv FILE; --help lists every option.
#include <cmath>
#include <cstdio>

#include "baseline_common.h"
#include "runtime/mesh/mesh.h"
#include "runtime/mesh/mesh_reader.h"

using namespace simit::baseline;

namespace {

constexpr double E = 5e3, nu = 0.45, density = 1000.0, h = 0.005;
const double default_cg_tol = 1e-12;  // --cg-tol overrides
const int default_cg_max = 100;       // --cg-max overrides
const Vec3 gravity(0.0, -10.0, 0.0);

struct TetRest {
  Mat3 B;                 // Dm^-1
  double W;               // rest volume
  std::array<Vec3, 4> g;  // shape-function gradients; g[3] = -(g0 + g1 + g2)
};

Mat3 edge_matrix(const Vec3s& x, const simit::runtime::Tet& t) {
  Mat3 d;
  for (int j = 0; j < 3; ++j) d.col(j) = x[t[j]] - x[t[3]];
  return d;
}

// A += -h^2 K for one tet (blocks: A's, or a thread's copy of them), K's block (i, j) in closed
// form: with a_i = F^-T g_i, K_ij = -W (mu (g_i'g_j) I + c a_j a_i' + lambda a_i a_j'), c = mu -
// lambda log J. It is fem.sim's tet_stiffness: dP multiplied out (dF = e_d g_j' makes each term
// rank one).
void add_stiffness(Mat3* blocks, const std::array<int, 16>& k, const TetRest& r, const Mat3& FinvT,
                   double c, double mu, double lambda) {
  std::array<Vec3, 4> af;
  for (int i = 0; i < 4; ++i) af[i] = FinvT * r.g[i];
  const double s = h * h * r.W;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) {
      if (k[4 * i + j] < 0) continue;
      Mat3& block = blocks[k[4 * i + j]];
      block.noalias() += (s * c) * af[j] * af[i].transpose();
      block.noalias() += (s * lambda) * af[i] * af[j].transpose();
      block.diagonal().array() += s * mu * r.g[i].dot(r.g[j]);
    }
}

// The same blocks column by column, as fem.sim wrote them before it took the closed form:
// K's column (j, d) is -W dP g_i with
// dP = mu dF + c F^-T dF' F^-T + lambda tr(F^-1 dF) F^-T, dF = e_d g_j' (--sim-form).
void add_stiffness_as_sim(Mat3* blocks, const std::array<int, 16>& k, const TetRest& r,
                          const Mat3& Finv, double c, double mu, double lambda) {
  const Mat3 FinvT = Finv.transpose();
  for (int j = 0; j < 4; ++j) {
    if (k[5 * j] < 0) continue;  // corner j pinned: fem.sim writes none of its column
    for (int d = 0; d < 3; ++d) {
      const Mat3 dF = Vec3::Unit(d) * r.g[j].transpose();
      const double tr = r.g[j].dot(Finv.col(d));
      const Mat3 dP = mu * dF + c * (FinvT * dF.transpose() * FinvT) + (lambda * tr) * FinvT;
      for (int i = 0; i < 4; ++i)
        if (k[4 * i + j] >= 0) blocks[k[4 * i + j]].col(d) += (h * h * r.W) * (dP * r.g[i]);
    }
  }
}

// fem.sim's energy statistic: Neo-Hookean W psi(F) per tet with
// psi = mu/2 (tr(F'F) - 3) - mu log J + lambda/2 (log J)^2, kinetic and gravitational per
// vertex. Summed directly: fem.sim spreads each tet's term over its corners only because its
// statistic is one vector over the vertices.
double total_energy(const simit::runtime::Mesh& mesh, const std::vector<TetRest>& rest,
                    const Vec3s& x, const Vec3s& v, const std::vector<double>& m, double mu,
                    double lambda) {
  const double elastic = parallel_sum(static_cast<int>(rest.size()), 0.0, [&](int e) {
    const Mat3 F = edge_matrix(x, mesh.tets[e]) * rest[e].B;
    const double logJ = std::log(F.determinant());
    const double psi = 0.5 * mu * (F.squaredNorm() - 3.0) - mu * logJ + 0.5 * lambda * logJ * logJ;
    return rest[e].W * psi;
  });
  return parallel_sum(static_cast<int>(x.size()), elastic, [&](int i) {
    return 0.5 * m[i] * v[i].squaredNorm() - m[i] * gravity.dot(x[i]);
  });
}

}  // namespace

int main(int argc, char** argv) {
  const Options options = parse_options(argc, argv, "examples/data/bunny.1.node", true);
  const double cg_tol = options.cg_tol >= 0 ? options.cg_tol : default_cg_tol;
  const int cg_max = options.cg_max >= 0 ? options.cg_max : default_cg_max;
  const simit::runtime::Mesh mesh = simit::runtime::read_mesh(options.input);
  const int n = static_cast<int>(mesh.points.size());
  const int nt = static_cast<int>(mesh.tets.size());

  Vec3s x(n);
  Vec3s v(n, Vec3(0.1, 0.0, 0.1));
  std::vector<char> pinned(n);
  for (int i = 0; i < n; ++i) {
    x[i] = Vec3(mesh.points[i][0], mesh.points[i][1], mesh.points[i][2]);
    pinned[i] = x[i].y() < 1e-4;
    if (pinned[i]) v[i].setZero();
  }

  // Precomputation: rest shape, lumped masses, the pattern and each tet's block indices.
  Stopwatch setup;
  std::vector<TetRest> rest(nt);
  std::vector<double> m(n, 0.0);
  BlockPatternBuilder builder(n);
  for (int e = 0; e < nt; ++e) {
    const auto& t = mesh.tets[e];
    const Mat3 dm = edge_matrix(x, t);
    TetRest& r = rest[e];
    r.B = dm.inverse();
    r.W = -dm.determinant() / 6.0;
    for (int j = 0; j < 3; ++j) r.g[j] = r.B.row(j).transpose();
    r.g[3] = -(r.B.row(0) + r.B.row(1) + r.B.row(2)).transpose();
    for (int j = 0; j < 4; ++j) m[t[j]] += 0.25 * density * r.W;
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j)
        if (!pinned[t[i]] && !pinned[t[j]]) builder.add(t[i], t[j]);
  }
  BlockCsr a(std::move(builder));
  // Block (t[i], t[j]) of tet e is blocks[e][4 i + j]; -1 where a corner is pinned.
  std::vector<std::array<int, 16>> blocks(nt);
  for (int e = 0; e < nt; ++e)
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j) {
        const auto& t = mesh.tets[e];
        blocks[e][4 * i + j] = pinned[t[i]] || pinned[t[j]] ? -1 : a.find(t[i], t[j]);
      }
  // Tets sharing a vertex add into the same force and blocks: each thread into its own copy.
  PartitionedLoop tet_loop(n, static_cast<int>(a.block_count()));
  std::printf("%s: %d vertices, %d tets, %zu blocks, %.0f bytes per CG iteration, set-up %.3f ms",
              options.input.c_str(), n, nt, a.block_count(), a.cg_bytes_per_iteration(),
              setup.lap_ms());
  if (options.threads > 1) std::printf(", %d threads", options.threads);
  std::printf("\n");

  // Compile-time constants, as the compiler folded them into the tet loop before its body
  // became a lambda: captured by reference they would not fold, and the compiled arithmetic
  // (FMA contraction is on for the baselines) would move the last bits of one thread's results.
  constexpr double mu = 0.5 * E / nu;  // sic: the original host's formula
  constexpr double lambda = E * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
  Vec3s f(n), b(n);
  ConjugateGradient cg(n);
  FrameLog log{"assembly", "solve", {}};
  for (int frame = 1; frame <= options.frames; ++frame) {
    Stopwatch clock;
    a.set_zero();
    parallel_for(n, [&](int i) {
      f[i].setZero();
      a.block(a.diagonal(i)) = m[i] * Mat3::Identity();
    });
    tet_loop.run(nt, f.data(), a.block_data(), [&](int e, Vec3* force, Mat3* block) {
      const auto& t = mesh.tets[e];
      const TetRest& r = rest[e];
      const Mat3 F = edge_matrix(x, t) * r.B;
      const Mat3 Finv = F.inverse();
      const Mat3 FinvT = Finv.transpose();
      const double logJ = std::log(F.determinant());
      const Mat3 P = mu * (F - FinvT) + lambda * logJ * FinvT;
      for (int j = 0; j < 4; ++j) force[t[j]] += -r.W * (P * r.g[j]);
      const double c = mu - lambda * logJ;
      if (options.sim_form)
        add_stiffness_as_sim(block, blocks[e], r, Finv, c, mu, lambda);
      else
        add_stiffness(block, blocks[e], r, FinvT, c, mu, lambda);
    });
    parallel_for(n, [&](int i) {
      b[i] = pinned[i] ? Vec3::Zero() : Vec3(m[i] * v[i] + h * (f[i] + m[i] * gravity));
    });
    const double assembly_ms = clock.lap_ms();
    const CgResult result = cg.solve(a, b, v, cg_tol, cg_max);
    parallel_for(n, [&](int i) { x[i] += h * v[i]; });
    const double energy = total_energy(mesh, rest, x, v, m, mu, lambda);
    log.frame(frame, assembly_ms, clock.lap_ms(), energy, result);
  }
  log.summary();
  return finish(options, x) ? 0 : 1;
}
