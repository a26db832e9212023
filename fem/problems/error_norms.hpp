// L2 and H1-semi norms of u_h − u against an exact solution, integrated on the curved mesh with
// an over-integrating rule (default_quadrature_degree(p, k, error)). Fields with c components
// store c values per DOF (DOF-major).
#pragma once

#include <Eigen/Core>
#include <functional>

#include "fem/space/function_space.hpp"
#include "meshing/core/lagrange_mesh.hpp"

namespace curvefem::fem {

struct ErrorNorms {
  double l2 = 0.0;                             ///< ‖u_h − u‖_L2
  double h1_semi = 0.0;                        ///< ‖∇(u_h − u)‖_L2
  double l2_exact = 0.0, h1_semi_exact = 0.0;  ///< norms of u, for relative errors
};

/// exact(x) fills c values, exact_gradient(x) fills a c × 3 row-major Jacobian (∂u_i/∂x_j).
using ExactValue = std::function<void(const Eigen::Vector3d& x, double* value)>;
using ExactGradient = std::function<void(const Eigen::Vector3d& x, double* gradient)>;

/// All the quadrature points of one cell at once: x is n_q × 3; fill values (n_q × c) and
/// gradients (n_q × 3c, column 3i + j = ∂u_i/∂x_j), both already sized. Lets the caller evaluate
/// the exact solution over a batch (pipeline's expressions: one walk of the tree per batch).
using ExactBatch = std::function<void(const Eigen::MatrixXd& x, Eigen::MatrixXd& values,
                                      Eigen::MatrixXd& gradients)>;

ErrorNorms compute_errors(const LagrangeMesh& mesh, const FunctionSpace& space,
                          const Eigen::VectorXd& u, int components, const ExactBatch& exact,
                          int quadrature_degree = -1);
ErrorNorms compute_errors(const LagrangeMesh& mesh, const FunctionSpace& space,
                          const Eigen::VectorXd& u, int components, const ExactValue& exact,
                          const ExactGradient& exact_gradient, int quadrature_degree = -1);

}  // namespace curvefem::fem
