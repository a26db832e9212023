// The linear solve shared by the 2-D and 3-D SLIM proxies (scaf.cpp, scaf3d.cpp).
#pragma once

#include <Eigen/Core>
#include <Eigen/Sparse>
#include <string>

namespace curvefem::meshing::param {

/// Solves A x = rhs, A the SLIM proxy's matrix (SPD in exact arithmetic, lower triangle used),
/// with CHOLMOD's supernodal LLᵀ on the AMD ordering. SLIM weights grow like σ⁻³, so on a badly
/// distorted map (σ_min ~ 1e-6) the factorisation may break down: then a proximal term
/// δ Σ_i A_ii (x_i − x0_i)² is added (its gradient vanishes at x0, so x − x0 is still a descent
/// direction), δ = 1e-10, 1e-7, 1e-4, 1e-2 until it succeeds. `regularisation` receives the δ
/// used (0: none). SolverError naming `who` when every δ fails.
Eigen::VectorXd solve_slim_system(const Eigen::SparseMatrix<double>& A, const Eigen::VectorXd& rhs,
                                  const Eigen::VectorXd& x0, double& regularisation,
                                  const std::string& who);

}  // namespace curvefem::meshing::param
