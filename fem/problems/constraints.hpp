// Strong Dirichlet conditions by elimination: unknowns flagged fixed take prescribed values; the
// free block K_ff u_f = F_f − K_fd u_d is solved (SPD when K is SPD on the free unknowns).
#pragma once

#include <Eigen/Core>
#include <vector>

#include "fem/solvers/linear_solver.hpp"

namespace curvefem::fem {

struct Constraints {
  std::vector<char> fixed;  ///< per unknown
  Eigen::VectorXd values;   ///< per unknown (used where fixed)
  int num_fixed() const;
};

/// Full solution vector (fixed entries = prescribed values).
Eigen::VectorXd solve_constrained(const SparseMatrix& K, const Eigen::VectorXd& F,
                                  const Constraints& constraints,
                                  const LinearSolverOptions& options, LinearSolveInfo* info);

}  // namespace curvefem::fem
