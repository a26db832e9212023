#include "fem/solvers/linear_solver.hpp"

#include "meshing/core/error.hpp"
#include "meshing/core/log.hpp"

namespace curvefem::fem {

Eigen::VectorXd solve_spd(const SparseMatrix& A, const Eigen::VectorXd& b,
                          const LinearSolverOptions& options, LinearSolveInfo* info) {
  if (A.rows() != A.cols() || A.rows() != b.size())
    throw InputError("linear system: matrix " + std::to_string(A.rows()) + "x" +
                     std::to_string(A.cols()) + ", right-hand side " + std::to_string(b.size()));
  LinearSolveInfo local;
  LinearSolveInfo& out = info ? *info : local;
  out = {};
  if (A.rows() == 0) return Eigen::VectorXd();
  std::string type = options.type;
  if (type == "auto") type = A.rows() <= options.auto_direct_max_dofs ? "direct" : "cg";
  Eigen::VectorXd x;
  if (type == "direct")
    x = solve_cholmod(A, b, out);
  else if (type == "cg")
    x = solve_petsc_cg(A, b, options, out);
  else
    throw InputError("unknown solver type '" + options.type + "' (direct, cg or auto)");
  const double bn = b.norm();
  out.relative_residual = (b - A * x).norm() / (bn > 0 ? bn : 1.0);
  log::info("linear solve (", out.method, "): ", A.rows(), " unknowns, ", out.iterations,
            " iterations, relative residual ", out.relative_residual, ", setup ", out.setup_s,
            " s, solve ", out.solve_s, " s");
  return x;
}

}  // namespace curvefem::fem
