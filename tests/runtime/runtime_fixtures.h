// Shared helpers for the runtime tests: small meshes, assembly through the pattern's index,
// and an independent dense assembly of the same local matrices.
#pragma once

#include <Eigen/Dense>
#include <array>
#include <functional>
#include <memory>
#include <random>

#include "runtime/set.h"
#include "runtime/system_matrix.h"

namespace simit::runtime::testing {

// n × n × n unit cubes, each split into the 6 tetrahedra around its main diagonal.
inline void build_cube_tets(int n, Set& verts, Set& tets) {
  const int m = n + 1;
  verts.add_many(m * m * m);
  auto vertex = [m](int x, int y, int z) { return x + m * (y + m * z); };
  const int axes[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  for (int z = 0; z < n; ++z)
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x)
        for (const auto& order : axes) {
          std::array<int, 3> c = {x, y, z};
          std::array<int32_t, 4> tet{};
          tet[0] = vertex(c[0], c[1], c[2]);
          for (int k = 0; k < 3; ++k) {
            ++c[order[k]];
            tet[k + 1] = vertex(c[0], c[1], c[2]);
          }
          tets.add(tet);
        }
}

// The member positions of `edges` (0: the element, k + 1: endpoint k) that lie in `target`.
inline std::vector<int> members_of(const Set& edges, const Set& target) {
  std::vector<int> out;
  for (int m = 0; m <= edges.arity(); ++m)
    if (&member_set(edges, m) == &target) out.push_back(m);
  return out;
}

// A local matrix per element: (row members × block rows) by (column members × block cols).
using LocalMatrix = std::function<Eigen::MatrixXd(int element)>;

// Adds every element's local matrix into `m` through the pattern's assembly index.
inline void assemble(SystemMatrix& m, const Set& edges, const LocalMatrix& local) {
  const AssemblyIndex& ix = m.pattern().assembly();
  const int br = m.block_rows(), bc = m.block_cols();
  for (int e = 0; e < edges.size(); ++e) {
    const Eigen::MatrixXd l = local(e);
    for (size_t i = 0; i < ix.row_members.size(); ++i)
      for (size_t j = 0; j < ix.col_members.size(); ++j) {
        double* blk = m.block(ix.position(e, static_cast<int>(i), static_cast<int>(j)));
        for (int a = 0; a < br; ++a)
          for (int b = 0; b < bc; ++b) blk[a * bc + b] += l(i * br + a, j * bc + b);
      }
  }
}

// The same sum assembled densely, straight from the endpoints.
inline Eigen::MatrixXd assemble_dense(const Set& edges, const Set& rows, const Set& cols, int br,
                                      int bc, const LocalMatrix& local) {
  Eigen::MatrixXd d = Eigen::MatrixXd::Zero(rows.size() * br, cols.size() * bc);
  const std::vector<int> rm = members_of(edges, rows), cm = members_of(edges, cols);
  for (int e = 0; e < edges.size(); ++e) {
    const Eigen::MatrixXd l = local(e);
    for (size_t i = 0; i < rm.size(); ++i)
      for (size_t j = 0; j < cm.size(); ++j)
        d.block(member_element(edges, e, rm[i]) * br, member_element(edges, e, cm[j]) * bc, br,
                bc) += l.block(i * br, j * bc, br, bc);
  }
  return d;
}

// Deterministic random local matrices (a fixed table, so two calls for one element agree).
inline LocalMatrix random_locals(int elements, int rows, int cols, unsigned seed) {
  std::mt19937 gen(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  auto table = std::make_shared<std::vector<Eigen::MatrixXd>>();
  for (int e = 0; e < elements; ++e)
    table->push_back(Eigen::MatrixXd::NullaryExpr(rows, cols, [&] { return u(gen); }));
  return [table](int e) { return (*table)[e]; };
}

// Symmetric positive semi-definite local matrices Gᵀ G.
inline LocalMatrix gram_locals(int elements, int size, unsigned seed) {
  LocalMatrix g = random_locals(elements, size, size, seed);
  return [g](int e) {
    const Eigen::MatrixXd m = g(e);
    // Eigen's product need not round (i, j) and (j, i) alike; the mean of the two is
    // symmetric exactly, as the solver tests require.
    const Eigen::MatrixXd p = m.transpose() * m;
    return Eigen::MatrixXd(0.5 * (p + p.transpose()));
  };
}

inline std::vector<double> random_vector(size_t n, unsigned seed) {
  std::mt19937 gen(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<double> v(n);
  for (double& x : v) x = u(gen);
  return v;
}

inline Eigen::Map<const Eigen::VectorXd> as_eigen(const std::vector<double>& v) {
  return Eigen::Map<const Eigen::VectorXd>(v.data(), static_cast<Eigen::Index>(v.size()));
}

}  // namespace simit::runtime::testing
