// Tiny curved Lagrange meshes built in code for the VTU / MSH volume I/O tests.
//
// curved_cell: one cell whose geometric map is an exact polynomial of degree k (random affine map
// plus a random degree-k perturbation), so LagrangeMesh::map reproduces it exactly and any
// interpolating reader with the right node order must agree to round-off.
// curved_patch: several cells sharing vertices, edges and faces (a cube split into 6 tetrahedra /
// a square split into 4 triangles), high-order nodes shared between neighbours and moved by a
// smooth displacement; neighbours see shared faces in different local orientations.
#pragma once

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <random>
#include <utility>
#include <vector>

#include "meshing/core/lagrange_mesh.hpp"

namespace curvefem::test {

/// A uniformly distributed point of the reference simplex (z = 0 for triangles).
inline Eigen::Vector3d random_reference_point(std::mt19937& rng, CellKind kind) {
  std::exponential_distribution<double> e(1.0);
  const int dim = cell_dimension(kind);
  double w[4];
  double sum = 0.0;
  for (int i = 0; i <= dim; ++i) sum += (w[i] = e(rng));
  Eigen::Vector3d xi = Eigen::Vector3d::Zero();
  for (int d = 0; d < dim; ++d) xi[d] = w[d + 1] / sum;
  return xi;
}

/// One curved cell of `order`: x(ξ) = A ξ + b + 0.15 p(ξ), p a random vector polynomial of degree
/// `order`; nodes = x at the canonical reference nodes, cells = 0..n-1.
inline LagrangeMesh curved_cell(CellKind kind, int order, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const int dim = cell_dimension(kind);
  Eigen::Matrix3d A = Eigen::Matrix3d::Identity();
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) A(r, c) += 0.3 * u(rng);
  const Eigen::Vector3d b(u(rng), u(rng), u(rng));
  // Monomials ξ^a of total degree ≤ order.
  std::vector<std::array<int, 3>> exponents;
  for (int a = 0; a <= order; ++a)
    for (int c = 0; a + c <= order; ++c)
      for (int d = 0; a + c + d <= order; ++d)
        if (dim == 3 || d == 0) exponents.push_back({a, c, d});
  Eigen::MatrixXd coeff(3, exponents.size());
  for (int r = 0; r < 3; ++r)
    for (Eigen::Index m = 0; m < coeff.cols(); ++m) coeff(r, m) = u(rng);

  const Eigen::MatrixXd ref = lagrange_reference_nodes(kind, order);
  LagrangeMesh mesh;
  mesh.kind = kind;
  mesh.order = order;
  mesh.nodes.resize(ref.rows(), 3);
  mesh.cells.resize(1, ref.rows());
  for (Eigen::Index i = 0; i < ref.rows(); ++i) {
    Eigen::Vector3d xi = Eigen::Vector3d::Zero();
    xi.head(dim) = ref.row(i).transpose();
    Eigen::Vector3d x = A.leftCols(dim) * xi.head(dim) + b;
    for (std::size_t m = 0; m < exponents.size(); ++m) {
      double mono = 1.0;
      for (int d = 0; d < 3; ++d) mono *= std::pow(xi[d], exponents[m][d]);
      x += 0.15 * mono * coeff.col(static_cast<Eigen::Index>(m));
    }
    mesh.nodes.row(i) = x.transpose();
    mesh.cells(0, i) = static_cast<int>(i);
  }
  return mesh;
}

/// Largest distance between nodes of the mesh: the length scale errors are measured against.
inline double mesh_size(const LagrangeMesh& mesh) {
  const Eigen::RowVector3d lo = mesh.nodes.colwise().minCoeff();
  const Eigen::RowVector3d hi = mesh.nodes.colwise().maxCoeff();
  return (hi - lo).norm();
}

/// Unit cube as 6 positively oriented tetrahedra around the diagonal 0-7 (vertex v = bits xyz),
/// or unit square as 4 triangles around its centre; nodes of `order` shared between cells and
/// moved by a smooth displacement. cell_tags: 3, 7, 3, 7, ... (tags empty if !tagged).
inline LagrangeMesh curved_patch(CellKind kind, int order, bool tagged = true) {
  const int dim = cell_dimension(kind);
  std::vector<Eigen::Vector3d> corners;
  std::vector<std::vector<int>> simplices;
  if (kind == CellKind::tetrahedron) {
    for (int v = 0; v < 8; ++v) corners.emplace_back(v & 1, (v >> 1) & 1, (v >> 2) & 1);
    std::array<int, 3> axes = {0, 1, 2};
    do {
      const int a = 1 << axes[0], b = a | (1 << axes[1]);
      std::vector<int> t = {0, a, b, 7};
      const double det =
          (corners[t[1]] - corners[t[0]])
              .dot((corners[t[2]] - corners[t[0]]).cross(corners[t[3]] - corners[t[0]]));
      if (det < 0) std::swap(t[1], t[2]);
      simplices.push_back(t);
    } while (std::next_permutation(axes.begin(), axes.end()));
  } else {
    corners = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0.5, 0.5, 0}};
    simplices = {{4, 0, 1}, {1, 2, 4}, {4, 2, 3}, {0, 4, 3}};
  }
  const auto& lattice = lagrange_lattice(kind, order);
  const int n = static_cast<int>(lattice.size());
  // A node's identity: its barycentric weights keyed by global vertex, sorted.
  std::map<std::vector<std::pair<int, int>>, int> node_of;
  std::vector<Eigen::Vector3d> points;
  LagrangeMesh mesh;
  mesh.kind = kind;
  mesh.order = order;
  mesh.cells.resize(static_cast<Eigen::Index>(simplices.size()), n);
  for (std::size_t c = 0; c < simplices.size(); ++c)
    for (int i = 0; i < n; ++i) {
      std::vector<std::pair<int, int>> key;
      for (int v = 0; v <= dim; ++v)
        if (lattice[i][v] > 0) key.emplace_back(simplices[c][v], lattice[i][v]);
      std::sort(key.begin(), key.end());
      auto [it, inserted] = node_of.try_emplace(key, static_cast<int>(points.size()));
      if (inserted) {
        Eigen::Vector3d x = Eigen::Vector3d::Zero();
        for (const auto& [v, a] : key) x += corners[v] * (static_cast<double>(a) / order);
        const Eigen::Vector3d y(std::sin(2.0 * x[0] + x[1]), std::cos(x[1] - x[2]),
                                std::sin(x[0] * x[2] + x[1]));
        points.push_back(x + 0.06 * y);
      }
      mesh.cells(static_cast<Eigen::Index>(c), i) = it->second;
    }
  mesh.nodes.resize(static_cast<Eigen::Index>(points.size()), 3);
  for (std::size_t i = 0; i < points.size(); ++i)
    mesh.nodes.row(static_cast<Eigen::Index>(i)) = points[i].transpose();
  if (tagged) {
    mesh.cell_tags.resize(mesh.num_cells());
    for (int c = 0; c < mesh.num_cells(); ++c) mesh.cell_tags[c] = c % 2 == 0 ? 3 : 7;
  }
  return mesh;
}

}  // namespace curvefem::test
