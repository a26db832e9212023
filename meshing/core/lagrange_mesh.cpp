#include "meshing/core/lagrange_mesh.hpp"

#include <cmath>

#include "meshing/core/error.hpp"

namespace curvefem {

Eigen::Vector3d LagrangeMesh::map(int cell, const Eigen::Vector3d& xi) const {
  const Eigen::VectorXd phi = lagrange_shape_values(kind, order, xi);
  Eigen::Vector3d x = Eigen::Vector3d::Zero();
  for (int i = 0; i < phi.size(); ++i) x += phi[i] * nodes.row(cells(cell, i)).transpose();
  return x;
}

Eigen::MatrixXd LagrangeMesh::jacobian(int cell, const Eigen::Vector3d& xi) const {
  const Eigen::MatrixXd grad = lagrange_shape_gradients(kind, order, xi);
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(3, grad.cols());
  for (int i = 0; i < grad.rows(); ++i) J += nodes.row(cells(cell, i)).transpose() * grad.row(i);
  return J;
}

std::pair<Eigen::Vector3d, Eigen::Vector3d> vertex_bounding_box(const LagrangeMesh& mesh) {
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(HUGE_VAL), hi = -lo;
  for (int c = 0; c < mesh.num_cells(); ++c)
    for (int j = 0; j < 4; ++j) {
      lo = lo.cwiseMin(mesh.nodes.row(mesh.cells(c, j)).transpose());
      hi = hi.cwiseMax(mesh.nodes.row(mesh.cells(c, j)).transpose());
    }
  return {lo, hi};
}

LagrangeMesh as_triangle_mesh(const SurfaceMesh& s) {
  LagrangeMesh m;
  m.kind = CellKind::triangle;
  m.order = 1;
  m.nodes = s.V;
  m.cells = s.F;
  m.cell_tags = s.tags;
  return m;
}

void validate_structure(const LagrangeMesh& mesh, const std::string& what) {
  if (mesh.order < 1 || mesh.order > k_max_order)
    throw InputError(what + ": geometric order " + std::to_string(mesh.order) + " is not in 1.." +
                     std::to_string(k_max_order));
  if (mesh.nodes.cols() != 3 && mesh.nodes.rows() > 0)
    throw InputError(what + ": nodes must have 3 columns");
  if (mesh.cells.rows() > 0 && mesh.cells.cols() != mesh.nodes_per_cell())
    throw InputError(what + ": cells have " + std::to_string(mesh.cells.cols()) + " nodes, order " +
                     std::to_string(mesh.order) + " needs " +
                     std::to_string(mesh.nodes_per_cell()));
  for (int n = 0; n < mesh.num_nodes(); ++n)
    for (int d = 0; d < 3; ++d)
      if (!std::isfinite(mesh.nodes(n, d)))
        throw InputError(what + ": non-finite node coordinate", {.vertex = n});
  for (int c = 0; c < mesh.num_cells(); ++c)
    for (int i = 0; i < mesh.cells.cols(); ++i)
      if (mesh.cells(c, i) < 0 || mesh.cells(c, i) >= mesh.num_nodes())
        throw InputError(what + ": node id " + std::to_string(mesh.cells(c, i)) +
                             " out of range [0, " + std::to_string(mesh.num_nodes()) + ")",
                         {.element = c});
  if (mesh.cell_tags.size() != 0 && mesh.cell_tags.size() != mesh.num_cells())
    throw InputError(what + ": " + std::to_string(mesh.cell_tags.size()) + " cell tags for " +
                     std::to_string(mesh.num_cells()) + " cells");
}

}  // namespace curvefem
