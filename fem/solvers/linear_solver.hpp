// Solves symmetric positive definite systems A x = b from the FEM assemblies.
//
// type "direct": CHOLMOD supernodal Cholesky (SuiteSparse, on OpenBLAS).
// type "cg":     PETSc KSP CG preconditioned by algebraic multigrid (GAMG), relative tolerance
//                `rtol` on the preconditioned residual, at most `max_iterations`.
// type "auto":   direct up to `auto_direct_max_dofs` unknowns, cg above.
// A failed factorization (not SPD) or non-convergence throws SolverError carrying the residual
// history. Engines' headers stay in the .cpp files.
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <string>
#include <vector>

namespace curvefem::fem {

struct LinearSolverOptions {
  std::string type = "auto";  ///< direct | cg | auto
  double rtol = 1e-10;
  int max_iterations = 5000;
  int auto_direct_max_dofs = 200000;
  int block_size = 1;  ///< unknowns per node (3 for elasticity): helps AMG
};

struct LinearSolveInfo {
  std::string method;              ///< "cholmod-supernodal" | "petsc-cg-gamg"
  int iterations = 0;              ///< 0 for direct
  double relative_residual = 0.0;  ///< ‖b − A x‖ / ‖b‖, measured after the solve
  double setup_s = 0.0, solve_s = 0.0;
  std::vector<double> residual_history;  ///< cg: preconditioned residual norms per iteration
};

using SparseMatrix = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;

/// A must be symmetric (both triangles stored). Throws InputError for size mismatch.
Eigen::VectorXd solve_spd(const SparseMatrix& A, const Eigen::VectorXd& b,
                          const LinearSolverOptions& options, LinearSolveInfo* info = nullptr);

// Engines (linear_solver_cholmod.cpp, linear_solver_petsc.cpp).
Eigen::VectorXd solve_cholmod(const SparseMatrix& A, const Eigen::VectorXd& b,
                              LinearSolveInfo& info);
Eigen::VectorXd solve_petsc_cg(const SparseMatrix& A, const Eigen::VectorXd& b,
                               const LinearSolverOptions& options, LinearSolveInfo& info);

}  // namespace curvefem::fem
