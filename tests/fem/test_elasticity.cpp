#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>

#include "fem/problems/elasticity.hpp"
#include "fem/problems/error_norms.hpp"
#include "meshing/core/error.hpp"
#include "meshing/core/primitives.hpp"
#include "tests/fem/manufactured.hpp"

using namespace curvefem;

namespace {

fem::ErrorNorms vector_errors(const LagrangeMesh& mesh, const fem::FunctionSpace& space,
                              const Eigen::VectorXd& u, const test::ExponentialDisplacement& ex) {
  return fem::compute_errors(
      mesh, space, u, 3,
      [&](const Eigen::Vector3d& x, double* v) {
        Eigen::Map<Eigen::Vector3d> m(v);
        m = ex.value(x);
      },
      [&](const Eigen::Vector3d& x, double* g) {
        Eigen::Map<Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> m(g);
        m = ex.gradient(x);
      });
}

fem::ElasticityProblem clamped_problem(const fem::FunctionSpace& space,
                                       const test::ExponentialDisplacement& ex,
                                       const fem::ElasticMaterial& m) {
  fem::ElasticityProblem problem;
  problem.material = m;
  problem.body_force = [ex](const Eigen::Vector3d& x) { return ex.body_force(x); };
  problem.dirichlet.push_back({std::vector<char>(space.boundary_faces.size(), 1),
                               {true, true, true},
                               [ex](const Eigen::Vector3d& x) { return ex.value(x); },
                               {}});
  return problem;
}

}  // namespace

TEST(LinearElasticity, PatchTestLinearAndQuadraticDisplacements) {
  const fem::ElasticMaterial m{2.0, 0.3};
  const LagrangeMesh mesh = make_cube_tets(2);
  // Linear u, no body force: every p reproduces it.
  const Eigen::Matrix3d A =
      (Eigen::Matrix3d() << 0.1, 0.02, -0.03, 0.01, -0.05, 0.04, 0.0, 0.03, 0.07).finished();
  for (int p = 1; p <= 3; ++p) {
    const fem::FunctionSpace space = fem::build_function_space(mesh, p);
    fem::ElasticityProblem problem;
    problem.material = m;
    problem.dirichlet.push_back({std::vector<char>(space.boundary_faces.size(), 1),
                                 {true, true, true},
                                 [A](const Eigen::Vector3d& x) {
                                   return Eigen::Vector3d(A * x + Eigen::Vector3d(0.1, 0, -0.2));
                                 },
                                 {}});
    const auto sol = fem::solve_linear_elasticity(mesh, space, problem, {});
    double worst = 0;
    for (int d = 0; d < space.num_dofs; ++d) {
      const Eigen::Vector3d x = space.dof_points.row(d).transpose();
      worst = std::max(worst,
                       (sol.u.segment<3>(3 * d) - (A * x + Eigen::Vector3d(0.1, 0, -0.2))).norm());
    }
    EXPECT_LT(worst, 1e-11) << "p=" << p;
  }
  // Quadratic u with its constant body force: p ≥ 2 reproduces it.
  auto uq = [](const Eigen::Vector3d& x) {
    return Eigen::Vector3d(x[0] * x[0], x[1] * x[2], 0.5 * x[0] * x[1]);
  };
  // div σ = (λ+μ) ∇(div u) + μ Δu; div u = 2x + z → ∇div = (2, 0, 1); Δu = (2, 0, 0).
  const double l = m.lambda(), mu = m.mu();
  const Eigen::Vector3d f = -((l + mu) * Eigen::Vector3d(2, 0, 1) + mu * Eigen::Vector3d(2, 0, 0));
  for (int p = 2; p <= 3; ++p) {
    const fem::FunctionSpace space = fem::build_function_space(mesh, p);
    fem::ElasticityProblem problem;
    problem.material = m;
    problem.body_force = [f](const Eigen::Vector3d&) { return f; };
    problem.dirichlet.push_back(
        {std::vector<char>(space.boundary_faces.size(), 1), {true, true, true}, uq, {}});
    const auto sol = fem::solve_linear_elasticity(mesh, space, problem, {});
    double worst = 0;
    for (int d = 0; d < space.num_dofs; ++d)
      worst = std::max(worst,
                       (sol.u.segment<3>(3 * d) - uq(space.dof_points.row(d).transpose())).norm());
    EXPECT_LT(worst, 1e-10) << "p=" << p;
  }
}

TEST(LinearElasticity, ConvergenceRatesWithSmoothDisplacement) {
  const fem::ElasticMaterial m{1.0, 0.3};
  const test::ExponentialDisplacement ex{m.lambda(), m.mu()};
  const int base[4] = {0, 2, 2, 2};
  for (int p = 1; p <= 3; ++p) {
    std::vector<fem::ErrorNorms> e;
    for (int level = 0; level < 3; ++level) {
      const LagrangeMesh mesh = make_cube_tets(base[p] << level);
      const fem::FunctionSpace space = fem::build_function_space(mesh, p);
      const auto sol = fem::solve_linear_elasticity(mesh, space, clamped_problem(space, ex, m), {});
      e.push_back(vector_errors(mesh, space, sol.u, ex));
    }
    const double r_l2 = test::rate(e[1].l2, e[2].l2), r_h1 = test::rate(e[1].h1_semi, e[2].h1_semi);
    std::printf("p=%d  L2 %.3e %.3e %.3e (rate %.2f)  H1 %.3e %.3e %.3e (rate %.2f)\n", p, e[0].l2,
                e[1].l2, e[2].l2, r_l2, e[0].h1_semi, e[1].h1_semi, e[2].h1_semi, r_h1);
    EXPECT_NEAR(r_l2, p + 1, 0.25) << "p=" << p;
    EXPECT_NEAR(r_h1, p, 0.25) << "p=" << p;
  }
}

namespace {
// Cantilever 1 × 0.25 × 0.25 (cube scaled), clamped at x = 0, traction on x = 1.
struct Cantilever {
  LagrangeMesh mesh;
  fem::FunctionSpace space;
  fem::ElasticityProblem problem;
  Cantilever(double load, int p) {
    mesh = make_cube_tets(4);
    for (int i = 0; i < mesh.num_nodes(); ++i) mesh.nodes(i, 1) *= 0.25, mesh.nodes(i, 2) *= 0.25;
    space = fem::build_function_space(mesh, p);
    problem.material = {100.0, 0.3};
    std::vector<char> left(space.boundary_faces.size(), 0), right = left;
    for (std::size_t f = 0; f < space.boundary_faces.size(); ++f) {
      const auto [cell, j] = space.boundary_faces[f];
      double xmin = 1e9, xmax = -1e9;
      for (int i = 0; i < 4; ++i)
        if (i != j)
          xmin = std::min(xmin, mesh.nodes(mesh.cells(cell, i), 0)),
          xmax = std::max(xmax, mesh.nodes(mesh.cells(cell, i), 0));
      left[f] = xmax < 1e-12;
      right[f] = xmin > 1 - 1e-12;
    }
    problem.dirichlet.push_back({left,
                                 {true, true, true},
                                 [](const Eigen::Vector3d&) { return Eigen::Vector3d::Zero(); },
                                 {}});
    problem.traction.push_back({right,
                                [load](const Eigen::Vector3d&, const Eigen::Vector3d&) {
                                  return Eigen::Vector3d(0, 0, -load);
                                },
                                {}});
  }
};
}  // namespace

TEST(NeoHookean, ReducesToLinearElasticityForTinyLoads) {
  Cantilever c(1e-8, 2);
  const auto lin = fem::solve_linear_elasticity(c.mesh, c.space, c.problem, {});
  const auto nh = fem::solve_neo_hookean(c.mesh, c.space, c.problem, {}, {});
  EXPECT_GT(lin.u.norm(), 0);
  EXPECT_LT((nh.u - lin.u).norm() / lin.u.norm(), 1e-6);
}

TEST(NeoHookean, NewtonConvergesQuadratically) {
  Cantilever c(2.0, 2);  // tip deflection ~ a third of the length: clearly nonlinear
  fem::NewtonOptions newton;
  newton.load_steps = 2;
  newton.tolerance = 1e-11;
  const auto sol = fem::solve_neo_hookean(c.mesh, c.space, c.problem, {}, newton);
  const auto lin = fem::solve_linear_elasticity(c.mesh, c.space, c.problem, {});
  EXPECT_GT((sol.u - lin.u).norm() / lin.u.norm(), 1e-2);  // the nonlinearity is visible
  // Residual history of the last load step.
  std::vector<double> r;
  for (const auto& s : sol.newton)
    if (s.load_step == 2) r.push_back(s.residual);
  for (double v : r) std::printf("%.3e ", v);
  std::printf("\n");
  ASSERT_GE(r.size(), 4u);
  // Estimated order q = log(r_{k+1}/r_k) / log(r_k/r_{k-1}) on the last triple above round-off.
  double best = 0;
  for (std::size_t k = 1; k + 1 < r.size(); ++k)
    if (r[k + 1] > 1e-12 * r[0] && r[k] < 0.5 * r[k - 1])
      best = std::max(best, std::log(r[k + 1] / r[k]) / std::log(r[k] / r[k - 1]));
  EXPECT_GT(best, 1.7);
}

// Equilibrium (issue 20): the supports' force, recomputed from u, balances the applied load.
TEST(ForceBalance, CantileverReactionEqualsTheTractionTimesTheArea) {
  for (int p = 1; p <= 3; ++p) {
    Cantilever c(1.5, p);
    c.problem.body_force = [](const Eigen::Vector3d&) { return Eigen::Vector3d(0.2, 0, -1); };
    const auto sol = fem::solve_linear_elasticity(c.mesh, c.space, c.problem, {});
    const fem::ForceBalance fb = fem::force_balance(c.mesh, c.space, c.problem, sol.u, false);
    // Applied: traction (0, 0, -1.5) on the 0.25 x 0.25 end, body force over the 1/16 volume.
    const Eigen::Vector3d expected(0.2 / 16, 0, -1.5 / 16 - 1.0 / 16);
    EXPECT_LT((fb.applied - expected).norm(), 1e-12) << "p = " << p;
    EXPECT_LT(fb.imbalance(), 1e-10) << "p = " << p;
    EXPECT_GT(fb.supported_unknowns, 0);
    // A solution that is not the equilibrium one shows: the imbalance is the residual left.
    const fem::ForceBalance off =
        fem::force_balance(c.mesh, c.space, c.problem, 0.9 * sol.u, false);
    EXPECT_GT(off.imbalance(), 1e-2) << "p = " << p;
  }
}

TEST(ForceBalance, NitscheSupportsAndNeoHookeanBalanceTheLoad) {
  // A clamp by the filter x < 0.1 on every boundary face: it passes the x = 0 end whole and the
  // side faces of the first layer in part, which Nitsche's method imposes weakly.
  Cantilever c(1.0, 2);
  c.problem.dirichlet[0].faces.assign(c.space.boundary_faces.size(), 1);
  c.problem.dirichlet[0].where = [](const Eigen::Vector3d& x) { return x[0] < 0.1; };
  c.problem.partial_dirichlet = fem::PartialDirichlet::nitsche;
  const auto lin = fem::solve_linear_elasticity(c.mesh, c.space, c.problem, {});
  ASSERT_GT(lin.nitsche_faces, 0);
  const fem::ForceBalance fb = fem::force_balance(c.mesh, c.space, c.problem, lin.u, false);
  EXPECT_NEAR(fb.applied[2], -1.0 / 16, 1e-12);
  EXPECT_LT(fb.imbalance(), 1e-10);
  Cantilever d(2.0, 2);
  fem::NewtonOptions newton;
  newton.load_steps = 2;
  const auto nh = fem::solve_neo_hookean(d.mesh, d.space, d.problem, {}, newton);
  const fem::ForceBalance fn = fem::force_balance(d.mesh, d.space, d.problem, nh.u, true);
  EXPECT_NEAR(fn.applied[2], -2.0 / 16, 1e-12);
  EXPECT_LT(fn.imbalance(), 1e-8);
  // The linear stress of the large-deformation solution does not balance: the check sees the
  // constitutive law.
  EXPECT_GT(fem::force_balance(d.mesh, d.space, d.problem, nh.u, false).imbalance(), 1e-3);
}

TEST(LinearElasticity, StraightCellsUseTheReferenceTensorsExactly) {
  // Straight cells take the reference-table kernel, a curved mesh the point loop. The same
  // generic (perturbed) straight mesh as order 1 and raised to order 2 without moving a node
  // must give the same displacement to rounding, P1..P3 (non-polynomial Dirichlet data and a
  // constant body force: both codes' rules are exact for the stiffness and this load on affine
  // cells, so only rounding differs; the load makes a wrongly scaled stiffness show).
  LagrangeMesh mesh = make_cube_tets(2);
  std::uint32_t state = 777;
  for (Eigen::Index v = 0; v < mesh.nodes.rows(); ++v)
    for (int d = 0; d < 3; ++d) {
      state = state * 1664525u + 1013904223u;
      mesh.nodes(v, d) += (double(state >> 8) / double(1u << 24) - 0.5) * 0.1;
    }
  const LagrangeMesh curved = elevate_order(mesh, 2, [](const Eigen::Vector3d& x) { return x; });
  fem::ElasticityProblem problem;
  problem.material = {3.0, 0.35};
  problem.body_force = [](const Eigen::Vector3d&) { return Eigen::Vector3d(0.3, -2.0, 0.5); };
  auto g = [](const Eigen::Vector3d& x) {
    return Eigen::Vector3d(std::exp(0.5 * x[0]) * x[1], std::sin(x[2]) + x[0] * x[0],
                           std::cos(x[0] + x[1]));
  };
  for (int p = 1; p <= 3; ++p) {
    SCOPED_TRACE(p);
    const fem::FunctionSpace a_space = fem::build_function_space(mesh, p);
    const fem::FunctionSpace b_space = fem::build_function_space(curved, p);
    ASSERT_EQ(a_space.num_dofs, b_space.num_dofs);
    problem.dirichlet = {
        {std::vector<char>(a_space.boundary_faces.size(), 1), {true, true, true}, g, {}}};
    const auto a = fem::solve_linear_elasticity(mesh, a_space, problem, {});
    const auto b = fem::solve_linear_elasticity(curved, b_space, problem, {});
    ASSERT_EQ(a.u.size(), b.u.size());
    EXPECT_GT(a.u.lpNorm<Eigen::Infinity>(), 0.5);
    EXPECT_LE((a.u - b.u).lpNorm<Eigen::Infinity>(), 1e-11 * a.u.lpNorm<Eigen::Infinity>());
  }
}

// The load functional (issue 22's integral QoI): with the clamp at rest it is the compliance
// a(u_h, u_h), which grows with the nested spaces P1 ⊂ P2 ⊂ P3 on one straight mesh towards
// a(u, u), by shrinking steps; it is linear in u_h (twice the load: four times the work).
TEST(LinearElasticity, TheLoadFunctionalIsTheComplianceAndGrowsWithTheDegree) {
  std::vector<double> work;
  for (int p = 1; p <= 3; ++p) {
    Cantilever c(1.5, p);
    const auto sol = fem::solve_linear_elasticity(c.mesh, c.space, c.problem, {});
    work.push_back(sol.load_functional);
    EXPECT_EQ(sol.load_functional_volume, 0.0);  // no body force: the traction's work alone
    std::printf("cantilever p=%d  l(u_h) = %.10e\n", p, sol.load_functional);
    if (p == 2) {
      Cantilever d(3.0, p);
      const auto twice = fem::solve_linear_elasticity(d.mesh, d.space, d.problem, {});
      EXPECT_NEAR(twice.load_functional, 4 * sol.load_functional, 1e-10 * sol.load_functional);
    }
  }
  EXPECT_GT(work[0], 0);
  EXPECT_GT(work[1], work[0]);
  EXPECT_GT(work[2], work[1]);
  EXPECT_LT(work[2] - work[1], 0.5 * (work[1] - work[0]));
  // A body force and the traction: the volume part is the body force's work alone, which is
  // what the traction-free problem reports as its whole functional (the same matrix, so the
  // split is exact up to the solver).
  Cantilever both(1.5, 2), body_only(0.0, 2);
  for (auto* c : {&both, &body_only})
    c->problem.body_force = [](const Eigen::Vector3d&) { return Eigen::Vector3d(0.2, 0, -1); };
  body_only.problem.traction.clear();
  const auto sb = fem::solve_linear_elasticity(both.mesh, both.space, both.problem, {});
  const auto so =
      fem::solve_linear_elasticity(body_only.mesh, body_only.space, body_only.problem, {});
  const auto st =
      fem::solve_linear_elasticity(both.mesh, both.space, Cantilever(1.5, 2).problem, {});
  // By symmetry of the compliance, ∫b·u(t) = ∫t·u(b): l(u(b+t)) = l_b(u_b) + 2 ∫b·u_t + l_t(u_t).
  EXPECT_NEAR(so.load_functional_volume, so.load_functional, 1e-12 * so.load_functional);
  EXPECT_GT(so.load_functional, 0);
  EXPECT_NEAR(sb.load_functional,
              so.load_functional + 2 * (sb.load_functional_volume - so.load_functional) +
                  st.load_functional,
              1e-9 * sb.load_functional);
}

TEST(NeoHookean, AFailingIncrementIsHalvedUntilItConverges) {
  // A load that one Newton increment from rest cannot take (the tangent of a far iterate is not
  // positive definite, or an iterate inverts a cell): without cuts the solve fails, with them it
  // converges to the solution of many small increments.
  Cantilever c(12.0, 2);
  fem::NewtonOptions once;
  once.max_load_cuts = 0;
  EXPECT_THROW(fem::solve_neo_hookean(c.mesh, c.space, c.problem, {}, once), SolverError);
  fem::NewtonOptions cut;
  const auto sol = fem::solve_neo_hookean(c.mesh, c.space, c.problem, {}, cut);
  EXPECT_GT(sol.load_cuts, 0);
  EXPECT_LE(sol.load_cuts, cut.max_load_cuts);
  fem::NewtonOptions fine;
  fine.load_steps = 16;
  fine.max_load_cuts = 0;
  const auto ref = fem::solve_neo_hookean(c.mesh, c.space, c.problem, {}, fine);
  std::printf("load cuts %d, %zu iterations; max |u| %.4f (16 steps: %.4f)\n", sol.load_cuts,
              sol.newton.size(), sol.u.cwiseAbs().maxCoeff(), ref.u.cwiseAbs().maxCoeff());
  EXPECT_LT((sol.u - ref.u).norm() / ref.u.norm(), 1e-6);
  // The history holds the accepted increments only, at rising loads ending at the full one.
  double last = 0;
  for (const auto& s : sol.newton) {
    EXPECT_GE(s.load, last);
    last = s.load;
  }
  EXPECT_EQ(last, 1.0);
  const fem::ForceBalance fb = fem::force_balance(c.mesh, c.space, c.problem, sol.u, true);
  EXPECT_LT(fb.imbalance(), 1e-8);
}

// Solves sharing a FactorizationCache (load cases, the shifted values' re-solves) assemble the
// stiffness once: the second solve takes the kept one and gives the fresh solve's answer bit for
// bit; another material, or another space, assembles again.
TEST(LinearElasticity, SolvesSharingACacheAssembleTheStiffnessOnce) {
  const LagrangeMesh mesh = make_cube_tets(2);
  const fem::FunctionSpace space = fem::build_function_space(mesh, 2);
  const fem::ElasticMaterial m{2.0, 0.3};
  const test::ExponentialDisplacement ex{m.lambda(), m.mu()};
  fem::LinearSolverOptions fresh;
  fresh.type = fem::SolverType::direct;
  fem::LinearSolverOptions cached = fresh;
  cached.factorization_cache = std::make_shared<fem::FactorizationCache>();
  fem::ElasticityProblem a = clamped_problem(space, ex, m);
  fem::ElasticityProblem b = a;  // another load on the same operator
  b.body_force = [](const Eigen::Vector3d& x) { return Eigen::Vector3d(x[2], 1.0, -x[0]); };
  const auto ua = fem::solve_linear_elasticity(mesh, space, a, cached);
  const auto ub = fem::solve_linear_elasticity(mesh, space, b, cached);
  EXPECT_EQ(cached.factorization_cache->assemblies(), 1);
  EXPECT_EQ(cached.factorization_cache->assembly_reuses(), 1);
  EXPECT_EQ(ub.u, fem::solve_linear_elasticity(mesh, space, b, fresh).u);
  EXPECT_EQ(ua.u, fem::solve_linear_elasticity(mesh, space, a, fresh).u);
  // Another material: assembled again (and its answer is the fresh one's).
  const fem::ElasticityProblem c = clamped_problem(space, ex, {3.0, 0.25});
  EXPECT_EQ(fem::solve_linear_elasticity(mesh, space, c, cached).u,
            fem::solve_linear_elasticity(mesh, space, c, fresh).u);
  EXPECT_EQ(cached.factorization_cache->assemblies(), 2);
  // Another space on the same mesh: assembled again.
  const fem::FunctionSpace p3 = fem::build_function_space(mesh, 3);
  const fem::ElasticityProblem d = clamped_problem(p3, ex, {3.0, 0.25});
  EXPECT_EQ(fem::solve_linear_elasticity(mesh, p3, d, cached).u,
            fem::solve_linear_elasticity(mesh, p3, d, fresh).u);
  EXPECT_EQ(cached.factorization_cache->assemblies(), 3);
  EXPECT_EQ(cached.factorization_cache->assembly_reuses(), 1);
}
