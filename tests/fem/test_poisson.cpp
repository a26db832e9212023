#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>

#include "fem/problems/error_norms.hpp"
#include "fem/problems/poisson.hpp"
#include "meshing/core/error.hpp"
#include "meshing/core/primitives.hpp"
#include "tests/fem/manufactured.hpp"

using namespace curvefem;

namespace {

fem::ErrorNorms solve_and_measure(
    const LagrangeMesh& mesh, int p, const fem::ScalarField& exact,
    const std::function<Eigen::Vector3d(const Eigen::Vector3d&)>& grad, const fem::ScalarField& f,
    const std::string& solver = "direct", int* dofs = nullptr) {
  const fem::FunctionSpace space = fem::build_function_space(mesh, p);
  fem::PoissonProblem problem;
  problem.rhs = f;
  problem.dirichlet.push_back({std::vector<char>(space.boundary_faces.size(), 1), exact, {}});
  fem::LinearSolverOptions options;
  options.type = fem::solver_type_from(solver);
  const auto sol = fem::solve_poisson(mesh, space, problem, options);
  if (dofs) *dofs = space.num_dofs;
  return fem::compute_errors(
      mesh, space, sol.u, 1, [&](const Eigen::Vector3d& x, double* v) { *v = exact(x); },
      [&](const Eigen::Vector3d& x, double* g) {
        Eigen::Map<Eigen::Vector3d> m(g);
        m = grad(x);
      });
}

}  // namespace

TEST(Poisson, PatchTestReproducesPolynomialsOfDegreeP) {
  const LagrangeMesh mesh = make_cube_tets(2);
  for (int p = 1; p <= 4; ++p) {
    auto s = [](const Eigen::Vector3d& x) { return 1 + 0.3 * x[0] + 0.5 * x[1] - 0.2 * x[2]; };
    const double c2 = 0.09 + 0.25 + 0.04;
    auto u = [&](const Eigen::Vector3d& x) { return std::pow(s(x), p); };
    auto grad = [&](const Eigen::Vector3d& x) -> Eigen::Vector3d {
      return Eigen::Vector3d(0.3, 0.5, -0.2) * (p * std::pow(s(x), p - 1));
    };
    auto f = [&](const Eigen::Vector3d& x) {
      return p > 1 ? -p * (p - 1) * c2 * std::pow(s(x), p - 2) : 0.0;
    };
    const auto e = solve_and_measure(mesh, p, u, grad, f);
    EXPECT_LT(e.l2, 1e-11) << "p=" << p;
    EXPECT_LT(e.h1_semi, 1e-10) << "p=" << p;
  }
}

TEST(Poisson, CurvedIsoparametricMeshReproducesLinearFunctions) {
  auto deform = [](const Eigen::Vector3d& x) {
    return Eigen::Vector3d(
        x + 0.05 * Eigen::Vector3d(std::sin(3 * x[1]), x[0] * x[2], std::cos(2 * x[0])));
  };
  for (int k = 2; k <= 3; ++k) {
    const LagrangeMesh mesh = elevate_order(make_cube_tets(2), k, deform);
    for (int p = k; p <= 4; ++p) {
      auto u = [](const Eigen::Vector3d& x) { return 1 + 2 * x[0] - x[1] + 0.5 * x[2]; };
      auto grad = [](const Eigen::Vector3d&) { return Eigen::Vector3d(2, -1, 0.5); };
      const auto e = solve_and_measure(mesh, p, u, grad, {});
      EXPECT_LT(e.l2, 1e-11) << "k=" << k << " p=" << p;
      EXPECT_LT(e.h1_semi, 1e-10) << "k=" << k << " p=" << p;
    }
  }
}

namespace {
std::vector<fem::ErrorNorms> franke_levels(int p, const std::vector<int>& levels) {
  std::vector<fem::ErrorNorms> e;
  for (int n : levels) {
    const LagrangeMesh mesh = make_cube_tets(n);
    // Large systems through CG + AMG: same answer (see IterativeSolverMatchesDirect), faster.
    const std::string solver = n * p > 30 ? "cg" : "direct";
    e.push_back(solve_and_measure(
        mesh, p, test::Franke::value, test::Franke::gradient,
        [](const Eigen::Vector3d& x) { return -test::Franke::laplacian(x); }, solver));
  }
  std::printf("p=%d  L2 %.3e %.3e %.3e (rate %.2f)  H1 %.3e %.3e %.3e (rate %.2f)\n", p, e[0].l2,
              e[1].l2, e[2].l2, test::rate(e[1].l2, e[2].l2), e[0].h1_semi, e[1].h1_semi,
              e[2].h1_semi, test::rate(e[1].h1_semi, e[2].h1_semi));
  return e;
}
}  // namespace

TEST(Poisson, ConvergenceRatesOnCubeWithFrankeSolution) {
  // The thesis's solution (§5.4.4) on the unit cube; levels n, 2n, 4n, rates from the last pair:
  // L2 p+1 and H1 p within ±0.25. Its narrowest Gaussian has width 1/9, so coarse meshes are
  // pre-asymptotic (measured here: H1 rate 0.91 for p = 1 at n = 4 → 8); levels are chosen so
  // the last pair is asymptotic, up to ~120k DOFs.
  const std::vector<int> levels[4] = {{8, 16, 32}, {4, 8, 16}, {4, 8, 16}, {3, 6, 12}};
  for (int p = 1; p <= 3; ++p) {
    const auto e = franke_levels(p, levels[p - 1]);
    EXPECT_NEAR(test::rate(e[1].l2, e[2].l2), p + 1, 0.25) << "p=" << p;
    EXPECT_NEAR(test::rate(e[1].h1_semi, e[2].h1_semi), p, 0.25) << "p=" << p;
  }
  // p = 4 does not reach its asymptotic range on this solution below ~300k DOFs: measured rates
  // n = 3 → 6: L2 4.26, H1 3.13; n = 6 → 12: L2 4.56, H1 3.52 — below optimal and still rising.
  // Asserted: the rates rise with refinement and exceed p + 1 − 0.75 / p − 0.75; the optimal P4
  // rates (±0.25) are asserted on a smooth solution in the next test.
  const auto e = franke_levels(4, levels[3]);
  EXPECT_GT(test::rate(e[1].l2, e[2].l2), test::rate(e[0].l2, e[1].l2));
  EXPECT_GT(test::rate(e[1].h1_semi, e[2].h1_semi), test::rate(e[0].h1_semi, e[1].h1_semi));
  EXPECT_GT(test::rate(e[1].l2, e[2].l2), 5 - 0.75);
  EXPECT_GT(test::rate(e[1].h1_semi, e[2].h1_semi), 4 - 0.75);
}

TEST(Poisson, ConvergenceRatesOnCubeWithSmoothSolution) {
  // u = exp(x/2) sin(y + z/2): −Δu = u.
  const auto u = &test::ExpSine::value;
  const auto grad = &test::ExpSine::gradient;
  for (int p = 1; p <= 4; ++p) {
    std::vector<fem::ErrorNorms> e;
    for (int n : {2, 4, 8}) e.push_back(solve_and_measure(make_cube_tets(n), p, u, grad, u));
    const double r_l2 = test::rate(e[1].l2, e[2].l2), r_h1 = test::rate(e[1].h1_semi, e[2].h1_semi);
    std::printf("smooth p=%d  L2 %.3e %.3e %.3e (rate %.2f)  H1 %.3e %.3e %.3e (rate %.2f)\n", p,
                e[0].l2, e[1].l2, e[2].l2, r_l2, e[0].h1_semi, e[1].h1_semi, e[2].h1_semi, r_h1);
    EXPECT_NEAR(r_l2, p + 1, 0.25) << "p=" << p;
    EXPECT_NEAR(r_h1, p, 0.25) << "p=" << p;
  }
}

TEST(Poisson, IterativeSolverMatchesDirect) {
  const LagrangeMesh mesh = make_cube_tets(4);
  int dofs = 0;
  auto f = [](const Eigen::Vector3d& x) { return -test::Franke::laplacian(x); };
  const auto direct =
      solve_and_measure(mesh, 2, test::Franke::value, test::Franke::gradient, f, "direct", &dofs);
  const auto cg = solve_and_measure(mesh, 2, test::Franke::value, test::Franke::gradient, f, "cg");
  EXPECT_GT(dofs, 500);
  EXPECT_NEAR(cg.l2, direct.l2, 1e-6 * direct.l2);
}

TEST(Poisson, InvertedElementIsASolverErrorNamingIt) {
  LagrangeMesh mesh = make_cube_tets(1);
  std::swap(mesh.cells(3, 1), mesh.cells(3, 2));  // flip cell 3
  const fem::FunctionSpace space = fem::build_function_space(mesh, 1);
  fem::PoissonProblem problem;
  problem.dirichlet.push_back({std::vector<char>(space.boundary_faces.size(), 1),
                               [](const Eigen::Vector3d&) { return 0.0; },
                               {}});
  try {
    fem::solve_poisson(mesh, space, problem, {});
    FAIL() << "expected SolverError";
  } catch (const SolverError& e) {
    EXPECT_EQ(e.context().element, 3);
  }
}

TEST(Poisson, TheBatchedLoadEqualsThePointwiseOne) {
  // rhs_batch (the load over a cell's points at once) against rhs on the same mesh, P1..P3: the
  // load vectors agree to rounding, and an rhs_batch that disagrees with rhs wins.
  const LagrangeMesh mesh = make_cube_tets(3);
  auto f = [](const Eigen::Vector3d& x) { return std::exp(x[0]) * std::cos(2 * x[1]) + x[2]; };
  for (int p = 1; p <= 3; ++p) {
    SCOPED_TRACE(p);
    const fem::FunctionSpace space = fem::build_function_space(mesh, p);
    fem::PoissonProblem pointwise;
    pointwise.rhs = f;
    fem::PoissonProblem batched;
    batched.rhs = [](const Eigen::Vector3d&) { return 1e6; };  // ignored where rhs_batch is set
    batched.rhs_batch = [&](const Eigen::MatrixXd& x, Eigen::VectorXd& v) {
      ASSERT_EQ(v.size(), x.rows());
      for (Eigen::Index q = 0; q < x.rows(); ++q) v[q] = f(x.row(q).transpose());
    };
    const fem::AssembledSystem a = fem::assemble_poisson(mesh, space, pointwise);
    const fem::AssembledSystem b = fem::assemble_poisson(mesh, space, batched);
    ASSERT_EQ(a.F.size(), b.F.size());
    EXPECT_GT(a.F.norm(), 1e-3);
    EXPECT_LE((a.F - b.F).lpNorm<Eigen::Infinity>(), 1e-14 * a.F.lpNorm<Eigen::Infinity>());
  }
}

TEST(Poisson, StraightCellsWithAConstantKappaUseTheReferenceTensorsExactly) {
  // A constant κ (kappa_value) on straight cells takes the reference-tensor kernel; a κ given as a
  // field takes the point loop. Both must give the same stiffness matrix to rounding, on generic
  // (perturbed) tets, P1..P4, with a κ other than 1; and on a curved mesh (order 2) the constant
  // κ keeps the point loop, so the two agree there too.
  LagrangeMesh mesh = make_cube_tets(3);
  std::uint32_t state = 12345;
  auto jitter = [&state] {
    state = state * 1664525u + 1013904223u;
    return (double(state >> 8) / double(1u << 24) - 0.5) * 0.08;  // ± 0.04 of a 1/3 cell
  };
  for (Eigen::Index v = 0; v < mesh.nodes.rows(); ++v)
    for (int d = 0; d < 3; ++d) mesh.nodes(v, d) += jitter();
  const double kappa = 2.75;
  for (int k : {1, 2}) {
    const LagrangeMesh m =
        k == 1 ? mesh : elevate_order(mesh, 2, [](const Eigen::Vector3d& x) { return x; });
    for (int p = 1; p <= 4; ++p) {
      SCOPED_TRACE("order " + std::to_string(k) + ", P" + std::to_string(p));
      const fem::FunctionSpace space = fem::build_function_space(m, p);
      fem::PoissonProblem field;
      field.kappa = [kappa](const Eigen::Vector3d&) { return kappa; };
      fem::PoissonProblem constant;
      constant.kappa_value = kappa;
      const fem::AssembledSystem a = fem::assemble_poisson(m, space, field);
      const fem::AssembledSystem b = fem::assemble_poisson(m, space, constant);
      ASSERT_EQ(a.K.nonZeros(), b.K.nonZeros());
      const double scale = Eigen::Map<const Eigen::VectorXd>(a.K.valuePtr(), a.K.nonZeros())
                               .lpNorm<Eigen::Infinity>();
      EXPECT_GT(scale, 1.0);
      const Eigen::VectorXd diff =
          Eigen::Map<const Eigen::VectorXd>(a.K.valuePtr(), a.K.nonZeros()) -
          Eigen::Map<const Eigen::VectorXd>(b.K.valuePtr(), b.K.nonZeros());
      EXPECT_LE(diff.lpNorm<Eigen::Infinity>(), 1e-13 * scale);
      // The row sums of a stiffness matrix vanish (constants are in its kernel).
      EXPECT_LE((b.K * Eigen::VectorXd::Ones(b.K.cols())).lpNorm<Eigen::Infinity>(), 1e-12 * scale);
    }
  }
}
