// Strong Dirichlet conditions by elimination: unknowns flagged fixed take prescribed values; the
// free block K_ff u_f = F_f − K_fd u_d is solved (SPD when K is SPD on the free unknowns).
#pragma once

#include <Eigen/Core>
#include <functional>
#include <vector>

#include "fem/problems/boundary_conditions.hpp"
#include "fem/solvers/distributed.hpp"
#include "fem/solvers/linear_solver.hpp"
#include "fem/space/function_space.hpp"

namespace curvefem::fem {

struct Constraints {
  std::vector<char> fixed;  ///< per unknown
  Eigen::VectorXd values;   ///< per unknown (used where fixed)
  int num_fixed() const;
};

/// Calls visit(dof) once per DOF lying on a flagged boundary face (a DOF shared by several faces
/// is visited once per face) whose point passes `where` (if set).
void for_each_boundary_dof(const FunctionSpace& space, const std::vector<char>& faces,
                           const PointFilter& where, const std::function<void(int dof)>& visit);

/// Full solution vector (fixed entries = prescribed values). options.near_nullspace_coordinates,
/// if set, are those of the full system (#unknowns/3 x 3); the reduced system gets the free
/// nodes' (or, where components are fixed separately, the rigid-body modes as vectors).
Eigen::VectorXd solve_constrained(const SparseMatrix& K, const Eigen::VectorXd& F,
                                  const Constraints& constraints,
                                  const LinearSolverOptions& options, LinearSolveInfo* info);
/// The same, taking K over: it is freed as soon as the reduced system is built, so the solve
/// (factorization or AMG set-up, the peak of a run) does not hold K beside K_ff.
Eigen::VectorXd solve_constrained(SparseMatrix&& K, const Eigen::VectorXd& F,
                                  const Constraints& constraints,
                                  const LinearSolverOptions& options, LinearSolveInfo* info);

/// Several MPI ranks (fem/solvers/distributed.hpp, on rank 0): the same solve with the matrix
/// assembled by rows, one rank's rows at a time (distributed::solve_by_rows), so that rank 0
/// never holds the whole matrix. `system` gives the rows of the full system (F's numbering).
/// "auto" is cg; direct is MUMPS over the ranks.
Eigen::VectorXd solve_constrained_by_rows(const distributed::RowAssembly& system,
                                          const Eigen::VectorXd& F, const Constraints& constraints,
                                          const LinearSolverOptions& options,
                                          LinearSolveInfo* info);

}  // namespace curvefem::fem
