// CHOLMOD supernodal Cholesky through Eigen's CholmodSupport module.
#include <Eigen/CholmodSupport>

#include "fem/solvers/linear_solver.hpp"
#include "meshing/core/error.hpp"
#include "meshing/core/timer.hpp"

namespace curvefem::fem {

Eigen::VectorXd solve_cholmod(const SparseMatrix& A, const Eigen::VectorXd& b,
                              LinearSolveInfo& info) {
  info.method = "cholmod-supernodal";
  Stopwatch watch;
  Eigen::CholmodSupernodalLLT<SparseMatrix, Eigen::Lower> llt;
  llt.compute(A);
  info.setup_s = watch.seconds();
  if (llt.info() != Eigen::Success)
    throw SolverError(
        "CHOLMOD factorization failed: the matrix is not positive definite "
        "(inverted element, missing Dirichlet condition or a floating part?)");
  watch.reset();
  Eigen::VectorXd x = llt.solve(b);
  info.solve_s = watch.seconds();
  if (llt.info() != Eigen::Success) throw SolverError("CHOLMOD solve failed");
  return x;
}

}  // namespace curvefem::fem
