// Hand-written Eigen version of examples/springs/springs.sim: implicit mass-spring system,
// linearized backward Euler, unpreconditioned CG with the same stopping rule. The matrix is a
// block-CSR of 3x3 blocks holding only the blocks springs.sim writes: the diagonal, and the
// pairs of points joined by a spring when neither is pinned.
// --threads N runs the frame on N OpenMP threads: the springs partitioned (each thread adding
// into its own copy of the forces and blocks), the point passes and CG by rows
// (baseline_common.h).
// Usage: springs_baseline [--check] [--csv FILE] [--cg-tol T] [--cg-max N] [--threads N] [MESH]
//                         [FRAMES]
// Final positions are written only with --csv FILE; --help lists every option.
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "baseline_common.h"
#include "runtime/mesh/mesh.h"
#include "runtime/mesh/mesh_reader.h"

using namespace simit::baseline;

namespace {

const double stiffness = 1000.0, spring_mass = 0.001, h = 0.01;
const double default_cg_tol = 1e-12;  // --cg-tol overrides
const int default_cg_max = 50;        // --cg-max overrides
const Vec3 gravity(0.0, -10.0, 0.0);

// springs.sim's energy statistic: k/2 (l - l0)^2 per spring, kinetic and gravitational per
// point. Summed directly: springs.sim splits each spring's term between its ends only because
// its statistic is one vector over the points.
double total_energy(const simit::runtime::Mesh& mesh, const std::vector<double>& l0, const Vec3s& x,
                    const Vec3s& v, const std::vector<double>& m) {
  const double elastic = parallel_sum(static_cast<int>(l0.size()), 0.0, [&](int s) {
    const double stretch = (x[mesh.edges[s][1]] - x[mesh.edges[s][0]]).norm() - l0[s];
    return 0.5 * stiffness * stretch * stretch;
  });
  return parallel_sum(static_cast<int>(x.size()), elastic, [&](int i) {
    return 0.5 * m[i] * v[i].squaredNorm() - m[i] * gravity.dot(x[i]);
  });
}

}  // namespace

int main(int argc, char** argv) {
  const Options options = parse_options(argc, argv, "examples/data/bunny.1.node");
  const double cg_tol = options.cg_tol >= 0 ? options.cg_tol : default_cg_tol;
  const int cg_max = options.cg_max >= 0 ? options.cg_max : default_cg_max;
  const simit::runtime::Mesh mesh = simit::runtime::read_mesh(options.input);
  const int n = static_cast<int>(mesh.points.size());
  const int ns = static_cast<int>(mesh.edges.size());
  if (ns == 0) {
    std::fprintf(stderr, "%s: no edges (the springs come from the .edge file)\n",
                 options.input.c_str());
    return 1;
  }

  // The mesh rescaled to [0, 1] on each axis separately; pinned where z < 0.1.
  Vec3 lo = Vec3::Constant(INFINITY), hi = Vec3::Constant(-INFINITY);
  for (const auto& p : mesh.points) {
    const Vec3 q(p[0], p[1], p[2]);
    lo = lo.cwiseMin(q);
    hi = hi.cwiseMax(q);
  }
  Vec3s x(n), v(n, Vec3::Zero());
  std::vector<char> pinned(n);
  for (int i = 0; i < n; ++i) {
    const Vec3 q(mesh.points[i][0], mesh.points[i][1], mesh.points[i][2]);
    x[i] = (q - lo).cwiseQuotient(hi - lo);
    pinned[i] = x[i].z() < 0.1;
  }

  // Precomputation: rest lengths, lumped masses, the pattern and each spring's block indices.
  Stopwatch setup;
  std::vector<double> l0(ns), m(n, 0.0);
  BlockPatternBuilder builder(n);
  for (int s = 0; s < ns; ++s) {
    const auto& e = mesh.edges[s];
    l0[s] = (x[e[1]] - x[e[0]]).norm();
    m[e[0]] += 0.5 * spring_mass;
    m[e[1]] += 0.5 * spring_mass;
    if (!pinned[e[0]] && !pinned[e[1]]) {
      builder.add(e[0], e[1]);
      builder.add(e[1], e[0]);
    }
  }
  BlockCsr a(std::move(builder));
  // Blocks (a, a), (c, c), (a, c), (c, a) of spring (a, c); -1 where springs.sim writes none.
  std::vector<std::array<int, 4>> blocks(ns);
  for (int s = 0; s < ns; ++s) {
    const int p = mesh.edges[s][0], q = mesh.edges[s][1];
    const bool coupled = !pinned[p] && !pinned[q];
    blocks[s] = {pinned[p] ? -1 : a.diagonal(p), pinned[q] ? -1 : a.diagonal(q),
                 coupled ? a.find(p, q) : -1, coupled ? a.find(q, p) : -1};
  }
  // Springs sharing a point add into the same force and blocks: each thread into its own copy.
  PartitionedLoop spring_loop(n, static_cast<int>(a.block_count()));
  std::printf("%s: %d points, %d springs, %zu blocks, %.0f bytes per CG iteration, set-up %.3f ms",
              options.input.c_str(), n, ns, a.block_count(), a.cg_bytes_per_iteration(),
              setup.lap_ms());
  if (options.threads > 1) std::printf(", %d threads", options.threads);
  std::printf("\n");

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
    spring_loop.run(ns, f.data(), a.block_data(), [&](int s, Vec3* force, Mat3* block) {
      const int p = mesh.edges[s][0], q = mesh.edges[s][1];
      const Vec3 d = x[q] - x[p];
      const double l = d.norm();
      const Vec3 t = stiffness * (l - l0[s]) / l * d;
      force[p] += t;
      force[q] -= t;
      // K = [-Ks Ks; Ks -Ks]; the transverse term is dropped under compression. Blocks
      // coupling to a pinned point are not written; a free end keeps its own block.
      const std::array<int, 4>& k = blocks[s];
      if (k[0] < 0 && k[1] < 0) return;
      const Vec3 u = d / l;
      const Mat3 uu = u * u.transpose();
      const Mat3 ks = stiffness * (uu + std::max(0.0, 1.0 - l0[s] / l) * (Mat3::Identity() - uu));
      if (k[0] >= 0) block[k[0]] += (h * h) * ks;
      if (k[1] >= 0) block[k[1]] += (h * h) * ks;
      if (k[2] < 0) return;
      block[k[2]] -= (h * h) * ks;
      block[k[3]] -= (h * h) * ks;
    });
    parallel_for(n, [&](int i) {
      b[i] = pinned[i] ? Vec3::Zero() : Vec3(m[i] * v[i] + h * (f[i] + m[i] * gravity));
    });
    const double assembly_ms = clock.lap_ms();
    const CgResult result = cg.solve(a, b, v, cg_tol, cg_max);
    parallel_for(n, [&](int i) { x[i] += h * v[i]; });
    const double energy = total_energy(mesh, l0, x, v, m);
    log.frame(frame, assembly_ms, clock.lap_ms(), energy, result);
  }
  log.summary();
  return finish(options, x) ? 0 : 1;
}
