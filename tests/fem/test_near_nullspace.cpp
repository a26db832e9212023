// GAMG's near-nullspace for elasticity (rigid-body modes from the DOF points) and singular
// systems in solve_spd (fem/solvers/linear_solver.hpp).
#include <gtest/gtest.h>

#include <array>
#include <cmath>

#include "fem/problems/elasticity.hpp"
#include "meshing/core/error.hpp"
#include "meshing/core/primitives.hpp"

using namespace curvefem;

namespace {

/// Faces whose corners all satisfy coordinate `axis` == value.
std::vector<char> faces_at(const LagrangeMesh& mesh, const fem::FunctionSpace& space, int axis,
                           double value) {
  std::vector<char> out(space.boundary_faces.size(), 0);
  for (std::size_t f = 0; f < out.size(); ++f) {
    const auto [cell, j] = space.boundary_faces[f];
    bool all = true;
    for (int i = 0; i < 4; ++i)
      if (i != j) all = all && std::abs(mesh.nodes(mesh.cells(cell, i), axis) - value) < 1e-12;
    out[f] = all;
  }
  return out;
}

/// Beam 4 × 1 × 1 (n × n/4 × n/4 cells of the cube, scaled), clamped at x = 0, pulled down at
/// x = 4.
struct Cantilever {
  LagrangeMesh mesh;
  fem::FunctionSpace space;
  fem::ElasticityProblem problem;
  Cantilever(int n, int p) {
    mesh = make_cube_tets(n);
    for (int i = 0; i < mesh.num_nodes(); ++i) mesh.nodes(i, 0) *= 4;
    space = fem::build_function_space(mesh, p);
    problem.material = {100.0, 0.3};
    problem.dirichlet.push_back({faces_at(mesh, space, 0, 0.0),
                                 {true, true, true},
                                 [](const Eigen::Vector3d&) { return Eigen::Vector3d::Zero(); },
                                 {}});
    problem.traction.push_back(
        {faces_at(mesh, space, 0, 4.0),
         [](const Eigen::Vector3d&, const Eigen::Vector3d&) { return Eigen::Vector3d(0, 0, -1); },
         {}});
  }
};

fem::LinearSolverOptions cg(bool near_nullspace) {
  fem::LinearSolverOptions o;
  o.type = fem::SolverType::cg;
  o.rtol = 1e-10;
  o.use_near_nullspace = near_nullspace;
  return o;
}

}  // namespace

TEST(NearNullspace, RigidBodyModesLowerGamgIterationsOnACantilever) {
  for (int p = 1; p <= 2; ++p) {
    const Cantilever beam(p == 1 ? 6 : 3, p);
    const auto with = fem::solve_linear_elasticity(beam.mesh, beam.space, beam.problem, cg(true));
    const auto without =
        fem::solve_linear_elasticity(beam.mesh, beam.space, beam.problem, cg(false));
    const auto direct = fem::solve_linear_elasticity(beam.mesh, beam.space, beam.problem, {});
    std::printf("p=%d unknowns %d: CG+GAMG iterations %d with rigid-body modes, %d without\n", p,
                with.free_unknowns, with.solve.iterations, without.solve.iterations);
    EXPECT_EQ(with.solve.near_nullspace, "rigid-body modes");
    EXPECT_EQ(without.solve.near_nullspace, "default");
    EXPECT_LT(with.solve.iterations, without.solve.iterations) << "p=" << p;
    EXPECT_LT((with.u - direct.u).norm(), 1e-7 * direct.u.norm()) << "p=" << p;
    EXPECT_LT((without.u - direct.u).norm(), 1e-7 * direct.u.norm()) << "p=" << p;
  }
}

// solver.preconditioner: every AMG of Debian's PETSc solves elasticity (P2 cantilever) to the
// direct solution; GAMG and ML use the rigid-body modes, BoomerAMG does not take them.
TEST(NearNullspace, EveryPreconditionerSolvesTheCantileverToTheDirectSolution) {
  const Cantilever beam(3, 2);
  const auto direct = fem::solve_linear_elasticity(beam.mesh, beam.space, beam.problem, {});
  for (const char* pc : {"gamg", "hypre", "ml"}) {
    fem::LinearSolverOptions o = cg(true);
    o.preconditioner = fem::preconditioner_from(pc);
    const auto s = fem::solve_linear_elasticity(beam.mesh, beam.space, beam.problem, o);
    std::printf("%s: %d unknowns, %d iterations\n", pc, s.free_unknowns, s.solve.iterations);
    EXPECT_EQ(s.solve.method, std::string("petsc-cg-") + pc);
    EXPECT_GT(s.solve.iterations, 0);
    EXPECT_LT(s.solve.iterations, 200) << pc;
    EXPECT_LT((s.u - direct.u).norm(), 1e-7 * direct.u.norm()) << pc;
  }
  // A spelling outside the set is refused where text becomes the enum.
  EXPECT_THROW(fem::preconditioner_from("jacobi"), InputError);
  EXPECT_THROW(fem::solver_type_from("gmres"), InputError);
  for (const fem::SolverType t :
       {fem::SolverType::automatic, fem::SolverType::direct, fem::SolverType::cg})
    EXPECT_EQ(fem::solver_type_from(fem::to_string(t)), t);
}

TEST(NearNullspace, ComponentsFixedSeparatelyGiveTheModesAsVectors) {
  // x = 0: u_x = u_y = 0 everywhere, u_z = 0 only where y < 0.5; pulled at x = 1. The reduced
  // system is not in blocks of 3 (before, MatSetBlockSize(3) failed on its size).
  const LagrangeMesh mesh = make_cube_tets(3);
  const fem::FunctionSpace space = fem::build_function_space(mesh, 2);
  fem::ElasticityProblem problem;
  const auto zero = [](const Eigen::Vector3d&) { return Eigen::Vector3d::Zero(); };
  problem.dirichlet.push_back({faces_at(mesh, space, 0, 0.0), {true, true, false}, zero, {}});
  problem.dirichlet.push_back(
      {faces_at(mesh, space, 0, 0.0), {false, false, true}, zero, [](const Eigen::Vector3d& x) {
         return x[1] < 0.5;
       }});
  problem.traction.push_back({faces_at(mesh, space, 0, 1.0),
                              [](const Eigen::Vector3d& x, const Eigen::Vector3d&) {
                                return Eigen::Vector3d(1 + x[1], 0, -1);
                              },
                              {}});
  const auto direct = fem::solve_linear_elasticity(mesh, space, problem, {});
  ASSERT_NE(direct.free_unknowns % 3, 0);  // no block structure left
  const auto with = fem::solve_linear_elasticity(mesh, space, problem, cg(true));
  const auto without = fem::solve_linear_elasticity(mesh, space, problem, cg(false));
  std::printf(
      "components fixed separately, %d unknowns: %d iterations with the modes, %d without\n",
      direct.free_unknowns, with.solve.iterations, without.solve.iterations);
  EXPECT_EQ(with.solve.near_nullspace, "vectors");
  EXPECT_LT((with.u - direct.u).norm(), 1e-7 * direct.u.norm());
  EXPECT_LT((without.u - direct.u).norm(), 1e-7 * direct.u.norm());
  EXPECT_LE(with.solve.iterations, without.solve.iterations);
}

TEST(NearNullspace, SingularSystemDirectAndCgAgreeUpToTheKernel) {
  // The 1-D Laplacian with free ends: kernel = constants; b with Σ b = 0.
  const int n = 50;
  std::vector<Eigen::Triplet<double, int>> t;
  for (int i = 0; i + 1 < n; ++i) {
    t.emplace_back(i, i, 1.0);
    t.emplace_back(i + 1, i + 1, 1.0);
    t.emplace_back(i, i + 1, -1.0);
    t.emplace_back(i + 1, i, -1.0);
  }
  fem::SparseMatrix A(n, n);
  A.setFromTriplets(t.begin(), t.end());
  Eigen::VectorXd b(n);
  for (int i = 0; i < n; ++i) b[i] = std::sin(0.3 * i);
  b.array() -= b.mean();
  fem::LinearSolverOptions direct;
  direct.type = fem::SolverType::direct;
  direct.null_space = Eigen::VectorXd::Ones(n);
  fem::LinearSolverOptions iterative = direct;
  iterative.type = fem::SolverType::cg;
  iterative.rtol = 1e-12;
  fem::LinearSolveInfo di, ci;
  Eigen::VectorXd x = fem::solve_spd(A, b, direct, &di);
  Eigen::VectorXd y = fem::solve_spd(A, b, iterative, &ci);
  EXPECT_EQ(di.null_space_dim, 1);
  EXPECT_LT(di.relative_residual, 1e-12);
  EXPECT_LT(ci.relative_residual, 1e-9);
  x.array() -= x.mean();
  y.array() -= y.mean();
  EXPECT_LT((x - y).norm(), 1e-8 * x.norm());
}

TEST(NearNullspace, CgReusesItsSetUpForAnIdenticalMatrixThroughTheCache) {
  // The 1-D Laplacian with one end fixed (SPD); two right-hand sides, then a changed matrix.
  const int n = 200;
  std::vector<Eigen::Triplet<double, int>> t;
  for (int i = 0; i < n; ++i) {
    t.emplace_back(i, i, i == 0 ? 3.0 : 2.0);
    if (i + 1 < n) {
      t.emplace_back(i, i + 1, -1.0);
      t.emplace_back(i + 1, i, -1.0);
    }
  }
  fem::SparseMatrix A(n, n);
  A.setFromTriplets(t.begin(), t.end());
  fem::LinearSolverOptions o;
  o.type = fem::SolverType::cg;
  o.rtol = 1e-12;
  o.factorization_cache = std::make_shared<fem::FactorizationCache>();
  const Eigen::VectorXd b1 = Eigen::VectorXd::Ones(n), b2 = Eigen::VectorXd::LinSpaced(n, 0, 1);
  fem::LinearSolveInfo i1, i2, i3;
  const Eigen::VectorXd x1 = fem::solve_spd(A, b1, o, &i1);
  const Eigen::VectorXd x2 = fem::solve_spd(A, b2, o, &i2);
  EXPECT_FALSE(i1.reused_factorization);
  EXPECT_TRUE(i2.reused_factorization);
  EXPECT_LT(i1.relative_residual, 1e-9);
  EXPECT_LT(i2.relative_residual, 1e-9);
  EXPECT_GT(i2.iterations, 0);
  EXPECT_FALSE(i2.residual_history.empty());
  // The same answer as without the cache.
  fem::LinearSolverOptions plain = o;
  plain.factorization_cache = nullptr;
  EXPECT_LT((fem::solve_spd(A, b2, plain) - x2).norm(), 1e-12 * x2.norm());
  // A changed matrix is set up again.
  fem::SparseMatrix B = A;
  B.coeffRef(5, 5) += 1.0;
  const Eigen::VectorXd x3 = fem::solve_spd(B, b1, o, &i3);
  EXPECT_FALSE(i3.reused_factorization);
  EXPECT_LT((B * x3 - b1).norm(), 1e-9 * b1.norm());
  EXPECT_EQ(o.factorization_cache->factorizations(), 2);
  EXPECT_EQ(o.factorization_cache->reuses(), 1);
}

TEST(LinearSolver, TheBlasThreadCountFollowsTheRunsThreadCount) {
  // Debian's OpenBLAS (the BLAS of CHOLMOD and PETSc here) starts a thread per core; a run's
  // --threads must hold for it. Skipped where the BLAS is not OpenBLAS.
  if (!fem::set_blas_threads(1)) GTEST_SKIP() << "the BLAS loaded is not OpenBLAS";
  EXPECT_EQ(fem::blas_threads(), 1);
  ASSERT_TRUE(fem::set_blas_threads(2));
  EXPECT_EQ(fem::blas_threads(), 2);
  EXPECT_FALSE(fem::set_blas_threads(0));  // refused: the count stays
  EXPECT_EQ(fem::blas_threads(), 2);
}

TEST(LinearSolver, CgWithoutACacheLeavesTheCallersMatrixUntouched) {
  // Without a cache, PETSc works on the caller's own arrays (linear_solver_petsc.cpp, no copy):
  // every preconditioner, and GAMG with rigid-body modes in blocks of 3, must leave them bitwise
  // as they were.
  const int n = 300;
  std::vector<Eigen::Triplet<double, int>> t;
  for (int i = 0; i < n; ++i) {
    t.emplace_back(i, i, i == 0 ? 3.0 : 2.0 + 0.01 * (i % 7));
    if (i + 1 < n) {
      t.emplace_back(i, i + 1, -1.0);
      t.emplace_back(i + 1, i, -1.0);
    }
  }
  fem::SparseMatrix A(n, n);
  A.setFromTriplets(t.begin(), t.end());
  A.makeCompressed();
  const fem::SparseMatrix before = A;
  const Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(n, -1, 2);
  Eigen::MatrixXd xyz(n / 3, 3);
  for (int i = 0; i < n / 3; ++i) xyz.row(i) << 0.1 * i, std::sin(0.3 * i), 0.05 * i * i;
  for (int variant = 0; variant < 4; ++variant) {
    SCOPED_TRACE(variant);
    fem::LinearSolverOptions o = cg(variant == 3);
    o.preconditioner = variant == 1   ? fem::Preconditioner::hypre
                       : variant == 2 ? fem::Preconditioner::ml
                                      : fem::Preconditioner::gamg;
    if (variant == 3) {
      o.block_size = 3;
      o.near_nullspace_coordinates = xyz;
    }
    fem::LinearSolveInfo info;
    const Eigen::VectorXd x = fem::solve_spd(A, b, o, &info);
    EXPECT_LT(info.relative_residual, 1e-8);
    ASSERT_EQ(A.nonZeros(), before.nonZeros());
    for (Eigen::Index k = 0; k < A.nonZeros(); ++k) {
      ASSERT_EQ(A.valuePtr()[k], before.valuePtr()[k]) << k;
      ASSERT_EQ(A.innerIndexPtr()[k], before.innerIndexPtr()[k]) << k;
    }
    for (Eigen::Index c = 0; c <= n; ++c)
      ASSERT_EQ(A.outerIndexPtr()[c], before.outerIndexPtr()[c]);
  }
}
