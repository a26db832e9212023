// A posteriori estimate of the discretization error by gradient recovery (Zienkiewicz–Zhu, nodal
// averaging; issue 22). The gradient of u_h is evaluated at every DOF point of every cell (the
// reference lattice of degree p mapped by the cell's order-k geometry) and averaged over the
// cells sharing the DOF, weighted by their volumes (of the straight tets on their corners);
// interpolated in the same Lagrange space it is the recovered gradient G(u_h), continuous where
// ∇u_h jumps. The indicator of cell K is
//   η_K = ‖G(u_h) − ∇u_h‖_L2(K)   (all components of a vector field together),
// and η = (Σ_K η_K²)^{1/2} estimates ‖∇(u − u_h)‖_L2, the H1-semi error compute_errors reports.
// It needs no exact solution, no rhs and no second derivatives, so it works on curved cells of
// any order and for every physics; what it measures is the smoothness of ∇u_h, so it misses
// error that leaves ∇u_h smooth (a wrong boundary value, the geometric error of ε).
#pragma once

#include <Eigen/Core>

#include "fem/space/function_space.hpp"
#include "meshing/core/lagrange_mesh.hpp"

namespace curvefem::fem {

struct RecoveryEstimate {
  Eigen::VectorXd cell_eta;  ///< η_K per cell
  double eta = 0.0;          ///< (Σ η_K²)^{1/2}
  double gradient_norm = 0;  ///< ‖∇u_h‖_L2, for the relative estimate η / ‖∇u_h‖
};

/// The recovered gradient G(u_h) at every DOF: #DOFs × 3c (component i's gradient in columns
/// 3i..3i+2). u: c values per DOF (DOF-major).
Eigen::MatrixXd recover_gradient(const LagrangeMesh& mesh, const FunctionSpace& space,
                                 const Eigen::VectorXd& u, int components);

/// u: components values per DOF (DOF-major), as compute_errors takes it. quadrature_degree < 0:
/// default_quadrature_degree(p, k, mass) — exact on straight cells, where G(u_h) and ∇u_h are
/// polynomials of degrees p and p − 1 (the over-integration of compute_errors is for the exact
/// solution, which the estimate does not have).
RecoveryEstimate estimate_gradient_recovery(const LagrangeMesh& mesh, const FunctionSpace& space,
                                            const Eigen::VectorXd& u, int components,
                                            int quadrature_degree = -1);

}  // namespace curvefem::fem
