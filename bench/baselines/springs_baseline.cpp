// Hand-written Eigen version of examples/springs/springs.sim: implicit mass-spring system,
// linearized backward Euler, unpreconditioned CG with the same stopping rule.
// Usage: springs_baseline [--check] [--csv FILE] [MESH] [FRAMES]
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
const int default_cg_max = 50;  // --cg-max overrides
const Vec3 gravity(0.0, -10.0, 0.0);

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
  std::vector<Vec3> x(n), v(n, Vec3::Zero());
  std::vector<char> pinned(n);
  for (int i = 0; i < n; ++i) {
    const Vec3 q(mesh.points[i][0], mesh.points[i][1], mesh.points[i][2]);
    x[i] = (q - lo).cwiseQuotient(hi - lo);
    pinned[i] = x[i].z() < 0.1;
  }

  Stopwatch setup;
  std::vector<double> l0(ns), m(n, 0.0);
  std::vector<int> ends;
  ends.reserve(2 * ns);
  for (int s = 0; s < ns; ++s) {
    const auto& e = mesh.edges[s];
    l0[s] = (x[e[1]] - x[e[0]]).norm();
    m[e[0]] += 0.5 * spring_mass;
    m[e[1]] += 0.5 * spring_mass;
    ends.push_back(e[0]);
    ends.push_back(e[1]);
  }
  BlockPattern pattern(n, ends, 2);
  std::vector<std::array<int, 4>> slots(ns);
  for (int s = 0; s < ns; ++s)
    for (int i = 0; i < 2; ++i)
      for (int j = 0; j < 2; ++j) slots[s][2 * i + j] = pattern.slot(ends[2 * s + i], ends[2 * s + j]);
  std::printf("%s: %d points, %d springs, %ld nonzeros, set-up %.3f ms\n",
              options.input.c_str(), n, ns, static_cast<long>(pattern.matrix().nonZeros()),
              setup.lap_ms());

  std::vector<Vec3> f(n);
  Eigen::VectorXd b(3 * n), vel(3 * n);
  FrameLog log{"assembly", "solve", {}};
  for (int frame = 1; frame <= options.frames; ++frame) {
    Stopwatch clock;
    pattern.set_zero();
    std::fill(f.begin(), f.end(), Vec3::Zero());
    for (int i = 0; i < n; ++i) pattern.add(i, pattern.diagonal_slot(i), m[i] * Mat3::Identity());
    for (int s = 0; s < ns; ++s) {
      const int a = ends[2 * s], c = ends[2 * s + 1];
      const Vec3 d = x[c] - x[a];
      const double l = d.norm();
      const Vec3 t = stiffness * (l - l0[s]) / l * d;
      f[a] += t;
      f[c] -= t;
      // K = [-Ks Ks; Ks -Ks]; the transverse term is dropped under compression. Blocks
      // coupling to a pinned point are dropped; a free end keeps its own block.
      const Vec3 u = d / l;
      const Mat3 uu = u * u.transpose();
      const Mat3 ks = stiffness * (uu + std::max(0.0, 1.0 - l0[s] / l) * (Mat3::Identity() - uu));
      if (!pinned[a]) pattern.add(a, slots[s][0], ks, h * h);
      if (!pinned[c]) pattern.add(c, slots[s][3], ks, h * h);
      if (pinned[a] || pinned[c]) continue;
      pattern.add(a, slots[s][1], ks, -h * h);
      pattern.add(c, slots[s][2], ks, -h * h);
    }
    for (int i = 0; i < n; ++i) {
      const Vec3 bi = pinned[i] ? Vec3::Zero() : Vec3(m[i] * v[i] + h * (f[i] + m[i] * gravity));
      b.segment<3>(3 * i) = bi;
      vel.segment<3>(3 * i) = v[i];
    }
    const double assembly_ms = clock.lap_ms();
    const CgResult cg = conjugate_gradient(pattern.matrix(), b, vel, cg_tol, cg_max);
    for (int i = 0; i < n; ++i) {
      v[i] = vel.segment<3>(3 * i);
      x[i] += h * v[i];
    }
    log.frame(frame, assembly_ms, clock.lap_ms(), cg.iterations, cg.residual);
  }
  log.summary();
  return finish(options, x) ? 0 : 1;
}
