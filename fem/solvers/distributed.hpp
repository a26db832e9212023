// Distributed linear solves under an MPI launcher (`mpirun -n N curvefem run`, N > 1; issue 24).
//
// Model: rank 0 runs the whole pipeline (meshing, discretization, assembly, Dirichlet elimination,
// errors, output); the other ranks wait in `serve()` for rank 0's requests. A linear solve on
// rank 0 (solve_spd) becomes collective: rank 0 partitions the unknowns' graph (nodes = blocks of
// block_size rows in groups of consecutive ones, at most 2^17 groups; edges = the matrix
// pattern) with PETSc's MatPartitioning "ptscotch" (a
// contiguous split with a warning when that fails; each rank's share of the rows from
// LinearSolverOptions::rank_balance: by default rank 0, which holds the rest of the run, gets
// fewer, see memory_balanced_shares), renumbers the rows so that every rank owns a
// contiguous range, sends each rank its rows (CSR), its slice of the right-hand side, of the
// near-nullspace coordinates / vectors and of the kernel; every rank builds its part of a
// MATMPIAIJ and the same KSP as the one-process engine (CG + GAMG | hypre | ML, rigid-body modes
// from its owned nodes' coordinates; `direct`: MUMPS Cholesky), the solution is gathered on rank 0
// (VecScatterCreateToZero) and put back in the caller's numbering.
// Distributed assembly (solve_by_rows; Poisson, linear elasticity and Neo-Hookean's tangents with
// Dirichlet conditions):
// the matrix is never whole on rank 0. The partition is computed first, from the cells' node
// graph; then each rank's rows are assembled (by rank 0, from the cells touching that rank's
// nodes), reduced by the Dirichlet values and sent, one rank at a time, so rank 0 holds one
// rank's rows at once, like the others. The element matrices are still computed by rank 0 alone
// (the coefficients are functions of the case, which only rank 0 holds). Everything else before
// and after the solve stays on rank 0. The matrix path (solve) remains for the singular systems
// (pure Neumann, tractions only): there, when the caller hands the matrix over
// (solve_spd(SparseMatrix&&)), rank 0 keeps only its own rows through the solve, but its peak
// is at least the whole assembly's.
//
// Protocol: every rank calls start(); ranks != 0 call serve(), which returns when rank 0 calls
// release_workers(); then every rank calls finish(). Between the two, rank 0 alone runs library
// code; solve_spd and peak_rss_mb_per_rank are collective through serve(). PETSc and MPI headers
// stay in distributed_solver.cpp.
#pragma once

#include <Eigen/Core>
#include <functional>
#include <string>
#include <vector>

#include "fem/solvers/linear_solver.hpp"

namespace curvefem::fem::distributed {

/// Initializes MPI through PETSc (PetscInitializeNoArguments; $PETSC_OPTIONS is honoured) and
/// turns the distributed mode on when the world has more than one rank. Returns this rank.
int start();
/// Finalizes PETSc (and MPI). After release_workers() on rank 0, after serve() on the others.
void finish();

/// True between start() and finish() with more than one rank: solve_spd on rank 0 is collective.
bool active();
int rank();  ///< 0 without start()
int size();  ///< 1 without start()

/// Ranks != 0: answers rank 0's requests until release_workers(). Polls (sleeping 2 ms) instead
/// of spinning, so that the ranks sharing cores with rank 0's threads leave them free.
void serve();
/// Rank 0: ends serve() on every other rank.
void release_workers();
/// Rank 0, collective: aborts every rank (MPI_Abort) with `code`; for a failure that leaves the
/// protocol in an unknown state.
[[noreturn]] void abort(int code);

/// Rank 0, collective: the peak resident set size (getrusage ru_maxrss, MiB) of every rank.
std::vector<double> peak_rss_mb_per_rank();

/// Rank 0, collective: solve A x = b (both triangles stored, SPD, or semi-definite with an
/// orthonormal kernel basis `null_space`, #rows x m) over all ranks. `direct`: MUMPS Cholesky
/// (kernel: the caller pins unknowns first); otherwise CG with options.preconditioner. Fills
/// info.method, iterations, residual_history, near_nullspace, setup_s, solve_s, ranks,
/// rows_per_rank, partitioner. Throws SolverError when CG does not converge.
Eigen::VectorXd solve(const SparseMatrix& A, const Eigen::VectorXd& b,
                      const LinearSolverOptions& options, bool direct,
                      const Eigen::MatrixXd& null_space, LinearSolveInfo& info);
/// The same, freeing A (*owned, which must be A) once every rank's rows are built and sent, so
/// that rank 0 holds only its own rows through the preconditioner's set-up and the solve; also
/// fills info.relative_residual from the distributed matrix (MatMult on the ranks).
Eigen::VectorXd solve(const SparseMatrix& A, const Eigen::VectorXd& b,
                      const LinearSolverOptions& options, bool direct,
                      const Eigen::MatrixXd& null_space, LinearSolveInfo& info,
                      SparseMatrix* owned);

/// A symmetric system that rank 0 assembles by rows (distributed assembly).
struct RowAssembly {
  /// The graph the partition splits: `nodes` nodes, each owning `block_size` consecutive
  /// unknowns of the full system (node d: unknowns b·d .. b·d+b−1); nodes sharing a cell of
  /// `cell_dofs` are neighbours.
  const Eigen::MatrixXi* cell_dofs = nullptr;
  int nodes = 0;
  int block_size = 1;
  /// The rows of the unknowns of the nodes flagged (size `nodes`), every column, in the full
  /// numbering, as a compressed column-major matrix whose column u holds row u (the matrix is
  /// symmetric); the columns of the other unknowns may be empty.
  std::function<SparseMatrix(const std::vector<char>& nodes)> rows;
};

/// Rank 0, collective: solves the reduced system K_ff x = F_f − K_fd v_d over all ranks, where
/// reduced[u] is the index of full unknown u among the m free ones (-1: fixed at values[u]) and
/// `options` are the reduced system's (block size, near-nullspace in the reduced numbering; no
/// null space). Each rank's rows are assembled by system.rows for the nodes it owns, reduced and
/// sent before the next rank's are assembled. Returns x in the reduced numbering; fills info as
/// solve() does. Throws SolverError when CG does not converge.
Eigen::VectorXd solve_by_rows(const RowAssembly& system, const Eigen::VectorXd& F,
                              const Eigen::VectorXd& values, const std::vector<int>& reduced, int m,
                              const LinearSolverOptions& options, bool direct,
                              LinearSolveInfo& info);

/// Shares of the rows per rank (summing to 1) that even out the ranks' peak memory: rank p holds
/// `heap_mb[p]` before the solve and the solver adds about `solve_mb` × its share, so the shares
/// fill every rank up to one common level (water-filling), each at least `min_share`. Equal
/// shares when solve_mb is not positive. Pure; unit-tested.
std::vector<double> memory_balanced_shares(const std::vector<double>& heap_mb, double solve_mb,
                                           double min_share);

/// Renumbering of nodes by owning rank, keeping the order within a rank: new_of[old] and the
/// first new index of each rank (size ranks + 1). Pure; unit-tested.
struct Renumbering {
  std::vector<int> new_of, old_of, offsets;
};
Renumbering renumber_by_owner(const std::vector<int>& owner, int ranks);

}  // namespace curvefem::fem::distributed
