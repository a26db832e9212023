#include "fem/problems/error_estimate.hpp"

#include <tbb/parallel_for.h>

#include <Eigen/LU>
#include <cmath>

#include "fem/assembly/element_geometry.hpp"
#include "fem/assembly/tabulation.hpp"
#include "fem/quadrature/simplex_quadrature.hpp"
#include "meshing/core/error.hpp"
#include "meshing/core/lagrange_nodes.hpp"

namespace curvefem::fem {

Eigen::MatrixXd recover_gradient(const LagrangeMesh& mesh, const FunctionSpace& space,
                                 const Eigen::VectorXd& u, int c) {
  CF_VERIFY(c >= 1 && u.size() == static_cast<Eigen::Index>(space.num_dofs) * c,
            "recover_gradient: field size mismatch");
  const int p = space.degree, nc = mesh.num_cells();
  const int n = static_cast<int>(space.cell_dofs.cols());
  // The DOF points of the reference cell (the degree-p lattice, the basis's order).
  const auto& lattice = lagrange_lattice(CellKind::tetrahedron, p);
  Eigen::MatrixXd nodes(n, 3);
  for (int a = 0; a < n; ++a)
    for (int d = 0; d < 3; ++d)
      nodes(a, d) = double(lattice[std::size_t(a)][std::size_t(d + 1)]) / p;
  const GeometryEvaluator at_nodes(mesh, nodes, Eigen::VectorXd::Ones(n));
  const ReferenceTabulation node_basis = tabulate(CellKind::tetrahedron, p, nodes);

  // Per cell: its volume and ∇u_h at its DOF points (c × 3 each, row-major in `grad`).
  Eigen::VectorXd volume(nc);
  Eigen::MatrixXd grad(Eigen::Index(nc) * n, 3 * c);
  tbb::parallel_for(0, nc, [&](int cell) {
    CellGeometry gn;
    at_nodes.evaluate(cell, gn);
    // The weight: the volume of the straight tet on the corners (only a weight).
    Eigen::Matrix3d E;
    for (int d = 0; d < 3; ++d)
      E.col(d) = (mesh.nodes.row(mesh.cells(cell, d + 1)) - mesh.nodes.row(mesh.cells(cell, 0)))
                     .transpose();
    volume[cell] = std::abs(E.determinant()) / 6;
    Eigen::MatrixXd U(n, c);
    for (int a = 0; a < n; ++a)
      for (int i = 0; i < c; ++i) U(a, i) = u[space.cell_dofs(cell, a) * c + i];
    for (int a = 0; a < n; ++a) {
      const Eigen::MatrixXd G = U.transpose() * (node_basis.gradients[a] * gn.jacobian_inv[a]);
      for (int i = 0; i < c; ++i)
        for (int d = 0; d < 3; ++d) grad(Eigen::Index(cell) * n + a, 3 * i + d) = G(i, d);
    }
  });
  // Volume-weighted averages per DOF (serial: a fixed summation order).
  Eigen::MatrixXd recovered = Eigen::MatrixXd::Zero(space.num_dofs, 3 * c);
  Eigen::VectorXd weight = Eigen::VectorXd::Zero(space.num_dofs);
  for (int cell = 0; cell < nc; ++cell)
    for (int a = 0; a < n; ++a) {
      const int dof = space.cell_dofs(cell, a);
      recovered.row(dof) += volume[cell] * grad.row(Eigen::Index(cell) * n + a);
      weight[dof] += volume[cell];
    }
  for (int dof = 0; dof < space.num_dofs; ++dof)
    if (weight[dof] > 0) recovered.row(dof) /= weight[dof];
  return recovered;
}

RecoveryEstimate estimate_gradient_recovery(const LagrangeMesh& mesh, const FunctionSpace& space,
                                            const Eigen::VectorXd& u, int c,
                                            int quadrature_degree) {
  CF_VERIFY(c >= 1 && u.size() == static_cast<Eigen::Index>(space.num_dofs) * c,
            "estimate_gradient_recovery: field size mismatch");
  const int p = space.degree, nc = mesh.num_cells();
  const int n = static_cast<int>(space.cell_dofs.cols());
  const int degree = quadrature_degree >= 0
                         ? quadrature_degree
                         : default_quadrature_degree(p, mesh.order, QuadratureUse::mass);
  const QuadratureRule& rule = tetrahedron_quadrature(degree);
  const GeometryEvaluator geometry(mesh, rule.points, rule.weights);
  const ReferenceTabulation basis = tabulate(CellKind::tetrahedron, p, rule.points);
  const Eigen::MatrixXd recovered = recover_gradient(mesh, space, u, c);

  RecoveryEstimate out;
  out.cell_eta.resize(nc);
  Eigen::VectorXd cell_grad(nc);
  tbb::parallel_for(0, nc, [&](int cell) {
    CellGeometry g;
    geometry.evaluate(cell, g);
    Eigen::MatrixXd U(n, c), R(n, 3 * c);
    for (int a = 0; a < n; ++a) {
      for (int i = 0; i < c; ++i) U(a, i) = u[space.cell_dofs(cell, a) * c + i];
      R.row(a) = recovered.row(space.cell_dofs(cell, a));
    }
    double s = 0, gs = 0;
    Eigen::MatrixXd physical(n, 3), G(c, 3);
    Eigen::RowVectorXd r(3 * c);
    for (int q = 0; q < geometry.num_points(); ++q) {
      physical.noalias() = basis.gradients[q] * g.jacobian_inv[q];
      G.noalias() = U.transpose() * physical;  // c × 3
      r.noalias() = basis.values.row(q) * R;   // 1 × 3c
      for (int i = 0; i < c; ++i)
        for (int d = 0; d < 3; ++d) {
          const double e = r[3 * i + d] - G(i, d);
          s += g.det_w[q] * e * e;
          gs += g.det_w[q] * G(i, d) * G(i, d);
        }
    }
    out.cell_eta[cell] = std::sqrt(s);
    cell_grad[cell] = gs;
  });
  out.eta = out.cell_eta.norm();
  out.gradient_norm = std::sqrt(cell_grad.sum());
  return out;
}

}  // namespace curvefem::fem
