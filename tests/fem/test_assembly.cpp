#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>

#include "fem/assembly/parallel_assembly.hpp"
#include "fem/problems/poisson.hpp"
#include "meshing/core/error.hpp"
#include "meshing/core/primitives.hpp"

using namespace curvefem;

namespace {
LagrangeMesh wobbly_cube(int n, int k) {
  return elevate_order(make_cube_tets(n), k, [](const Eigen::Vector3d& x) {
    return Eigen::Vector3d(
        x + 0.03 * Eigen::Vector3d(std::sin(4 * x[1]), std::cos(3 * x[2]), x[0] * x[1]));
  });
}

fem::AssembledSystem assemble_with_threads(const LagrangeMesh& mesh,
                                           const fem::FunctionSpace& space, int threads) {
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
  fem::PoissonProblem problem;
  problem.kappa = [](const Eigen::Vector3d& x) { return 1 + x.squaredNorm(); };
  problem.rhs = [](const Eigen::Vector3d& x) { return std::sin(x[0] + x[2]); };
  return fem::assemble_poisson(mesh, space, problem);
}
}  // namespace

TEST(Assembly, IdenticalWithOneAndTwoThreads) {
  const LagrangeMesh mesh = wobbly_cube(4, 2);
  const fem::FunctionSpace space = fem::build_function_space(mesh, 3);
  const auto a = assemble_with_threads(mesh, space, 1);
  const auto b = assemble_with_threads(mesh, space, 2);
  ASSERT_EQ(a.K.nonZeros(), b.K.nonZeros());
  // Bit-identical: element matrices do not depend on the thread, scatter is serial in cell order.
  for (Eigen::Index i = 0; i < a.K.nonZeros(); ++i) ASSERT_EQ(a.K.valuePtr()[i], b.K.valuePtr()[i]);
  EXPECT_EQ(a.F, b.F);
}

TEST(Assembly, StiffnessIsSymmetricAndKillsConstants) {
  const LagrangeMesh mesh = wobbly_cube(2, 3);
  for (int p = 1; p <= 4; ++p) {
    const fem::FunctionSpace space = fem::build_function_space(mesh, p);
    const auto s = assemble_with_threads(mesh, space, 2);
    const fem::SparseMatrix asym = s.K - fem::SparseMatrix(s.K.transpose());
    EXPECT_LT(asym.norm(), 1e-12 * s.K.norm()) << "p=" << p;
    // Constants are in the kernel of the stiffness: K·1 = 0.
    const Eigen::VectorXd k1 = s.K * Eigen::VectorXd::Ones(space.num_dofs);
    EXPECT_LT(k1.cwiseAbs().maxCoeff(), 1e-11 * s.K.norm()) << "p=" << p;
  }
}

TEST(Solvers, NonPositiveDefiniteSystemIsASolverError) {
  const LagrangeMesh mesh = make_cube_tets(2);
  const fem::FunctionSpace space = fem::build_function_space(mesh, 1);
  fem::PoissonProblem problem;
  problem.kappa = [](const Eigen::Vector3d&) { return -1.0; };  // negative definite
  problem.dirichlet.push_back({std::vector<char>(space.boundary_faces.size(), 1),
                               [](const Eigen::Vector3d&) { return 1.0; },
                               {}});
  fem::LinearSolverOptions direct;
  direct.type = fem::SolverType::direct;
  EXPECT_THROW(fem::solve_poisson(mesh, space, problem, direct), SolverError);
}

TEST(Solvers, CgNonConvergenceReportsResidualHistory) {
  const LagrangeMesh mesh = make_cube_tets(4);
  const fem::FunctionSpace space = fem::build_function_space(mesh, 2);
  fem::PoissonProblem problem;
  problem.rhs = [](const Eigen::Vector3d&) { return 1.0; };
  problem.dirichlet.push_back({std::vector<char>(space.boundary_faces.size(), 1),
                               [](const Eigen::Vector3d&) { return 0.0; },
                               {}});
  fem::LinearSolverOptions cg;
  cg.type = fem::SolverType::cg;
  cg.max_iterations = 2;
  cg.rtol = 1e-14;
  try {
    fem::solve_poisson(mesh, space, problem, cg);
    FAIL() << "expected SolverError";
  } catch (const SolverError& e) {
    EXPECT_NE(std::string(e.what()).find("residual history"), std::string::npos) << e.what();
  }
}

// A FactorizationCache reuses the CHOLMOD factor for a bit-identical matrix (load cases with the
// same Dirichlet part): the same solution as a fresh factorization, bit for bit; another matrix
// (other Dirichlet faces, or a changed value) is factorized again; a failed factorization is not
// kept.
TEST(Solvers, FactorizationCacheReusesTheFactorOfAnIdenticalMatrix) {
  const LagrangeMesh mesh = wobbly_cube(3, 2);
  const fem::FunctionSpace space = fem::build_function_space(mesh, 2);
  auto problem = [&](double load, bool all_faces) {
    fem::PoissonProblem p;
    p.rhs = [load](const Eigen::Vector3d& x) { return load * (1 + x[0]); };
    std::vector<char> faces(space.boundary_faces.size(), 1);
    if (!all_faces)
      for (std::size_t f = 0; f < faces.size(); f += 2) faces[f] = 0;
    p.dirichlet.push_back({faces, [load](const Eigen::Vector3d& x) { return load * x[1]; }, {}});
    return p;
  };
  fem::LinearSolverOptions fresh;
  fresh.type = fem::SolverType::direct;
  fem::LinearSolverOptions cached = fresh;
  cached.factorization_cache = std::make_shared<fem::FactorizationCache>();
  const auto a = fem::solve_poisson(mesh, space, problem(1.0, true), cached);
  const auto b = fem::solve_poisson(mesh, space, problem(2.5, true), cached);
  EXPECT_FALSE(a.solve.reused_factorization);
  EXPECT_TRUE(b.solve.reused_factorization);
  EXPECT_EQ(b.u, fem::solve_poisson(mesh, space, problem(2.5, true), fresh).u);
  EXPECT_LT((b.u - 2.5 * a.u).cwiseAbs().maxCoeff(), 1e-12 * a.u.cwiseAbs().maxCoeff());
  EXPECT_EQ(cached.factorization_cache->factorizations(), 1);
  EXPECT_EQ(cached.factorization_cache->reuses(), 1);
  const auto c = fem::solve_poisson(mesh, space, problem(1.0, false), cached);  // other faces
  EXPECT_FALSE(c.solve.reused_factorization);
  EXPECT_EQ(c.u, fem::solve_poisson(mesh, space, problem(1.0, false), fresh).u);
  EXPECT_EQ(cached.factorization_cache->factorizations(), 2);
  fem::PoissonProblem negative = problem(1.0, true);
  negative.kappa = [](const Eigen::Vector3d&) { return -1.0; };
  EXPECT_THROW(fem::solve_poisson(mesh, space, negative, cached), SolverError);
  const auto d = fem::solve_poisson(mesh, space, problem(1.0, true), cached);
  EXPECT_FALSE(d.solve.reused_factorization);  // the failed one was not kept, nor the one before
  EXPECT_EQ(d.u, a.u);
}

// Poisson solves sharing a FactorizationCache take the kept cell stiffness and assemble only
// their loads: bit-identical to fresh solves, Robin terms (added after the cells) included once;
// another κ assembles again.
TEST(Solvers, PoissonSolvesSharingACacheAssembleTheStiffnessOnce) {
  const LagrangeMesh mesh = wobbly_cube(3, 2);
  const fem::FunctionSpace space = fem::build_function_space(mesh, 2);
  auto problem = [&](double load, double kappa) {
    fem::PoissonProblem p;
    p.kappa_value = kappa;
    p.rhs = [load](const Eigen::Vector3d& x) { return load * (1 + x[0]); };
    std::vector<char> dirichlet(space.boundary_faces.size(), 1), robin(dirichlet.size(), 0);
    for (std::size_t f = 0; f < dirichlet.size(); f += 3) std::swap(dirichlet[f], robin[f]);
    p.dirichlet.push_back(
        {dirichlet, [load](const Eigen::Vector3d& x) { return load * x[1]; }, {}});
    p.robin.push_back({robin,
                       [](const Eigen::Vector3d&, const Eigen::Vector3d&) { return 2.0; },
                       [](const Eigen::Vector3d& x, const Eigen::Vector3d&) { return x[2]; },
                       {}});
    return p;
  };
  fem::LinearSolverOptions fresh;
  fresh.type = fem::SolverType::direct;
  fem::LinearSolverOptions cached = fresh;
  cached.factorization_cache = std::make_shared<fem::FactorizationCache>();
  const auto a = fem::solve_poisson(mesh, space, problem(1.0, 1.5), cached);
  const auto b = fem::solve_poisson(mesh, space, problem(2.5, 1.5), cached);
  EXPECT_EQ(cached.factorization_cache->assemblies(), 1);
  EXPECT_EQ(cached.factorization_cache->assembly_reuses(), 1);
  EXPECT_EQ(a.u, fem::solve_poisson(mesh, space, problem(1.0, 1.5), fresh).u);
  EXPECT_EQ(b.u, fem::solve_poisson(mesh, space, problem(2.5, 1.5), fresh).u);
  const auto c = fem::solve_poisson(mesh, space, problem(1.0, 3.0), cached);  // another κ
  EXPECT_EQ(c.u, fem::solve_poisson(mesh, space, problem(1.0, 3.0), fresh).u);
  EXPECT_EQ(cached.factorization_cache->assemblies(), 2);
}

TEST(SparseMatrixOwnership, TakeMovesTheStorageAndReleaseFreesIt) {
  // Eigen 3.4's SparseMatrix has no moves: std::move copies and `= SparseMatrix()` keeps the
  // storage. take() and release() must do neither (rank 0's memory in a distributed solve, and
  // a copy of K per solve, depended on it).
  curvefem::fem::SparseMatrix A(1000, 1000);
  A.setIdentity();
  A.makeCompressed();
  const double* values = A.valuePtr();
  curvefem::fem::SparseMatrix B = curvefem::fem::take(A);
  EXPECT_EQ(B.valuePtr(), values);  // the same storage, not a copy
  EXPECT_EQ(B.nonZeros(), 1000);
  EXPECT_EQ(A.nonZeros(), 0);
  curvefem::fem::release(B);
  EXPECT_EQ(B.data().allocatedSize(), 0);
  // What the helpers replace: the copy and the kept capacity.
  curvefem::fem::SparseMatrix C(1000, 1000);
  C.setIdentity();
  curvefem::fem::SparseMatrix D = std::move(C);
  EXPECT_NE(D.valuePtr(), C.valuePtr());
  EXPECT_EQ(C.nonZeros(), 1000);  // std::move left C whole: it copied
  C = curvefem::fem::SparseMatrix();
  EXPECT_GE(C.data().allocatedSize(), 1000);  // cleared, not freed
}

// Distributed assembly (fem/solvers/distributed.hpp, solve_by_rows) assembles a matrix by blocks
// of rows: a pattern of some DOFs' rows, and only the cells touching them. Those rows must be the
// whole matrix's, bit for bit (same cells, same order), and the other rows empty.
TEST(Assembly, RowsOfSomeDofsAreTheWholeMatricesRowsBitForBit) {
  const LagrangeMesh mesh = wobbly_cube(3, 2);
  const fem::FunctionSpace space = fem::build_function_space(mesh, 2);
  const int n = static_cast<int>(space.cell_dofs.cols());
  for (const int b : {1, 3}) {
    // A symmetric element matrix depending on the cell (values of all magnitudes).
    const fem::ElementKernel kernel = [&](int cell, Eigen::MatrixXd& Ke, Eigen::VectorXd&) {
      for (int i = 0; i < b * n; ++i)
        for (int j = 0; j <= i; ++j)
          Ke(i, j) = Ke(j, i) = std::sin(1.0 + cell + 0.37 * i * j) * std::exp(0.1 * (i - j));
    };
    const fem::SparsePattern whole(space.cell_dofs, space.num_dofs, b);
    auto K = whole.zero_matrix();
    fem::assemble_cells(mesh.num_cells(), b * n, kernel, &whole, space.cell_dofs, b, K.valuePtr(),
                        nullptr);
    // The DOFs of one corner of the cube (a rank's part), and every third DOF (scattered).
    for (const int kind : {0, 1}) {
      std::vector<char> rows(static_cast<std::size_t>(space.num_dofs), 0);
      for (int d = 0; d < space.num_dofs; ++d)
        rows[std::size_t(d)] =
            kind == 0 ? space.dof_points(d, 0) < 0.4 && space.dof_points(d, 1) < 0.6 : d % 3 == 0;
      const std::vector<char> active = fem::cells_touching(space.cell_dofs, rows);
      const long long used = std::count(active.begin(), active.end(), 1);
      EXPECT_GT(used, 0);
      if (kind == 0) EXPECT_LT(used, mesh.num_cells());
      const fem::SparsePattern some(space.cell_dofs, space.num_dofs, b, &rows);
      EXPECT_LT(some.nonzeros(), whole.nonzeros());
      auto A = some.zero_matrix();
      fem::assemble_cells(mesh.num_cells(), b * n, kernel, &some, space.cell_dofs, b, A.valuePtr(),
                          nullptr, &active);
      long long kept = 0;
      for (int u = 0; u < b * space.num_dofs; ++u) {
        const int begin = A.outerIndexPtr()[u], end = A.outerIndexPtr()[u + 1];
        if (!rows[std::size_t(u / b)]) {
          ASSERT_EQ(begin, end) << "row " << u << " is not one of the rows asked for";
          continue;
        }
        const int wb = K.outerIndexPtr()[u], we = K.outerIndexPtr()[u + 1];
        ASSERT_EQ(end - begin, we - wb) << "row " << u;
        for (int k = 0; k < end - begin; ++k) {
          ASSERT_EQ(A.innerIndexPtr()[begin + k], K.innerIndexPtr()[wb + k]);
          ASSERT_EQ(A.valuePtr()[begin + k], K.valuePtr()[wb + k]) << "row " << u;
        }
        ++kept;
      }
      EXPECT_EQ(kept, b * std::count(rows.begin(), rows.end(), 1));
    }
  }
}
