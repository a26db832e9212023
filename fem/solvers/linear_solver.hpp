// Solves symmetric positive definite systems A x = b from the FEM assemblies.
//
// type "direct": CHOLMOD supernodal Cholesky (SuiteSparse, on OpenBLAS).
// type "cg":     PETSc KSP CG preconditioned by algebraic multigrid, relative tolerance `rtol`
//                on the preconditioned residual, at most `max_iterations`. `preconditioner`:
//                "gamg" (PETSc's smoothed aggregation, the default; takes the near-nullspace),
//                "hypre" (hypre BoomerAMG, classical AMG; scalar, no near-nullspace) or "ml"
//                (Trilinos ML smoothed aggregation; takes the near-nullspace too).
// type "auto":   direct up to `auto_direct_max_dofs` unknowns, cg above (the pipeline sets the
//                limit per physics and degree from benchmarks/results/solver_crossover.md).
// Near-nullspace (cg): GAMG builds its coarse spaces from the near-nullspace of A. The default is
// the constant vector per block; elasticity needs the six rigid-body modes, given either as the
// nodes' coordinates (block_size 3, MatNullSpaceCreateRigidBody) or as explicit vectors.
// Singular A (pure Neumann problems): `null_space` spans ker A (#rows x m). b is first projected
// onto range A (b - Q Q^T b, Q an orthonormal basis of the null space; a no-op for compatible
// data); direct pins the m unknowns that a column-pivoted QR of null_space^T picks (u = 0 there: an
// exact regularization, the pinned system is SPD and its solution solves A x = b); cg solves the
// singular consistent system with the null space removed from the Krylov space (MatSetNullSpace).
// Either way x is one solution: the caller picks the one it wants by removing its null-space part.
// A failed factorization (not SPD) or non-convergence throws SolverError carrying the residual
// history. Engines' headers stay in the .cpp files.
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <memory>
#include <string>
#include <vector>

namespace curvefem::fem {

/// A CHOLMOD factorization — or, for CG, the PETSc KSP with its GAMG hierarchy — kept between
/// solves (load cases of one run): the next matrix handed to the same engine with the cache is
/// checked against the kept one bit for bit (sizes, pattern and values); the factor / set-up is
/// reused when they are identical and recomputed (and kept) otherwise. A problem may also keep
/// its assembled operator here (linear elasticity and Poisson: the stiffness before boundary
/// terms), so that the solves sharing the cache assemble it once. Not
/// thread-safe: one cache per sequence of solves.
class FactorizationCache {
 public:
  FactorizationCache();
  ~FactorizationCache();
  FactorizationCache(const FactorizationCache&) = delete;
  FactorizationCache& operator=(const FactorizationCache&) = delete;
  int factorizations() const;   ///< how many times a matrix was factorized
  int reuses() const;           ///< how many solves reused the kept factor
  int assemblies() const;       ///< how many times a problem assembled the operator it keeps here
  int assembly_reuses() const;  ///< how many solves took the kept operator instead
  struct Impl;
  Impl& impl() { return *m_impl; }

 private:
  std::unique_ptr<Impl> m_impl;
};

/// direct: CHOLMOD (MUMPS over several ranks); cg: PETSc CG with an AMG; automatic: direct up
/// to auto_direct_max_dofs unknowns on one process, else cg.
enum class SolverType { automatic, direct, cg };
/// The AMG of cg.
enum class Preconditioner { gamg, hypre, ml };
/// GAMG over several MPI ranks: PETSc's algorithm for the parallel Galerkin products of its
/// set-up (-matptap_via; fem/solvers/distributed.hpp). allatonce: a fraction of the memory per
/// rank, several times the set-up time of scalable (PETSc's default). automatic: allatonce with
/// an explicit near-nullspace (elasticity's rigid-body modes, where scalable's memory per rank is
/// the one-process set-up's), scalable otherwise (scalar problems: 3% more memory, 0.6x the
/// set-up time; benchmarks/results/mpi.md).
enum class ParallelPtap { automatic, allatonce, scalable };
/// How a distributed solve splits the rows between the ranks (fem/solvers/distributed.hpp).
/// memory: so that every rank's peak memory is about the same — rank 0 also holds the mesh, the
/// space and the run's other data, so it gets fewer rows (the shares from each rank's heap in use
/// when the solve starts and an estimate of the solver's memory per matrix entry); rows: equal
/// rows per rank (PT-Scotch's default balance).
enum class RankBalance { memory, rows };
/// Spellings as in case files and reports: "auto" | "direct" | "cg", "gamg" | "hypre" | "ml".
std::string to_string(SolverType type);
std::string to_string(Preconditioner preconditioner);
/// From those spellings; InputError naming the allowed ones otherwise.
SolverType solver_type_from(const std::string& text);
Preconditioner preconditioner_from(const std::string& text);

struct LinearSolverOptions {
  SolverType type = SolverType::automatic;
  double rtol = 1e-10;
  int max_iterations = 5000;
  int auto_direct_max_dofs = 200000;
  Preconditioner preconditioner = Preconditioner::gamg;  ///< cg
  ParallelPtap parallel_ptap = ParallelPtap::automatic;  ///< cg + gamg over several ranks
  RankBalance rank_balance = RankBalance::memory;        ///< several ranks
  int block_size = 1;  ///< unknowns per node (3 for elasticity): helps AMG
  /// cg, block_size 3: coordinates of the node of each block of 3 consecutive rows (#rows/3 x 3,
  /// row r = the node of unknowns 3r, 3r+1, 3r+2): GAMG's near-nullspace = the rigid-body modes.
  Eigen::MatrixXd near_nullspace_coordinates;
  /// cg, when the rows are not in blocks (components fixed separately): the near-nullspace as
  /// explicit vectors (#rows x m, any scaling; orthonormalized here). Ignored with coordinates.
  Eigen::MatrixXd near_nullspace_vectors;
  /// false: GAMG's default near-nullspace (constants per block), to measure what the modes buy.
  bool use_near_nullspace = true;
  /// Basis of ker A (#rows x m) for a singular positive semi-definite A; empty: A is SPD.
  Eigen::MatrixXd null_space;
  /// direct: keep / reuse the factorization across solves of an identical matrix (may be null).
  std::shared_ptr<FactorizationCache> factorization_cache;
};

struct LinearSolveInfo {
  std::string method;  ///< "cholmod-supernodal" | "petsc-cg-gamg" | "petsc-cg-hypre" |
                       ///< "petsc-cg-ml" | "petsc-mumps-cholesky" (several ranks, direct)
  int iterations = 0;  ///< 0 for direct
  double relative_residual = 0.0;  ///< ‖b − A x‖ / ‖b‖, measured after the solve
  double setup_s = 0.0, solve_s = 0.0;
  std::vector<double> residual_history;  ///< cg: preconditioned residual norms per iteration
  /// cg: "rigid-body modes" (from coordinates), "vectors" (explicit) or "default" (GAMG's own)
  std::string near_nullspace;
  int null_space_dim = 0;             ///< dimension of the kernel handled (0: A was SPD)
  bool reused_factorization = false;  ///< direct: the factor of an identical earlier matrix
  // Distributed solves (fem/solvers/distributed.hpp; 1 rank otherwise):
  int ranks = 1;
  std::vector<long long> rows_per_rank;  ///< rows owned by each rank (empty on one rank)
  /// RankBalance::memory: the share of the rows asked of each rank, and the heap in use (MiB) on
  /// each rank it was computed from; empty with RankBalance::rows or one rank.
  std::vector<double> rank_shares, rank_heap_mb;
  std::string partitioner;                       ///< "ptscotch" | "contiguous" (several ranks)
  std::string parallel_ptap;                     ///< several ranks, GAMG: "allatonce" | "scalable"
  double partition_s = 0.0, distribute_s = 0.0;  ///< parts of setup_s
  /// Distributed assembly (distributed::solve_by_rows): the matrix was never whole on rank 0,
  /// each rank's rows were assembled in turn; assembly_s (part of distribute_s) is their time.
  bool assembled_by_rows = false;
  double assembly_s = 0.0;
};

using SparseMatrix = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;

// Eigen 3.4's SparseMatrix has no move constructor and no move assignment: `B =
// std::move(A)` and `SparseMatrix B = std::move(A)` copy A, and `A = SparseMatrix()` keeps A's
// storage (its clear() keeps the capacity). These two do what a move and a release should.
/// Moves A's storage into the result (A left empty); no copy.
inline SparseMatrix take(SparseMatrix& A) {
  SparseMatrix out;
  out.swap(A);
  return out;  // NRVO; GCC elides it, and at worst this is the copy a std::move would be
}
/// Frees A's storage.
inline void release(SparseMatrix& A) { SparseMatrix().swap(A); }

/// Limits the threads of the BLAS the solvers call (CHOLMOD's supernodal factorization, PETSc's
/// dense kernels) to `threads` (>= 1), so that a run's thread count holds for BLAS too: Debian's
/// OpenBLAS starts one thread per core, and its idle threads spin (sched_yield) beside a
/// one-thread run. Acts through openblas_set_num_threads when the BLAS loaded is OpenBLAS
/// (looked up at run time: the BLAS is a Debian alternative); returns whether it did.
bool set_blas_threads(int threads);
/// The BLAS's thread count where it can be queried (OpenBLAS), else 0.
int blas_threads();

/// A must be symmetric (both triangles stored), positive definite, or semi-definite with the
/// kernel given in options.null_space. Throws InputError for size mismatch.
Eigen::VectorXd solve_spd(const SparseMatrix& A, const Eigen::VectorXd& b,
                          const LinearSolverOptions& options, LinearSolveInfo* info = nullptr);
/// The same, given A to keep or free: on several MPI ranks (fem/solvers/distributed.hpp) rank 0
/// frees A once every rank has its rows, before the preconditioner is set up, and the relative
/// residual is PETSc's on the distributed matrix; elsewhere as above.
Eigen::VectorXd solve_spd(SparseMatrix&& A, const Eigen::VectorXd& b,
                          const LinearSolverOptions& options, LinearSolveInfo* info = nullptr);

// Engines (linear_solver_cholmod.cpp, linear_solver_petsc.cpp).
Eigen::VectorXd solve_cholmod(const SparseMatrix& A, const Eigen::VectorXd& b,
                              LinearSolveInfo& info, FactorizationCache* cache = nullptr);
/// null_space: an orthonormal basis of ker A (#rows x m) or empty. With a cache, a KSP set up
/// for an identical matrix (bit for bit) with the same null space, near-nullspace, tolerance,
/// iteration limit and block size is reused, GAMG's hierarchy included (info.reused_factorization).
Eigen::VectorXd solve_petsc_cg(const SparseMatrix& A, const Eigen::VectorXd& b,
                               const LinearSolverOptions& options,
                               const Eigen::MatrixXd& null_space, LinearSolveInfo& info,
                               FactorizationCache* cache = nullptr);

// Shared by the engines: same sizes, pattern and values, bit for bit (both compressed); the
// cache's PETSc slot and counters.
bool identical_matrices(const SparseMatrix& a, const SparseMatrix& b);
std::shared_ptr<void>& petsc_cache_slot(FactorizationCache& cache);
void count_cache_use(FactorizationCache& cache, bool reused);
/// What a problem keeps in a FactorizationCache: its assembled operator, in a type of its own
/// derived from this (read back with dynamic_pointer_cast, so another problem's is never
/// mistaken for it). The slot and its counters:
struct KeptOperator {
  virtual ~KeptOperator() = default;
};
std::shared_ptr<KeptOperator>& assembly_cache_slot(FactorizationCache& cache);
void count_assembly(FactorizationCache& cache, bool reused);

}  // namespace curvefem::fem
