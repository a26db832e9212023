// PETSc KSP CG + GAMG on one process (MPI_COMM_SELF). PETSc is initialized once, lazily, and
// finalized at exit.
#include <petscksp.h>

#include <cstdlib>
#include <mutex>
#include <sstream>

#include "fem/solvers/linear_solver.hpp"
#include "meshing/core/error.hpp"
#include "meshing/core/timer.hpp"

namespace curvefem::fem {
namespace {

void check(PetscErrorCode code, const char* what) {
  if (code != 0)
    throw SolverError(std::string("PETSc error in ") + what + " (code " +
                      std::to_string(static_cast<int>(code)) + ")");
}

void ensure_petsc() {
  static std::once_flag once;
  std::call_once(once, [] {
    PetscBool initialized = PETSC_FALSE;
    PetscInitialized(&initialized);
    if (!initialized) {
      check(PetscInitializeNoArguments(), "PetscInitialize");
      std::atexit([] { PetscFinalize(); });
    }
  });
}

PetscErrorCode record_residual(KSP, PetscInt, PetscReal norm, void* ctx) {
  static_cast<std::vector<double>*>(ctx)->push_back(static_cast<double>(norm));
  return 0;
}

}  // namespace

Eigen::VectorXd solve_petsc_cg(const SparseMatrix& A, const Eigen::VectorXd& b,
                               const LinearSolverOptions& options, LinearSolveInfo& info) {
  ensure_petsc();
  info.method = "petsc-cg-gamg";
  Stopwatch watch;
  const PetscInt n = static_cast<PetscInt>(A.rows());
  // CSR from the column-major symmetric matrix: rows of A = columns of A (symmetric).
  std::vector<PetscInt> row_ptr(A.outerIndexPtr(), A.outerIndexPtr() + n + 1);
  std::vector<PetscInt> col(A.innerIndexPtr(), A.innerIndexPtr() + A.nonZeros());
  std::vector<PetscScalar> val(A.valuePtr(), A.valuePtr() + A.nonZeros());
  Mat M;
  Vec x, rhs;
  KSP ksp;
  PC pc;
  check(
      MatCreateSeqAIJWithArrays(PETSC_COMM_SELF, n, n, row_ptr.data(), col.data(), val.data(), &M),
      "MatCreateSeqAIJWithArrays");
  if (options.block_size > 1) check(MatSetBlockSize(M, options.block_size), "MatSetBlockSize");
  check(MatSetOption(M, MAT_SYMMETRIC, PETSC_TRUE), "MatSetOption");
  check(MatSetOption(M, MAT_SPD, PETSC_TRUE), "MatSetOption");
  check(VecCreateSeq(PETSC_COMM_SELF, n, &x), "VecCreateSeq");
  check(VecDuplicate(x, &rhs), "VecDuplicate");
  PetscScalar* r;
  check(VecGetArray(rhs, &r), "VecGetArray");
  for (PetscInt i = 0; i < n; ++i) r[i] = b[i];
  check(VecRestoreArray(rhs, &r), "VecRestoreArray");
  check(KSPCreate(PETSC_COMM_SELF, &ksp), "KSPCreate");
  check(KSPSetOperators(ksp, M, M), "KSPSetOperators");
  check(KSPSetType(ksp, KSPCG), "KSPSetType");
  check(KSPGetPC(ksp, &pc), "KSPGetPC");
  check(PCSetType(pc, PCGAMG), "PCSetType");
  check(KSPSetTolerances(ksp, options.rtol, PETSC_DEFAULT, PETSC_DEFAULT, options.max_iterations),
        "KSPSetTolerances");
  check(KSPMonitorSet(ksp, record_residual, &info.residual_history, nullptr), "KSPMonitorSet");
  // PETSc's options database ($PETSC_OPTIONS, e.g. "-pc_type hypre") may override the defaults.
  check(KSPSetFromOptions(ksp), "KSPSetFromOptions");
  check(KSPSetUp(ksp), "KSPSetUp");
  info.setup_s = watch.seconds();
  watch.reset();
  check(KSPSolve(ksp, rhs, x), "KSPSolve");
  info.solve_s = watch.seconds();
  KSPConvergedReason reason;
  PetscInt its;
  KSPGetConvergedReason(ksp, &reason);
  KSPGetIterationNumber(ksp, &its);
  info.iterations = static_cast<int>(its);
  Eigen::VectorXd result(n);
  const PetscScalar* xs;
  VecGetArrayRead(x, &xs);
  for (PetscInt i = 0; i < n; ++i) result[i] = xs[i];
  VecRestoreArrayRead(x, &xs);
  KSPDestroy(&ksp);
  VecDestroy(&x);
  VecDestroy(&rhs);
  MatDestroy(&M);
  if (reason < 0) {
    std::ostringstream s;
    s << "CG + GAMG did not converge (PETSc reason " << static_cast<int>(reason) << ") after "
      << its << " iterations; residual history:";
    const auto& h = info.residual_history;
    for (std::size_t i = 0; i < h.size(); i += std::max<std::size_t>(1, h.size() / 10))
      s << ' ' << h[i];
    throw SolverError(s.str());
  }
  return result;
}

}  // namespace curvefem::fem
