// CHOLMOD supernodal Cholesky through Eigen's CholmodSupport module.
#include <Eigen/CholmodSupport>
#include <cstring>
#include <memory>

#include "fem/solvers/linear_solver.hpp"
#include "meshing/core/error.hpp"
#include "meshing/core/timer.hpp"

namespace curvefem::fem {

using Llt = Eigen::CholmodSupernodalLLT<SparseMatrix, Eigen::Lower>;

struct FactorizationCache::Impl {
  SparseMatrix matrix;  // compressed copy of the factorized matrix
  std::unique_ptr<Llt> llt;
  int factorizations = 0, reuses = 0;
  // CG + GAMG: the KSP set up for an earlier matrix (linear_solver_petsc.cpp), kept with what it
  // was set up for; type-erased so this file needs no PETSc header.
  std::shared_ptr<void> ksp;
  std::shared_ptr<KeptOperator> assembled;  // a problem's operator (assembly_cache_slot)
  int assemblies = 0, assembly_reuses = 0;
};

std::shared_ptr<void>& petsc_cache_slot(FactorizationCache& cache) { return cache.impl().ksp; }
void count_cache_use(FactorizationCache& cache, bool reused) {
  ++(reused ? cache.impl().reuses : cache.impl().factorizations);
}
std::shared_ptr<KeptOperator>& assembly_cache_slot(FactorizationCache& cache) {
  return cache.impl().assembled;
}
void count_assembly(FactorizationCache& cache, bool reused) {
  ++(reused ? cache.impl().assembly_reuses : cache.impl().assemblies);
}

FactorizationCache::FactorizationCache() : m_impl(std::make_unique<Impl>()) {}
FactorizationCache::~FactorizationCache() = default;
int FactorizationCache::factorizations() const { return m_impl->factorizations; }
int FactorizationCache::reuses() const { return m_impl->reuses; }
int FactorizationCache::assemblies() const { return m_impl->assemblies; }
int FactorizationCache::assembly_reuses() const { return m_impl->assembly_reuses; }

bool identical_matrices(const SparseMatrix& a, const SparseMatrix& b) {
  if (a.rows() != b.rows() || a.cols() != b.cols() || a.nonZeros() != b.nonZeros()) return false;
  const auto n = std::size_t(a.nonZeros());
  return std::memcmp(a.outerIndexPtr(), b.outerIndexPtr(),
                     sizeof(int) * std::size_t(a.cols() + 1)) == 0 &&
         std::memcmp(a.innerIndexPtr(), b.innerIndexPtr(), sizeof(int) * n) == 0 &&
         std::memcmp(a.valuePtr(), b.valuePtr(), sizeof(double) * n) == 0;
}

Eigen::VectorXd solve_cholmod(const SparseMatrix& A, const Eigen::VectorXd& b,
                              LinearSolveInfo& info, FactorizationCache* cache) {
  info.method = "cholmod-supernodal";
  Stopwatch watch;
  Llt local;
  Llt* llt = &local;
  bool factorized = false;
  if (cache) {
    FactorizationCache::Impl& c = cache->impl();
    // A compressed A is compared as it is; a copy is made only to compress it, or to keep it.
    auto same_as_kept = [&] {
      if (A.isCompressed()) return identical_matrices(c.matrix, A);
      SparseMatrix compressed = A;
      compressed.makeCompressed();
      return identical_matrices(c.matrix, compressed);
    };
    if (c.llt && same_as_kept()) {  // only successful factors are kept
      ++c.reuses;
      info.reused_factorization = true;
      llt = c.llt.get();
      factorized = true;
    } else {
      SparseMatrix compressed = A;
      compressed.makeCompressed();
      c.llt.reset();
      c.matrix.swap(compressed);  // not std::move: it would copy (linear_solver.hpp)
      auto fresh = std::make_unique<Llt>();
      fresh->compute(c.matrix);
      ++c.factorizations;
      factorized = fresh->info() == Eigen::Success;
      if (factorized) c.llt = std::move(fresh);
      llt = c.llt.get();
    }
  } else {
    local.compute(A);
    factorized = local.info() == Eigen::Success;
  }
  info.setup_s = watch.seconds();
  if (!factorized)
    throw SolverError(
        "CHOLMOD factorization failed: the matrix is not positive definite "
        "(inverted element, missing Dirichlet condition or a floating part?)");
  watch.reset();
  Eigen::VectorXd x = llt->solve(b);
  info.solve_s = watch.seconds();
  if (llt->info() != Eigen::Success) throw SolverError("CHOLMOD solve failed");
  return x;
}

}  // namespace curvefem::fem
