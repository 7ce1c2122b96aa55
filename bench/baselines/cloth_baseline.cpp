// Hand-written Eigen version of examples/cloth/cloth.sim: membrane stretching on triangles,
// discrete-shells bending on hinges, explicit Velocity Verlet, on a generated square cloth.
// Each step is two passes: the forces over faces and hinges, then one over the points
// (acceleration, velocity and the next step's positions fused).
// --threads N runs the steps on N OpenMP threads: faces and hinges partitioned (each thread
// adding into its own copy of the forces), the point passes in chunks (baseline_common.h).
// Usage: cloth_baseline [--check] [--csv FILE] [--threads N] [N] [FRAMES]
//        (N x N vertices, default 32)
// Final positions are written only with --csv FILE; --help lists every option.
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "baseline_common.h"
#include "runtime/mesh/mesh.h"
#include "runtime/mesh/topology.h"

using namespace simit::baseline;

namespace {

const double density = 0.1, mu_s = 50.0, lambda_s = 50.0, kb = 1e-3, h = 2e-4;
const int substeps = 50;
const Vec3 gravity(0.0, -10.0, 0.0);
using Mat32 = Eigen::Matrix<double, 3, 2>;

struct FaceRest {
  Eigen::Matrix2d B;  // inverse rest edge matrix in the triangle's plane
  double area;
};

struct HingeRest {
  double theta0, w;
};

// Signed dihedral angle of hinge (a, b, c, d), triangles (a, b, c) and (b, a, d), and, unless
// g is null (the energy needs only the angle), its gradient per point (Bridson et al. 2003).
double dihedral(const Vec3s& x, const simit::runtime::Hinge& hg, std::array<Vec3, 4>* g) {
  const Vec3 &a = x[hg[0]], &b = x[hg[1]], &c = x[hg[2]], &d = x[hg[3]];
  const Vec3 e = b - a;
  const double le = e.norm();
  const Vec3 n1 = e.cross(c - a), n2 = (a - b).cross(d - b);
  if (g) {
    const Vec3 q1 = n1 / n1.squaredNorm(), q2 = n2 / n2.squaredNorm();
    (*g)[2] = -le * q1;
    (*g)[3] = -le * q2;
    (*g)[0] = -(((c - b).dot(e) / le) * q1 + ((d - b).dot(e) / le) * q2);
    (*g)[1] = ((c - a).dot(e) / le) * q1 + ((d - a).dot(e) / le) * q2;
  }
  return std::atan2(n1.cross(n2).dot(e) / le, n1.dot(n2));
}

}  // namespace

int main(int argc, char** argv) {
  const Options options = parse_options(argc, argv, "32");
  const int side = std::atoi(options.input.c_str());
  if (side < 2) {
    std::fprintf(stderr, "the cloth needs N >= 2 vertices per side, got '%s'\n",
                 options.input.c_str());
    return 2;
  }
  // A unit square in the xz-plane at y = 0, each quad split along one diagonal with the same
  // winding; pinned at the corners (0, 0, 0) and (1, 0, 0).
  const int n = side * side;
  Vec3s x(n), v(n, Vec3::Zero()), acc(n, Vec3::Zero()), f(n);
  std::vector<char> pinned(n, 0);
  for (int j = 0; j < side; ++j)
    for (int i = 0; i < side; ++i)
      x[i + side * j] = Vec3(double(i) / (side - 1), 0.0, double(j) / (side - 1));
  pinned[0] = pinned[side - 1] = 1;
  std::vector<simit::runtime::Triangle> faces;
  for (int j = 0; j + 1 < side; ++j)
    for (int i = 0; i + 1 < side; ++i) {
      const int p = i + side * j;
      faces.push_back({p, p + 1, p + side + 1});
      faces.push_back({p, p + side + 1, p + side});
    }
  const std::vector<simit::runtime::Hinge> hinges = simit::runtime::hinges(faces);
  const int nf = static_cast<int>(faces.size()), nh = static_cast<int>(hinges.size());

  std::vector<FaceRest> face_rest(nf);
  std::vector<double> m(n, 0.0);
  for (int k = 0; k < nf; ++k) {
    const auto& t = faces[k];
    const Vec3 e1 = x[t[1]] - x[t[0]], e2 = x[t[2]] - x[t[0]], nrm = e1.cross(e2);
    const Vec3 t1 = e1 / e1.norm(), t2 = nrm.cross(t1) / nrm.norm();
    Eigen::Matrix2d dm;
    dm << e1.norm(), t1.dot(e2), 0.0, t2.dot(e2);
    face_rest[k] = {dm.inverse(), 0.5 * nrm.norm()};
    for (int i = 0; i < 3; ++i) m[t[i]] += density * face_rest[k].area / 3.0;
  }
  std::vector<HingeRest> hinge_rest(nh);
  for (int k = 0; k < nh; ++k) {
    const auto& hg = hinges[k];
    const Vec3 e = x[hg[1]] - x[hg[0]];
    const double areas =
        0.5 * (e.cross(x[hg[2]] - x[hg[0]]).norm() + e.cross(x[hg[3]] - x[hg[1]]).norm());
    hinge_rest[k] = {dihedral(x, hg, nullptr), 3.0 * kb * e.squaredNorm() / areas};
  }
  // Faces and hinges sharing a point add into the same force: each thread into its own copy.
  PartitionedLoop force_loop(n, 0);
  std::printf("cloth %dx%d: %d points, %d faces, %d hinges", side, side, n, nf, nh);
  if (options.threads > 1) std::printf(", %d threads", options.threads);
  std::printf("\n");

  // Face k's deformation gradient and Green strain E = (F'F - I)/2.
  auto deformation = [&](int k) {
    const auto& t = faces[k];
    Mat32 ds;
    ds << x[t[1]] - x[t[0]], x[t[2]] - x[t[0]];
    return Mat32(ds * face_rest[k].B);
  };
  auto green_strain = [](const Mat32& F) {
    return Eigen::Matrix2d(0.5 * (F.transpose() * F - Eigen::Matrix2d::Identity()));
  };
  // Adds the membrane and bending forces into f (zero on entry): one loop over the faces,
  // then the hinges (element nf + k is hinge k), so that the threads split both at once.
  auto add_forces = [&]() {
    force_loop.run(nf + nh, f.data(), nullptr, [&](int element, Vec3* force, Mat3*) {
      if (element >= nf) {
        const int k = element - nf;
        const auto& hg = hinges[k];
        std::array<Vec3, 4> grad;
        const double theta = dihedral(x, hg, &grad);
        const double s = -2.0 * hinge_rest[k].w * (theta - hinge_rest[k].theta0);
        for (int i = 0; i < 4; ++i) force[hg[i]] += s * grad[i];
        return;
      }
      const int k = element;
      const auto& t = faces[k];
      const FaceRest& r = face_rest[k];
      const Mat32 F = deformation(k);
      const Eigen::Matrix2d E = green_strain(F);
      const Eigen::Matrix2d S =
          (lambda_s * E.trace()) * Eigen::Matrix2d::Identity() + (2.0 * mu_s) * E;
      const Mat32 H = -r.area * (F * S * r.B.transpose());
      force[t[0]] -= H.col(0) + H.col(1);
      force[t[1]] += H.col(0);
      force[t[2]] += H.col(1);
    });
  };
  auto acceleration = [&](int i) { return pinned[i] ? Vec3::Zero() : Vec3(f[i] / m[i] + gravity); };
  // cloth.sim's energy statistic: area (lambda/2 tr(E)^2 + mu tr(E^2)) per face,
  // w (theta - theta0)^2 per hinge, kinetic and gravitational per point. Summed directly:
  // cloth.sim spreads each element's term over its corners only because its statistic is one
  // vector over the points.
  auto total_energy = [&]() {
    const double membrane = parallel_sum(nf, 0.0, [&](int k) {
      const Eigen::Matrix2d E = green_strain(deformation(k));
      const double trE = E.trace();
      // tr(E^2) is the sum of squares: E is symmetric.
      return face_rest[k].area * (0.5 * lambda_s * trE * trE + mu_s * E.squaredNorm());
    });
    const double bending = parallel_sum(nh, membrane, [&](int k) {
      const double bend = dihedral(x, hinges[k], nullptr) - hinge_rest[k].theta0;
      return hinge_rest[k].w * bend * bend;
    });
    return parallel_sum(n, bending, [&](int i) {
      return 0.5 * m[i] * v[i].squaredNorm() - m[i] * gravity.dot(x[i]);
    });
  };

  std::fill(f.begin(), f.end(), Vec3::Zero());
  add_forces();
  for (int i = 0; i < n; ++i) acc[i] = acceleration(i), f[i].setZero();
  FrameLog log{"forces", "integration", {}};
  for (int frame = 1; frame <= options.frames; ++frame) {
    double force_ms = 0.0, integrate_ms = 0.0;
    Stopwatch clock;
    parallel_for(n, [&](int i) { x[i] += h * v[i] + (0.5 * h * h) * acc[i]; });
    integrate_ms += clock.lap_ms();
    for (int s = 0; s < substeps; ++s) {
      add_forces();
      force_ms += clock.lap_ms();
      // One pass per step over the points: the new acceleration, the velocity, f cleared for
      // the next step and, unless the frame ends here, the next step's positions.
      const bool last = s + 1 == substeps;
      parallel_for(n, [&](int i) {
        const Vec3 a_new = acceleration(i);
        v[i] += (0.5 * h) * (acc[i] + a_new);
        acc[i] = a_new;
        f[i].setZero();
        if (!last) x[i] += h * v[i] + (0.5 * h * h) * acc[i];
      });
      integrate_ms += clock.lap_ms();
    }
    // The frame's positions and velocities are final here: the next frame's first position
    // update comes first in the loop.
    const double energy = total_energy();
    integrate_ms += clock.lap_ms();
    log.frame(frame, force_ms, integrate_ms, energy);
  }
  log.summary();
  return finish(options, x) ? 0 : 1;
}
