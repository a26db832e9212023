// Distributed linear solves under an MPI launcher (`mpirun -n N curvefem run`, N > 1; issue 24).
//
// Model: rank 0 runs the whole pipeline (meshing, discretization, assembly, Dirichlet elimination,
// errors, output); the other ranks wait in `serve()` for rank 0's requests. A linear solve on
// rank 0 (solve_spd) becomes collective: rank 0 partitions the unknowns' graph (nodes = blocks of
// block_size rows in groups of consecutive ones, at most 2^17 groups; edges = the matrix
// pattern) with PETSc's MatPartitioning "ptscotch" (a
// contiguous split with a warning when that fails), renumbers the rows so that every rank owns a
// contiguous range, sends each rank its rows (CSR), its slice of the right-hand side, of the
// near-nullspace coordinates / vectors and of the kernel; every rank builds its part of a
// MATMPIAIJ and the same KSP as the one-process engine (CG + GAMG | hypre | ML, rigid-body modes
// from its owned nodes' coordinates; `direct`: MUMPS Cholesky), the solution is gathered on rank 0
// (VecScatterCreateToZero) and put back in the caller's numbering.
// Not distributed (yet): assembly and everything before and after the solve stay on rank 0, so
// rank 0's peak is at least the assembly's; through the solve, when the caller hands the matrix
// over (solve_spd(SparseMatrix&&), as the constrained solves do), rank 0 keeps only its own rows
// like the other ranks, plus its part of the preconditioner.
//
// Protocol: every rank calls start(); ranks != 0 call serve(), which returns when rank 0 calls
// release_workers(); then every rank calls finish(). Between the two, rank 0 alone runs library
// code; solve_spd and peak_rss_mb_per_rank are collective through serve(). PETSc and MPI headers
// stay in distributed_solver.cpp.
#pragma once

#include <Eigen/Core>
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

/// Renumbering of nodes by owning rank, keeping the order within a rank: new_of[old] and the
/// first new index of each rank (size ranks + 1). Pure; unit-tested.
struct Renumbering {
  std::vector<int> new_of, old_of, offsets;
};
Renumbering renumber_by_owner(const std::vector<int>& owner, int ranks);

}  // namespace curvefem::fem::distributed
