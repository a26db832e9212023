// PETSc KSP CG + GAMG on one process (MPI_COMM_SELF). PETSc is initialized once, lazily, and
// finalized at exit. Near-nullspace (MatSetNearNullSpace): rigid-body modes from coordinates or
// explicit vectors; exact null space of a singular A: MatSetNullSpace.
#include <petscksp.h>

#include <Eigen/QR>
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

/// A PETSc null space spanned by the columns of V (orthonormal, #rows x m).
MatNullSpace null_space_of(const Eigen::MatrixXd& V) {
  std::vector<Vec> vecs(static_cast<std::size_t>(V.cols()));
  for (Eigen::Index k = 0; k < V.cols(); ++k) {
    check(VecCreateSeq(PETSC_COMM_SELF, static_cast<PetscInt>(V.rows()), &vecs[std::size_t(k)]),
          "VecCreateSeq");
    PetscScalar* v;
    check(VecGetArray(vecs[std::size_t(k)], &v), "VecGetArray");
    for (Eigen::Index i = 0; i < V.rows(); ++i) v[i] = V(i, k);
    check(VecRestoreArray(vecs[std::size_t(k)], &v), "VecRestoreArray");
  }
  MatNullSpace space;
  check(MatNullSpaceCreate(PETSC_COMM_SELF, PETSC_FALSE, static_cast<PetscInt>(V.cols()),
                           vecs.data(), &space),
        "MatNullSpaceCreate");
  for (Vec& v : vecs) VecDestroy(&v);
  return space;
}

/// The six rigid-body modes of the nodes at `coordinates` (#nodes x 3, unknowns interleaved).
MatNullSpace rigid_body_modes(const Eigen::MatrixXd& coordinates) {
  Vec xyz;
  check(VecCreateSeq(PETSC_COMM_SELF, static_cast<PetscInt>(3 * coordinates.rows()), &xyz),
        "VecCreateSeq");
  check(VecSetBlockSize(xyz, 3), "VecSetBlockSize");
  PetscScalar* v;
  check(VecGetArray(xyz, &v), "VecGetArray");
  for (Eigen::Index i = 0; i < coordinates.rows(); ++i)
    for (int j = 0; j < 3; ++j) v[3 * i + j] = coordinates(i, j);
  check(VecRestoreArray(xyz, &v), "VecRestoreArray");
  MatNullSpace space;
  check(MatNullSpaceCreateRigidBody(xyz, &space), "MatNullSpaceCreateRigidBody");
  VecDestroy(&xyz);
  return space;
}

PetscErrorCode record_residual(KSP, PetscInt, PetscReal norm, void* ctx) {
  static_cast<std::vector<double>*>(ctx)->push_back(static_cast<double>(norm));
  return 0;
}

}  // namespace

Eigen::VectorXd solve_petsc_cg(const SparseMatrix& A, const Eigen::VectorXd& b,
                               const LinearSolverOptions& options,
                               const Eigen::MatrixXd& null_space, LinearSolveInfo& info) {
  ensure_petsc();
  info.method = "petsc-cg-gamg";
  Stopwatch watch;
  const PetscInt n = static_cast<PetscInt>(A.rows());
  const Eigen::MatrixXd& coordinates = options.near_nullspace_coordinates;
  const bool use_coordinates = options.use_near_nullspace && coordinates.size() > 0;
  if (use_coordinates &&
      (options.block_size != 3 || coordinates.cols() != 3 || 3 * coordinates.rows() != A.rows()))
    throw InputError("near-nullspace: " + std::to_string(coordinates.rows()) + "x" +
                     std::to_string(coordinates.cols()) + " coordinates for " +
                     std::to_string(A.rows()) + " unknowns in blocks of " +
                     std::to_string(options.block_size) + " (expected #rows/3 x 3, blocks of 3)");
  const bool use_vectors =
      options.use_near_nullspace && !use_coordinates && options.near_nullspace_vectors.size() > 0;
  if (use_vectors && options.near_nullspace_vectors.rows() != A.rows())
    throw InputError("near-nullspace: " + std::to_string(options.near_nullspace_vectors.rows()) +
                     " rows of vectors for " + std::to_string(A.rows()) + " unknowns");
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
  if (null_space.cols() == 0) check(MatSetOption(M, MAT_SPD, PETSC_TRUE), "MatSetOption");
  info.near_nullspace = "default";
  if (use_coordinates || use_vectors) {
    MatNullSpace near;
    if (use_coordinates) {
      near = rigid_body_modes(coordinates);
      info.near_nullspace = "rigid-body modes";
    } else {
      const Eigen::HouseholderQR<Eigen::MatrixXd> qr(options.near_nullspace_vectors);
      near = null_space_of(qr.householderQ() *
                           Eigen::MatrixXd::Identity(n, options.near_nullspace_vectors.cols()));
      info.near_nullspace = "vectors";
    }
    check(MatSetNearNullSpace(M, near), "MatSetNearNullSpace");
    MatNullSpaceDestroy(&near);
  }
  if (null_space.cols() > 0) {
    MatNullSpace kernel = null_space_of(null_space);
    check(MatSetNullSpace(M, kernel), "MatSetNullSpace");
    MatNullSpaceDestroy(&kernel);
  }
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
