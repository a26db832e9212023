#include "meshing/core/geometry_degree.hpp"

#include <algorithm>
#include <string>
#include <vector>

#include "meshing/core/error.hpp"

namespace curvefem {

namespace {

// P = R · E: the order-k nodes of the degree-m interpolant of a cell map from its order-k nodes.
Eigen::MatrixXd lowering_matrix(int k, int m) {
  const Eigen::MatrixXd low = lagrange_reference_nodes(CellKind::tetrahedron, m);
  const Eigen::MatrixXd high = lagrange_reference_nodes(CellKind::tetrahedron, k);
  Eigen::MatrixXd E(low.rows(), high.rows()), R(high.rows(), low.rows());
  for (Eigen::Index j = 0; j < low.rows(); ++j)
    E.row(j) =
        lagrange_shape_values(CellKind::tetrahedron, k, Eigen::Vector3d(low.row(j))).transpose();
  for (Eigen::Index n = 0; n < high.rows(); ++n)
    R.row(n) =
        lagrange_shape_values(CellKind::tetrahedron, m, Eigen::Vector3d(high.row(n))).transpose();
  return R * E;
}

}  // namespace

LagrangeMesh lower_geometry_degree(const LagrangeMesh& mesh, int m, const CellAccept& accept,
                                   int* kept) {
  if (mesh.kind != CellKind::tetrahedron)
    throw InputError("lower_geometry_degree: needs a tetrahedral mesh");
  if (m < 1 || m > mesh.order)
    throw InputError("lower_geometry_degree: degree " + std::to_string(m) + " outside 1.." +
                     std::to_string(mesh.order));
  if (kept) *kept = 0;
  if (m == mesh.order) return mesh;
  const int k = mesh.order, nc = mesh.num_cells(), nn = mesh.num_nodes();
  const Eigen::MatrixXd P = lowering_matrix(k, m);
  const Eigen::Index per = mesh.cells.cols();
  // The lowered position of every node (from the first cell holding it; an interpolant on a
  // shared entity depends on that entity only, so every cell gives it to rounding).
  Eigen::MatrixXd lowered = mesh.nodes;
  std::vector<char> done(static_cast<std::size_t>(nn), 0);
  Eigen::MatrixXd X(per, 3);
  for (int c = 0; c < nc; ++c) {
    for (Eigen::Index n = 0; n < per; ++n) X.row(n) = mesh.nodes.row(mesh.cells(c, n));
    const Eigen::MatrixXd Y = P * X;
    for (Eigen::Index n = 4; n < per; ++n) {  // corners stay bit-identical
      const int id = mesh.cells(c, n);
      if (!done[std::size_t(id)]) lowered.row(id) = Y.row(n);
      done[std::size_t(id)] = 1;
    }
  }
  // Cells kept at their own map: a node takes its lowered position only when every cell holding
  // it is lowered. Refused cells are removed until every cell is accepted (monotone).
  std::vector<char> lower(static_cast<std::size_t>(nc), 1);
  LagrangeMesh out = mesh;
  out.nodes = lowered;
  if (!accept) return out;
  std::vector<int> check(static_cast<std::size_t>(nc));
  for (int c = 0; c < nc; ++c) check[std::size_t(c)] = c;
  std::vector<std::vector<int>> node_cells(static_cast<std::size_t>(nn));
  for (int c = 0; c < nc; ++c)
    for (Eigen::Index n = 0; n < per; ++n) node_cells[std::size_t(mesh.cells(c, n))].push_back(c);
  while (!check.empty()) {
    std::vector<int> refused;
    for (int c : check) {
      if (!lower[std::size_t(c)]) continue;  // already on its own map
      for (Eigen::Index n = 0; n < per; ++n) X.row(n) = out.nodes.row(mesh.cells(c, n));
      if (!accept(c, X)) refused.push_back(c);
    }
    std::vector<int> next;
    for (int c : refused) {
      lower[std::size_t(c)] = 0;
      if (kept) ++*kept;
      for (Eigen::Index n = 4; n < per; ++n) {
        const int id = mesh.cells(c, n);
        out.nodes.row(id) = mesh.nodes.row(id);
        for (int g : node_cells[std::size_t(id)]) next.push_back(g);
      }
    }
    std::sort(next.begin(), next.end());
    next.erase(std::unique(next.begin(), next.end()), next.end());
    check = std::move(next);
  }
  return out;
}

}  // namespace curvefem
