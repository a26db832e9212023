// PETSc KSP CG + GAMG on one process (MPI_COMM_SELF). PETSc is initialized once, lazily, and
// finalized at exit. Near-nullspace (MatSetNearNullSpace): rigid-body modes from coordinates or
// explicit vectors; exact null space of a singular A: MatSetNullSpace.
#include <petscksp.h>

#include <Eigen/QR>
#include <cstdlib>
#include <mutex>
#include <sstream>
#include <type_traits>

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

// Whether an MPI launcher (mpirun / mpiexec of OpenMPI or MPICH) started this process.
bool launched_by_mpi() {
  for (const char* name : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_RANK"})
    if (std::getenv(name)) return true;
  return false;
}

void ensure_petsc() {
  static std::once_flag once;
  std::call_once(once, [] {
    PetscBool initialized = PETSC_FALSE;
    PetscInitialized(&initialized);
    if (!initialized) {
      // Not started by a launcher: MPI as an isolated singleton, so that OpenMPI does not start
      // its orted daemon, whose start-up and polling cost 0.6-1.1 s of the solve stage of a 5 s
      // run here (P2 Poisson, 105k DOFs, 1 thread: solve 2.3-2.8 s -> 1.7 s). A value the user
      // set is kept.
      if (!launched_by_mpi()) setenv("OMPI_MCA_ess_singleton_isolated", "1", 0);
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

namespace {

/// A KSP (CG + GAMG) set up for one matrix, with what it was set up for: load cases with the same
/// matrix and options reuse it (FactorizationCache), GAMG's hierarchy included.
struct KspState {
  SparseMatrix matrix;  // cached states only: a compressed copy (the key, with the options below)
  Eigen::MatrixXd null_space, coordinates, vectors;
  double rtol = 0;
  int max_iterations = 0, block_size = 1;
  std::string near_nullspace;
  Preconditioner preconditioner = Preconditioner::gamg;
  // MatCreateSeqAIJWithArrays keeps pointers to these (or to matrix's, or the caller's, arrays).
  std::vector<PetscInt> row_ptr, col;
  std::vector<PetscScalar> val;
  Mat M = nullptr;
  KSP ksp = nullptr;
  KspState() = default;
  KspState(const KspState&) = delete;
  KspState& operator=(const KspState&) = delete;
  ~KspState() {
    if (ksp) KSPDestroy(&ksp);
    if (M) MatDestroy(&M);
  }
  bool serves(const SparseMatrix& A, const Eigen::MatrixXd& ns, const Eigen::MatrixXd& xyz,
              const Eigen::MatrixXd& vec, const LinearSolverOptions& o) const {
    auto same = [](const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
      return a.rows() == b.rows() && a.cols() == b.cols() && a == b;
    };
    return rtol == o.rtol && max_iterations == o.max_iterations && block_size == o.block_size &&
           preconditioner == o.preconditioner && same(null_space, ns) && same(coordinates, xyz) &&
           same(vectors, vec) && identical_matrices(matrix, A);
  }
};

// `keep`: the state goes into a cache and outlives `compressed`, so it holds a copy (the cache
// key, whose arrays PETSc then uses); otherwise PETSc uses `compressed`'s own arrays, which outlive
// the state (no copy of the matrix at all).
std::shared_ptr<KspState> set_up(const SparseMatrix& compressed, const LinearSolverOptions& options,
                                 const Eigen::MatrixXd& coordinates, const Eigen::MatrixXd& vectors,
                                 const Eigen::MatrixXd& null_space, bool keep) {
  auto st = std::make_shared<KspState>();
  if (keep) st->matrix = compressed;
  st->null_space = null_space;
  st->coordinates = coordinates;
  st->vectors = vectors;
  st->rtol = options.rtol;
  st->max_iterations = options.max_iterations;
  st->block_size = options.block_size;
  st->preconditioner = options.preconditioner;
  const SparseMatrix& A = keep ? st->matrix : compressed;
  const PetscInt n = static_cast<PetscInt>(A.rows());
  // CSR from the column-major symmetric matrix: rows of A = columns of A (symmetric). Where
  // PETSc's index and scalar types are Eigen's, PETSc uses the kept copy's arrays (it does not
  // write to them: the preconditioners build their own matrices); otherwise converted copies.
  if constexpr (std::is_same_v<PetscInt, int> && std::is_same_v<PetscScalar, double>) {
    SparseMatrix& arrays = const_cast<SparseMatrix&>(A);  // PETSc does not write to them
    check(MatCreateSeqAIJWithArrays(PETSC_COMM_SELF, n, n, arrays.outerIndexPtr(),
                                    arrays.innerIndexPtr(), arrays.valuePtr(), &st->M),
          "MatCreateSeqAIJWithArrays");
  } else {
    st->row_ptr.assign(A.outerIndexPtr(), A.outerIndexPtr() + n + 1);
    st->col.assign(A.innerIndexPtr(), A.innerIndexPtr() + A.nonZeros());
    st->val.assign(A.valuePtr(), A.valuePtr() + A.nonZeros());
    check(MatCreateSeqAIJWithArrays(PETSC_COMM_SELF, n, n, st->row_ptr.data(), st->col.data(),
                                    st->val.data(), &st->M),
          "MatCreateSeqAIJWithArrays");
  }
  Mat M = st->M;
  if (options.block_size > 1) check(MatSetBlockSize(M, options.block_size), "MatSetBlockSize");
  check(MatSetOption(M, MAT_SYMMETRIC, PETSC_TRUE), "MatSetOption");
  if (null_space.cols() == 0) check(MatSetOption(M, MAT_SPD, PETSC_TRUE), "MatSetOption");
  st->near_nullspace = "default";
  if (coordinates.size() > 0 || vectors.size() > 0) {
    MatNullSpace near;
    if (coordinates.size() > 0) {
      near = rigid_body_modes(coordinates);
      st->near_nullspace = "rigid-body modes";
    } else {
      const Eigen::HouseholderQR<Eigen::MatrixXd> qr(vectors);
      near = null_space_of(qr.householderQ() * Eigen::MatrixXd::Identity(n, vectors.cols()));
      st->near_nullspace = "vectors";
    }
    check(MatSetNearNullSpace(M, near), "MatSetNearNullSpace");
    MatNullSpaceDestroy(&near);
  }
  if (null_space.cols() > 0) {
    MatNullSpace kernel = null_space_of(null_space);
    check(MatSetNullSpace(M, kernel), "MatSetNullSpace");
    MatNullSpaceDestroy(&kernel);
  }
  PC pc;
  check(KSPCreate(PETSC_COMM_SELF, &st->ksp), "KSPCreate");
  check(KSPSetOperators(st->ksp, M, M), "KSPSetOperators");
  check(KSPSetType(st->ksp, KSPCG), "KSPSetType");
  check(KSPGetPC(st->ksp, &pc), "KSPGetPC");
  if (options.preconditioner == Preconditioner::hypre) {
    check(PCSetType(pc, PCHYPRE), "PCSetType");
    check(PCHYPRESetType(pc, "boomeramg"), "PCHYPRESetType");
  } else if (options.preconditioner == Preconditioner::ml) {
    check(PCSetType(pc, PCML), "PCSetType");
  } else {
    check(PCSetType(pc, PCGAMG), "PCSetType");
  }
  check(
      KSPSetTolerances(st->ksp, options.rtol, PETSC_DEFAULT, PETSC_DEFAULT, options.max_iterations),
      "KSPSetTolerances");
  // PETSc's options database ($PETSC_OPTIONS, e.g. "-pc_type hypre") may override the defaults.
  check(KSPSetFromOptions(st->ksp), "KSPSetFromOptions");
  check(KSPSetUp(st->ksp), "KSPSetUp");
  return st;
}

}  // namespace

Eigen::VectorXd solve_petsc_cg(const SparseMatrix& A, const Eigen::VectorXd& b,
                               const LinearSolverOptions& options,
                               const Eigen::MatrixXd& null_space, LinearSolveInfo& info,
                               FactorizationCache* cache) {
  ensure_petsc();
  info.method = "petsc-cg-" + to_string(options.preconditioner);
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
  const Eigen::MatrixXd xyz = use_coordinates ? coordinates : Eigen::MatrixXd();
  const Eigen::MatrixXd vec = use_vectors ? options.near_nullspace_vectors : Eigen::MatrixXd();
  // The key and the solver's copy need compressed storage; copied here only if A is not.
  SparseMatrix copy;
  if (!A.isCompressed()) {
    copy = A;
    copy.makeCompressed();
  }
  const SparseMatrix& compressed = A.isCompressed() ? A : copy;
  std::shared_ptr<KspState> st;
  if (cache) {
    auto& slot = petsc_cache_slot(*cache);
    auto kept = std::static_pointer_cast<KspState>(slot);
    if (kept && kept->serves(compressed, null_space, xyz, vec, options)) {
      st = kept;
      info.reused_factorization = true;
    } else {
      slot.reset();
      st = set_up(compressed, options, xyz, vec, null_space, true);
      slot = st;
    }
    count_cache_use(*cache, info.reused_factorization);
  } else {
    st = set_up(compressed, options, xyz, vec, null_space, false);
  }
  info.near_nullspace = st->near_nullspace;
  info.setup_s = watch.seconds();
  watch.reset();
  Vec x, rhs;
  check(VecCreateSeq(PETSC_COMM_SELF, n, &x), "VecCreateSeq");
  check(VecDuplicate(x, &rhs), "VecDuplicate");
  PetscScalar* r;
  check(VecGetArray(rhs, &r), "VecGetArray");
  for (PetscInt i = 0; i < n; ++i) r[i] = b[i];
  check(VecRestoreArray(rhs, &r), "VecRestoreArray");
  check(KSPMonitorCancel(st->ksp), "KSPMonitorCancel");
  check(KSPMonitorSet(st->ksp, record_residual, &info.residual_history, nullptr), "KSPMonitorSet");
  check(KSPSolve(st->ksp, rhs, x), "KSPSolve");
  check(KSPMonitorCancel(st->ksp), "KSPMonitorCancel");
  info.solve_s = watch.seconds();
  KSPConvergedReason reason;
  PetscInt its;
  KSPGetConvergedReason(st->ksp, &reason);
  KSPGetIterationNumber(st->ksp, &its);
  info.iterations = static_cast<int>(its);
  Eigen::VectorXd result(n);
  const PetscScalar* xs;
  VecGetArrayRead(x, &xs);
  for (PetscInt i = 0; i < n; ++i) result[i] = xs[i];
  VecRestoreArrayRead(x, &xs);
  VecDestroy(&x);
  VecDestroy(&rhs);
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
