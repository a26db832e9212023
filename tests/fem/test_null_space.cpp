// Pure Neumann Poisson and traction-only elasticity (fem/problems/null_space.hpp): solutions up
// to constants / rigid motions, compatibility of the data, errors modulo the null space.
#include <gtest/gtest.h>

#include <cmath>
#include <mutex>
#include <string>
#include <vector>

#include "fem/problems/elasticity.hpp"
#include "fem/problems/null_space.hpp"
#include "fem/problems/poisson.hpp"
#include "meshing/core/error.hpp"
#include "meshing/core/log.hpp"
#include "meshing/core/primitives.hpp"
#include "tests/fem/manufactured.hpp"

using namespace curvefem;

namespace {

/// Collects warnings while alive.
struct WarningCapture {
  std::vector<std::string> lines;
  std::mutex mutex;
  WarningCapture() {
    log::set_sink([this](log::Level level, std::string_view s) {
      if (level != log::Level::warn) return;
      std::lock_guard lock(mutex);
      lines.emplace_back(s);
    });
  }
  ~WarningCapture() { log::set_sink({}); }
};

// u = exp(0.5 x + 0.3 y) cos(0.7 z) + x y z + 5: −Δu = 0.15 exp(0.5 x + 0.3 y) cos(0.7 z).
double u_exact(const Eigen::Vector3d& x) {
  return std::exp(0.5 * x[0] + 0.3 * x[1]) * std::cos(0.7 * x[2]) + x[0] * x[1] * x[2] + 5.0;
}
Eigen::Vector3d grad_exact(const Eigen::Vector3d& x) {
  const double e = std::exp(0.5 * x[0] + 0.3 * x[1]);
  return Eigen::Vector3d(0.5 * e * std::cos(0.7 * x[2]) + x[1] * x[2],
                         0.3 * e * std::cos(0.7 * x[2]) + x[0] * x[2],
                         -0.7 * e * std::sin(0.7 * x[2]) + x[0] * x[1]);
}

fem::PoissonProblem neumann_poisson(const fem::FunctionSpace& space, double f_shift = 0.0) {
  fem::PoissonProblem problem;
  problem.rhs = [f_shift](const Eigen::Vector3d& x) {
    return 0.15 * std::exp(0.5 * x[0] + 0.3 * x[1]) * std::cos(0.7 * x[2]) + f_shift;
  };
  problem.neumann.push_back(
      {std::vector<char>(space.boundary_faces.size(), 1),
       [](const Eigen::Vector3d& x, const Eigen::Vector3d& n) { return grad_exact(x).dot(n); },
       {}});
  return problem;
}

fem::ErrorNorms poisson_errors(const LagrangeMesh& mesh, const fem::FunctionSpace& space,
                               const Eigen::VectorXd& u, Eigen::VectorXd* offset = nullptr) {
  return fem::compute_errors_modulo_null_space(
      mesh, space, fem::null_space_modes(mesh, space, 1), u,
      [](const Eigen::Vector3d& x, double* v) { *v = u_exact(x); },
      [](const Eigen::Vector3d& x, double* g) {
        Eigen::Map<Eigen::Vector3d> m(g);
        m = grad_exact(x);
      },
      offset);
}

double integral(const LagrangeMesh& mesh, const fem::FunctionSpace& space, int c,
                const Eigen::VectorXd& u, int mode) {
  return fem::null_space_modes(mesh, space, c).moments.col(mode).dot(u);
}

}  // namespace

TEST(PureNeumannPoisson, OptimalRatesMeanZeroAndTheSameSolutionByCg) {
  fem::LinearSolverOptions direct, cg;
  direct.type = fem::SolverType::direct;
  cg.type = fem::SolverType::cg;
  cg.rtol = 1e-12;
  const int base[3] = {0, 4, 2};
  for (int p = 1; p <= 2; ++p) {
    std::vector<fem::ErrorNorms> e;
    for (int level = 0; level < 2; ++level) {
      const LagrangeMesh mesh = make_cube_tets(base[p] << level);
      const fem::FunctionSpace space = fem::build_function_space(mesh, p);
      const auto sol = fem::solve_poisson(mesh, space, neumann_poisson(space), direct);
      EXPECT_EQ(sol.null_space_dim, 1);
      EXPECT_EQ(sol.solve.null_space_dim, 1);
      // Data compatible up to quadrature: ∫f = −∫g.
      EXPECT_TRUE(sol.compatibility.compatible()) << sol.compatibility.relative;
      EXPECT_NEAR(sol.rhs_integral, -sol.flux_integral, 1e-6 * std::abs(sol.rhs_integral));
      // Reported with mean zero.
      EXPECT_LT(std::abs(integral(mesh, space, 1, sol.u, 0)), 1e-12);
      Eigen::VectorXd offset;
      e.push_back(poisson_errors(mesh, space, sol.u, &offset));
      // The constant taken out is minus the mean of u (u_h has mean zero): about −6.3.
      EXPECT_LT(offset[0], -6.0);
      std::printf("p=%d n=%d L2 %.3e H1 %.3e offset %.6f imbalance %.2e\n", p, base[p] << level,
                  e.back().l2, e.back().h1_semi, offset[0], sol.compatibility.relative);
      if (level == 1) {
        const auto by_cg = fem::solve_poisson(mesh, space, neumann_poisson(space), cg);
        EXPECT_EQ(by_cg.solve.method, "petsc-cg-gamg");
        EXPECT_LT((by_cg.u - sol.u).norm(), 1e-8 * sol.u.norm());
        EXPECT_GT(by_cg.solve.iterations, 0);
        EXPECT_LT(by_cg.solve.iterations, 40);
      }
    }
    const double r_l2 = test::rate(e[0].l2, e[1].l2), r_h1 = test::rate(e[0].h1_semi, e[1].h1_semi);
    EXPECT_NEAR(r_l2, p + 1, 0.3) << "p=" << p;
    EXPECT_NEAR(r_h1, p, 0.3) << "p=" << p;
    EXPECT_LT(e[1].l2, 1e-2 * e[1].l2_exact) << "p=" << p;
  }
}

TEST(PureNeumannPoisson, IncompatibleDataWarnWithTheirIntegralAndLoseOnlyTheirMean) {
  const LagrangeMesh mesh = make_cube_tets(3);
  const fem::FunctionSpace space = fem::build_function_space(mesh, 2);
  const auto good = fem::solve_poisson(mesh, space, neumann_poisson(space), {});
  WarningCapture warnings;
  const auto bad = fem::solve_poisson(mesh, space, neumann_poisson(space, 1.0), {});
  // f + 1 on the unit cube: ∫f + ∫g grows by 1; the solve removes exactly the mean of f.
  EXPECT_NEAR(bad.compatibility.resultant[0] - good.compatibility.resultant[0], 1.0, 1e-12);
  EXPECT_FALSE(bad.compatibility.compatible());
  EXPECT_LT((bad.u - good.u).norm(), 1e-10 * good.u.norm());
  ASSERT_EQ(warnings.lines.size(), 1u);
  EXPECT_NE(warnings.lines[0].find("not compatible"), std::string::npos) << warnings.lines[0];
  EXPECT_NE(warnings.lines[0].find("integral of f"), std::string::npos) << warnings.lines[0];
}

namespace {

fem::ElasticityProblem traction_only(const fem::FunctionSpace& space,
                                     const test::ExponentialDisplacement& ex,
                                     const fem::ElasticMaterial& m) {
  fem::ElasticityProblem problem;
  problem.material = m;
  problem.body_force = [ex](const Eigen::Vector3d& x) { return ex.body_force(x); };
  const double lambda = m.lambda(), mu = m.mu();
  problem.traction.push_back({std::vector<char>(space.boundary_faces.size(), 1),
                              [ex, lambda, mu](const Eigen::Vector3d& x, const Eigen::Vector3d& n) {
                                const Eigen::Matrix3d g = ex.gradient(x);
                                const Eigen::Matrix3d eps = 0.5 * (g + g.transpose());
                                const Eigen::Matrix3d sigma =
                                    lambda * eps.trace() * Eigen::Matrix3d::Identity() +
                                    2 * mu * eps;
                                return Eigen::Vector3d(sigma * n);
                              },
                              {}});
  return problem;
}

/// Errors modulo rigid motions against ex + (a + ω × x).
fem::ErrorNorms elastic_errors(const LagrangeMesh& mesh, const fem::FunctionSpace& space,
                               const Eigen::VectorXd& u, const test::ExponentialDisplacement& ex,
                               const Eigen::Vector3d& a = Eigen::Vector3d::Zero(),
                               const Eigen::Vector3d& w = Eigen::Vector3d::Zero()) {
  Eigen::Matrix3d W;
  W << 0, -w[2], w[1], w[2], 0, -w[0], -w[1], w[0], 0;  // W x = ω × x
  return fem::compute_errors_modulo_null_space(
      mesh, space, fem::null_space_modes(mesh, space, 3), u,
      [&](const Eigen::Vector3d& x, double* v) {
        Eigen::Map<Eigen::Vector3d> m(v);
        m = ex.value(x) + a + W * x;
      },
      [&](const Eigen::Vector3d& x, double* g) {
        Eigen::Map<Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> m(g);
        m = ex.gradient(x) + W;
      });
}

}  // namespace

TEST(TractionOnlyElasticity, OptimalRatesAndNoRigidMotionLeft) {
  const fem::ElasticMaterial m{1.0, 0.3};
  const test::ExponentialDisplacement ex{m.lambda(), m.mu()};
  const int base[3] = {0, 3, 2};
  for (int p = 1; p <= 2; ++p) {
    std::vector<fem::ErrorNorms> e;
    for (int level = 0; level < 2; ++level) {
      const LagrangeMesh mesh = make_cube_tets(base[p] << level);
      const fem::FunctionSpace space = fem::build_function_space(mesh, p);
      const auto sol = fem::solve_linear_elasticity(mesh, space, traction_only(space, ex, m), {});
      EXPECT_EQ(sol.null_space_dim, 6);
      EXPECT_TRUE(sol.compatibility.compatible()) << sol.compatibility.relative;
      // No mean translation or rotation left in u_h.
      const fem::NullSpaceModes modes = fem::null_space_modes(mesh, space, 3);
      EXPECT_LT((modes.moments.transpose() * sol.u).cwiseAbs().maxCoeff(), 1e-12);
      e.push_back(elastic_errors(mesh, space, sol.u, ex));
      // A rigid motion added to the exact solution does not change the data nor the errors.
      const fem::ErrorNorms moved =
          elastic_errors(mesh, space, sol.u, ex, {0.3, -1.0, 2.0}, {0.5, 0.2, -0.7});
      EXPECT_NEAR(moved.l2, e.back().l2, 1e-9 * e.back().l2);
      EXPECT_NEAR(moved.h1_semi, e.back().h1_semi, 1e-9 * e.back().h1_semi);
      std::printf("p=%d n=%d L2 %.3e H1 %.3e imbalance %.2e\n", p, base[p] << level, e.back().l2,
                  e.back().h1_semi, sol.compatibility.relative);
    }
    const double r_l2 = test::rate(e[0].l2, e[1].l2), r_h1 = test::rate(e[0].h1_semi, e[1].h1_semi);
    EXPECT_NEAR(r_l2, p + 1, 0.35) << "p=" << p;
    EXPECT_NEAR(r_h1, p, 0.3) << "p=" << p;
  }
}

TEST(TractionOnlyElasticity, UnbalancedLoadWarnsWithForceAndMoment) {
  const fem::ElasticMaterial m{1.0, 0.3};
  const test::ExponentialDisplacement ex{m.lambda(), m.mu()};
  const LagrangeMesh mesh = make_cube_tets(2);
  const fem::FunctionSpace space = fem::build_function_space(mesh, 2);
  const auto good = fem::solve_linear_elasticity(mesh, space, traction_only(space, ex, m), {});
  // Plus a uniform pull (0, 0, 2) on the face x = 1 (area 1): total force (0, 0, 2), moment
  // about the center (0.5, 0.5, 0.5) = (0.5, 0, 0) × (0, 0, 2) = (0, −1, 0).
  fem::ElasticityProblem problem = traction_only(space, ex, m);
  std::vector<char> right(space.boundary_faces.size(), 0);
  for (std::size_t f = 0; f < right.size(); ++f) {
    const auto [cell, j] = space.boundary_faces[f];
    bool all = true;
    for (int i = 0; i < 4; ++i)
      if (i != j) all = all && mesh.nodes(mesh.cells(cell, i), 0) > 1 - 1e-12;
    right[f] = all;
  }
  problem.traction.push_back(
      {right,
       [](const Eigen::Vector3d&, const Eigen::Vector3d&) { return Eigen::Vector3d(0, 0, 2); },
       {}});
  WarningCapture warnings;
  const auto bad = fem::solve_linear_elasticity(mesh, space, problem, {});
  const Eigen::VectorXd extra = bad.compatibility.resultant - good.compatibility.resultant;
  EXPECT_LT((extra.head<3>() - Eigen::Vector3d(0, 0, 2)).norm(), 1e-12);
  EXPECT_LT((bad.compatibility.center - Eigen::Vector3d(0.5, 0.5, 0.5)).norm(), 1e-12);
  EXPECT_LT((extra.tail<3>() - Eigen::Vector3d(0, -1, 0)).norm(), 1e-12);
  EXPECT_FALSE(bad.compatibility.compatible());
  ASSERT_EQ(warnings.lines.size(), 1u);
  EXPECT_NE(warnings.lines[0].find("not in equilibrium"), std::string::npos) << warnings.lines[0];
  EXPECT_NE(warnings.lines[0].find("total moment"), std::string::npos) << warnings.lines[0];
}

TEST(TractionOnlyElasticity, NeoHookeanWithoutDirichletIsAnInputError) {
  const LagrangeMesh mesh = make_cube_tets(1);
  const fem::FunctionSpace space = fem::build_function_space(mesh, 1);
  fem::ElasticityProblem problem;
  EXPECT_THROW(fem::solve_neo_hookean(mesh, space, problem, {}, {}), InputError);
}
