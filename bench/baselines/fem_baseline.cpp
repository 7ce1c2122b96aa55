// Hand-written Eigen version of examples/fem/fem.sim: Neo-Hookean tets, linearly-implicit
// backward Euler, unpreconditioned CG with the same stopping rule.
// Usage: fem_baseline [--check] [--csv FILE] [MESH] [FRAMES]
#include <cmath>
#include <cstdio>

#include "baseline_common.h"
#include "runtime/mesh/mesh.h"
#include "runtime/mesh/mesh_reader.h"

using namespace simit::baseline;

namespace {

const double E = 5e3, nu = 0.45, density = 1000.0, h = 0.005;
const double default_cg_tol = 1e-12;  // --cg-tol overrides
const int default_cg_max = 100;  // --cg-max overrides
const Vec3 gravity(0.0, -10.0, 0.0);

struct TetRest {
  Mat3 B;                        // Dm^-1
  double W;                      // rest volume
  std::array<Vec3, 4> g;         // shape-function gradients; g[3] = -(g0 + g1 + g2)
};

Mat3 edge_matrix(const std::vector<Vec3>& x, const simit::runtime::Tet& t) {
  Mat3 d;
  for (int j = 0; j < 3; ++j) d.col(j) = x[t[j]] - x[t[3]];
  return d;
}

}  // namespace

int main(int argc, char** argv) {
  const Options options = parse_options(argc, argv, "examples/data/bunny.1.node");
  const double cg_tol = options.cg_tol >= 0 ? options.cg_tol : default_cg_tol;
  const int cg_max = options.cg_max >= 0 ? options.cg_max : default_cg_max;
  const simit::runtime::Mesh mesh = simit::runtime::read_mesh(options.input);
  const int n = static_cast<int>(mesh.points.size());
  const int nt = static_cast<int>(mesh.tets.size());

  std::vector<Vec3> x(n);
  std::vector<Vec3> v(n, Vec3(0.1, 0.0, 0.1));
  std::vector<char> pinned(n);
  for (int i = 0; i < n; ++i) {
    x[i] = Vec3(mesh.points[i][0], mesh.points[i][1], mesh.points[i][2]);
    pinned[i] = x[i].y() < 1e-4;
    if (pinned[i]) v[i].setZero();
  }

  // Precomputation: rest shape, lumped masses, the pattern and each tet's block slots.
  Stopwatch setup;
  std::vector<TetRest> rest(nt);
  std::vector<double> m(n, 0.0);
  std::vector<int> tet_vertices;
  tet_vertices.reserve(4 * nt);
  for (int e = 0; e < nt; ++e) {
    const auto& t = mesh.tets[e];
    const Mat3 dm = edge_matrix(x, t);
    TetRest& r = rest[e];
    r.B = dm.inverse();
    r.W = -dm.determinant() / 6.0;
    for (int j = 0; j < 3; ++j) r.g[j] = r.B.row(j).transpose();
    r.g[3] = -(r.B.row(0) + r.B.row(1) + r.B.row(2)).transpose();
    for (int j = 0; j < 4; ++j) {
      m[t[j]] += 0.25 * density * r.W;
      tet_vertices.push_back(t[j]);
    }
  }
  BlockPattern pattern(n, tet_vertices, 4);
  std::vector<std::array<int, 16>> slots(nt);
  for (int e = 0; e < nt; ++e)
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j) slots[e][4 * i + j] = pattern.slot(mesh.tets[e][i], mesh.tets[e][j]);
  std::printf("%s: %d vertices, %d tets, %ld nonzeros, set-up %.3f ms\n", options.input.c_str(),
              n, nt, static_cast<long>(pattern.matrix().nonZeros()), setup.lap_ms());

  const double mu = 0.5 * E / nu;  // sic: the original host's formula
  const double lambda = E * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
  std::vector<Vec3> f(n);
  Eigen::VectorXd b(3 * n), vel(3 * n);
  FrameLog log{"assembly", "solve", {}};
  for (int frame = 1; frame <= options.frames; ++frame) {
    Stopwatch clock;
    pattern.set_zero();
    std::fill(f.begin(), f.end(), Vec3::Zero());
    for (int i = 0; i < n; ++i) pattern.add(i, pattern.diagonal_slot(i), m[i] * Mat3::Identity());
    for (int e = 0; e < nt; ++e) {
      const auto& t = mesh.tets[e];
      const TetRest& r = rest[e];
      const Mat3 F = edge_matrix(x, t) * r.B;
      const Mat3 Finv = F.inverse();
      const Mat3 FinvT = Finv.transpose();
      const double logJ = std::log(F.determinant());
      const Mat3 P = mu * (F - FinvT) + lambda * logJ * FinvT;
      for (int j = 0; j < 4; ++j) f[t[j]] += -r.W * (P * r.g[j]);
      // A = M - h^2 K, K's column (j, d) being -W dP(e_d g_j') g_i for each corner i.
      const double c = mu - lambda * logJ;
      std::array<Mat3, 16> blocks;
      for (int j = 0; j < 4; ++j)
        for (int d = 0; d < 3; ++d) {
          const Mat3 dF = Vec3::Unit(d) * r.g[j].transpose();
          const double tr = r.g[j].dot(Finv.col(d));
          const Mat3 dP = mu * dF + c * (FinvT * dF.transpose() * FinvT) + (lambda * tr) * FinvT;
          for (int i = 0; i < 4; ++i) blocks[4 * i + j].col(d) = -r.W * (dP * r.g[i]);
        }
      for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j)
          if (!pinned[t[i]] && !pinned[t[j]])
            pattern.add(t[i], slots[e][4 * i + j], blocks[4 * i + j], -h * h);
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
