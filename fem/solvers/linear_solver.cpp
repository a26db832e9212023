#include "fem/solvers/linear_solver.hpp"

#include <dlfcn.h>

#include <Eigen/QR>

#include "fem/solvers/distributed.hpp"
#include "meshing/core/error.hpp"
#include "meshing/core/log.hpp"

namespace curvefem::fem {

std::string to_string(SolverType type) {
  switch (type) {
    case SolverType::direct:
      return "direct";
    case SolverType::cg:
      return "cg";
    default:
      return "auto";
  }
}

std::string to_string(Preconditioner preconditioner) {
  switch (preconditioner) {
    case Preconditioner::hypre:
      return "hypre";
    case Preconditioner::ml:
      return "ml";
    default:
      return "gamg";
  }
}

SolverType solver_type_from(const std::string& text) {
  for (const SolverType t : {SolverType::automatic, SolverType::direct, SolverType::cg})
    if (to_string(t) == text) return t;
  throw InputError("unknown solver type '" + text + "' (direct, cg or auto)");
}

Preconditioner preconditioner_from(const std::string& text) {
  for (const Preconditioner p : {Preconditioner::gamg, Preconditioner::hypre, Preconditioner::ml})
    if (to_string(p) == text) return p;
  throw InputError("unknown preconditioner '" + text + "' (gamg, hypre or ml)");
}

bool set_blas_threads(int threads) {
  using Setter = void (*)(int);
  const auto set = reinterpret_cast<Setter>(dlsym(RTLD_DEFAULT, "openblas_set_num_threads"));
  if (!set || threads < 1) return false;
  set(threads);
  return true;
}

int blas_threads() {
  using Getter = int (*)();
  const auto get = reinterpret_cast<Getter>(dlsym(RTLD_DEFAULT, "openblas_get_num_threads"));
  return get ? get() : 0;
}

namespace {

/// Orthonormal basis of the columns of V (#rows x m, full column rank).
Eigen::MatrixXd orthonormal_basis(const Eigen::MatrixXd& V) {
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(V);
  Eigen::MatrixXd Q = qr.householderQ() * Eigen::MatrixXd::Identity(V.rows(), V.cols());
  const Eigen::VectorXd diag = qr.matrixQR().diagonal().cwiseAbs();
  if (diag.minCoeff() <= 1e-10 * diag.maxCoeff())
    throw InputError("linear system: the null-space vectors are linearly dependent");
  return Q;
}

/// Direct solve of the semi-definite A: pins the m unknowns a column-pivoted QR of N^T picks
/// (N = null space, #rows x m), solves the SPD remainder (CHOLMOD, or MUMPS over the ranks of a
/// distributed run), pinned unknowns = 0.
Eigen::VectorXd solve_pinned(const SparseMatrix& A, const Eigen::VectorXd& b,
                             const Eigen::MatrixXd& N, const LinearSolverOptions& options,
                             LinearSolveInfo& info, FactorizationCache* cache) {
  const Eigen::Index n = A.rows(), m = N.cols();
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(N.transpose());
  std::vector<int> reduced(static_cast<std::size_t>(n), 0);
  for (Eigen::Index k = 0; k < m; ++k) reduced[std::size_t(qr.colsPermutation().indices()[k])] = -1;
  int r = 0;
  for (auto& i : reduced)
    if (i == 0) i = r++;
  std::vector<Eigen::Triplet<double, int>> entries;
  entries.reserve(static_cast<std::size_t>(A.nonZeros()));
  for (int col = 0; col < n; ++col)
    for (SparseMatrix::InnerIterator it(A, col); it; ++it)
      if (reduced[std::size_t(it.row())] >= 0 && reduced[std::size_t(col)] >= 0)
        entries.emplace_back(reduced[std::size_t(it.row())], reduced[std::size_t(col)], it.value());
  SparseMatrix Ar(r, r);
  Ar.setFromTriplets(entries.begin(), entries.end());
  Eigen::VectorXd br(r);
  for (Eigen::Index i = 0; i < n; ++i)
    if (reduced[std::size_t(i)] >= 0) br[reduced[std::size_t(i)]] = b[i];
  const Eigen::VectorXd xr =
      distributed::active()
          ? distributed::solve(Ar, br, options, /*direct=*/true, Eigen::MatrixXd(), info)
          : solve_cholmod(Ar, br, info, cache);
  Eigen::VectorXd x = Eigen::VectorXd::Zero(n);
  for (Eigen::Index i = 0; i < n; ++i)
    if (reduced[std::size_t(i)] >= 0) x[i] = xr[reduced[std::size_t(i)]];
  return x;
}

}  // namespace

namespace {

/// solve_spd; `owned`, if set, is A itself, which a distributed solve may free.
Eigen::VectorXd solve_spd_impl(const SparseMatrix& A, const Eigen::VectorXd& b,
                               const LinearSolverOptions& options, LinearSolveInfo* info,
                               SparseMatrix* owned) {
  if (A.rows() != A.cols() || A.rows() != b.size())
    throw InputError("linear system: matrix " + std::to_string(A.rows()) + "x" +
                     std::to_string(A.cols()) + ", right-hand side " + std::to_string(b.size()));
  const bool singular = options.null_space.cols() > 0;
  if (singular && (options.null_space.rows() != A.rows() || options.null_space.cols() >= A.rows()))
    throw InputError("linear system: null space " + std::to_string(options.null_space.rows()) +
                     "x" + std::to_string(options.null_space.cols()) + " for " +
                     std::to_string(A.rows()) + " unknowns");
  LinearSolveInfo local;
  LinearSolveInfo& out = info ? *info : local;
  out = {};
  if (A.rows() == 0) return Eigen::VectorXd();
  // Several MPI ranks (fem/solvers/distributed.hpp): "auto" is cg, direct is MUMPS over the ranks.
  const bool several_ranks = distributed::active();
  const bool direct = options.type == SolverType::automatic
                          ? !several_ranks && A.rows() <= options.auto_direct_max_dofs
                          : options.type == SolverType::direct;
  Eigen::MatrixXd Q;
  Eigen::VectorXd rhs = b;
  if (singular) {
    Q = orthonormal_basis(options.null_space);
    rhs -= Q * (Q.transpose() * b);  // onto range A
    out.null_space_dim = static_cast<int>(Q.cols());
  }
  Eigen::VectorXd x;
  if (direct && singular)
    x = solve_pinned(A, rhs, options.null_space, options, out, options.factorization_cache.get());
  else if (several_ranks)
    x = distributed::solve(A, rhs, options, direct, Q, out, owned);
  else if (direct)
    x = solve_cholmod(A, rhs, out, options.factorization_cache.get());
  else
    x = solve_petsc_cg(A, rhs, options, Q, out, options.factorization_cache.get());
  const double bn = rhs.norm();
  const Eigen::Index n = b.size();
  if (A.rows() == n)  // else freed by the distributed solve, which measured the residual
    out.relative_residual = (rhs - A * x).norm() / (bn > 0 ? bn : 1.0);
  log::info("linear solve (", out.method, singular ? ", singular" : "",
            several_ranks ? ", " + std::to_string(out.ranks) + " ranks" : "", "): ", n,
            " unknowns, ", out.iterations, " iterations, relative residual ", out.relative_residual,
            ", setup ", out.setup_s, " s, solve ", out.solve_s, " s");
  return x;
}

}  // namespace

Eigen::VectorXd solve_spd(const SparseMatrix& A, const Eigen::VectorXd& b,
                          const LinearSolverOptions& options, LinearSolveInfo* info) {
  return solve_spd_impl(A, b, options, info, nullptr);
}

Eigen::VectorXd solve_spd(SparseMatrix&& A, const Eigen::VectorXd& b,
                          const LinearSolverOptions& options, LinearSolveInfo* info) {
  SparseMatrix owned;
  owned.swap(A);  // not std::move: Eigen's SparseMatrix would copy (linear_solver.hpp)
  return solve_spd_impl(owned, b, options, info, &owned);
}

}  // namespace curvefem::fem
