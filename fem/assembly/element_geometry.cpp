#include "fem/assembly/element_geometry.hpp"

#include <Eigen/LU>
#include <sstream>

#include "meshing/core/error.hpp"

namespace curvefem::fem {

GeometryEvaluator::GeometryEvaluator(const LagrangeMesh& mesh, const Eigen::MatrixXd& points,
                                     const Eigen::VectorXd& weights)
    : m_mesh(mesh),
      m_weights(weights),
      m_tab(tabulate(CellKind::tetrahedron, mesh.order, points)) {}

void GeometryEvaluator::evaluate(int cell, CellGeometry& out) const {
  const int nq = num_points();
  const int nk = static_cast<int>(m_tab.values.cols());
  // Nodes of an order ≤ 4 tet fit on the stack (35 × 3).
  Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::ColMajor, 35, 3> X(nk, 3);
  for (int i = 0; i < nk; ++i) X.row(i) = m_mesh.nodes.row(m_mesh.cells(cell, i));
  out.x.noalias() = m_tab.values * X;
  out.jacobian_inv.resize(nq);
  out.det_w.resize(nq);
  double det0 = 0;
  for (int q = 0; q < nq; ++q) {
    if (q > 0 && m_mesh.order == 1) {
      // A straight tet: J is the same at every point (the gradients of the P1 basis are).
      out.jacobian_inv[q] = out.jacobian_inv[0];
      out.det_w[q] = det0 * m_weights[q];
      continue;
    }
    const Eigen::Matrix3d J = X.transpose() * m_tab.gradients[q];  // 3 × 3: ∂x/∂ξ
    const double det = J.determinant();
    if (!(det > 0.0)) {
      std::ostringstream s;
      s << "curved element has non-positive Jacobian determinant " << det << " at quadrature point "
        << q << " (inverted or degenerate element)";
      throw SolverError(s.str(), {.element = cell});
    }
    out.jacobian_inv[q] = J.inverse();
    out.det_w[q] = det * m_weights[q];
    det0 = det;
  }
}

}  // namespace curvefem::fem
