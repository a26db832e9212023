// Weak boundary terms: Neumann flux and traction reproduce exact polynomial solutions, Dirichlet
// data on faces a filter selects in part (Nitsche) too, and the curved face quadrature satisfies
// the divergence theorem on the discrete geometry.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "fem/assembly/element_geometry.hpp"
#include "fem/assembly/face_integration.hpp"
#include "fem/problems/elasticity.hpp"
#include "fem/problems/error_norms.hpp"
#include "fem/problems/poisson.hpp"
#include "fem/quadrature/simplex_quadrature.hpp"
#include "meshing/core/error.hpp"
#include "meshing/core/primitives.hpp"
#include "meshing/io/cad_part.hpp"
#include "tests/fem/manufactured.hpp"

using namespace curvefem;

namespace {
/// Flags of the boundary faces of the unit cube lying on x = 0 (left) and the others.
void split_cube_faces(const LagrangeMesh& mesh, const fem::FunctionSpace& space,
                      std::vector<char>& left, std::vector<char>& others) {
  left.assign(space.boundary_faces.size(), 0);
  others.assign(space.boundary_faces.size(), 0);
  for (std::size_t f = 0; f < space.boundary_faces.size(); ++f) {
    const auto [cell, j] = space.boundary_faces[f];
    double xmax = -1;
    for (int i = 0; i < 4; ++i)
      if (i != j) xmax = std::max(xmax, mesh.nodes(mesh.cells(cell, i), 0));
    (xmax < 1e-12 ? left : others)[f] = 1;
  }
}
/// Outward unit normal of the unit cube at a point inside one of the faces other than x = 0.
Eigen::Vector3d cube_normal(const Eigen::Vector3d& x) {
  Eigen::Vector3d n = Eigen::Vector3d::Zero();
  for (int d = 0; d < 3; ++d)
    if (x[d] > 1 - 1e-12)
      n[d] = 1;
    else if (x[d] < 1e-12 && d > 0)
      n[d] = -1;
  return n.normalized();
}
}  // namespace

TEST(BoundaryTerms, PoissonNeumannReproducesQuadratic) {
  const LagrangeMesh mesh = make_cube_tets(3);
  const fem::FunctionSpace space = fem::build_function_space(mesh, 2);
  auto u = [](const Eigen::Vector3d& x) { return x[0] * x[0] - 0.5 * x[1] * x[2] + x[1]; };
  auto grad = [](const Eigen::Vector3d& x) -> Eigen::Vector3d {
    return Eigen::Vector3d(2 * x[0], -0.5 * x[2] + 1, -0.5 * x[1]);
  };
  std::vector<char> left, others;
  split_cube_faces(mesh, space, left, others);
  fem::PoissonProblem problem;
  problem.rhs = [](const Eigen::Vector3d&) { return -2.0; };
  problem.dirichlet.push_back({left, u, {}});
  // Flux g = ∇u · n with the normal the assembly passes (the mesh's outward normal), which must
  // be each cube side's outward normal.
  problem.neumann.push_back({others,
                             [&](const Eigen::Vector3d& x, const Eigen::Vector3d& n) {
                               EXPECT_LT((n - cube_normal(x)).norm(), 1e-12);
                               return grad(x).dot(n);
                             },
                             {}});
  const auto sol = fem::solve_poisson(mesh, space, problem, {});
  double worst = 0;
  for (int d = 0; d < space.num_dofs; ++d)
    worst = std::max(worst, std::abs(sol.u[d] - u(space.dof_points.row(d).transpose())));
  EXPECT_LT(worst, 1e-10);
}

TEST(BoundaryTerms, ElasticityTractionReproducesLinearDisplacement) {
  const LagrangeMesh mesh = make_cube_tets(2);
  const fem::FunctionSpace space = fem::build_function_space(mesh, 2);
  const fem::ElasticMaterial m{3.0, 0.25};
  const Eigen::Matrix3d A =
      (Eigen::Matrix3d() << 0.1, 0.02, 0.0, -0.03, 0.05, 0.01, 0.02, 0.0, -0.04).finished();
  const Eigen::Matrix3d eps = 0.5 * (A + A.transpose());
  const Eigen::Matrix3d sigma =
      m.lambda() * eps.trace() * Eigen::Matrix3d::Identity() + 2 * m.mu() * eps;
  std::vector<char> left, others;
  split_cube_faces(mesh, space, left, others);
  fem::ElasticityProblem problem;
  problem.material = m;
  problem.dirichlet.push_back({left,
                               {true, true, true},
                               [A](const Eigen::Vector3d& x) { return Eigen::Vector3d(A * x); },
                               {}});
  problem.traction.push_back({others,
                              [sigma](const Eigen::Vector3d&, const Eigen::Vector3d& n) {
                                return Eigen::Vector3d(
                                    sigma * n);  // the mesh's outward normal from the assembly
                              },
                              {}});
  const auto sol = fem::solve_linear_elasticity(mesh, space, problem, {});
  double worst = 0;
  for (int d = 0; d < space.num_dofs; ++d)
    worst =
        std::max(worst, (sol.u.segment<3>(3 * d) - A * space.dof_points.row(d).transpose()).norm());
  EXPECT_LT(worst, 1e-10);
}

TEST(BoundaryTerms, CurvedFaceQuadratureSatisfiesDivergenceTheorem) {
  // On the discrete curved ball: ∫∂Ω x·n ds = 3 |Ω| exactly (up to quadrature), and the area
  // converges to 4π with the geometric order.
  for (int k = 1; k <= 3; ++k) {
    const LagrangeMesh mesh = io::make_ball_mesh(1.0, 0.5, k);
    const fem::FunctionSpace space = fem::build_function_space(mesh, 1);
    const std::vector<char> all(space.boundary_faces.size(), 1);
    double area = 0, flux = 0;
    fem::for_each_face_point(mesh, space, all, 12, [&](int, int, const fem::FacePoint& p) {
      area += p.ds_w;
      flux += p.x.dot(p.normal) * p.ds_w;
    });
    const fem::QuadratureRule& rule = fem::tetrahedron_quadrature(12);
    const fem::GeometryEvaluator geometry(mesh, rule.points, rule.weights);
    double volume = 0;
    fem::CellGeometry g;
    for (int c = 0; c < mesh.num_cells(); ++c) {
      geometry.evaluate(c, g);
      volume += g.det_w.sum();
    }
    std::printf("k=%d: area %.8f (4π = %.8f), flux/3 %.10f, volume %.10f\n", k, area,
                4 * std::numbers::pi, flux / 3, volume);
    EXPECT_NEAR(flux / 3, volume, 1e-10 * volume) << "k=" << k;
    EXPECT_NEAR(area, 4 * std::numbers::pi, k == 1 ? 0.5 : 0.005) << "k=" << k;
  }
}

// Dirichlet where x < 0.37 and the flux where x >= 0.37, both point-wise on every boundary face
// of the unit cube (4³ cells: the plane cuts faces). A polynomial u in the space is reproduced
// exactly when the cut faces are imposed by Nitsche's method (it is consistent, and the two
// filters are complementary at every quadrature point); fixing the DOFs the filter passes
// (nodal) leaves the flux missing on the Dirichlet part of the cut faces.
namespace {
constexpr double kCut = 0.37;
bool dirichlet_side(const Eigen::Vector3d& x) { return x[0] < kCut; }

struct CutCube {
  LagrangeMesh mesh = make_cube_tets(4);
  fem::FunctionSpace space;
  std::vector<char> all;
  explicit CutCube(int degree) : space(fem::build_function_space(mesh, degree)) {
    all.assign(space.boundary_faces.size(), 1);
  }
};

double poisson_cut_error(int degree, fem::PartialDirichlet mode, int* nitsche_faces) {
  CutCube c(degree);
  auto u = [](const Eigen::Vector3d& x) { return x[0] * x[0] - 0.5 * x[1] * x[2] + x[1]; };
  fem::PoissonProblem problem;
  problem.kappa = [](const Eigen::Vector3d&) { return 2.0; };
  problem.rhs = [](const Eigen::Vector3d&) { return -4.0; };  // −∇·(2∇u)
  problem.partial_dirichlet = mode;
  problem.dirichlet.push_back({c.all, u, dirichlet_side});
  problem.neumann.push_back({c.all,
                             [](const Eigen::Vector3d& x, const Eigen::Vector3d& n) {
                               return 2 *
                                      Eigen::Vector3d(2 * x[0], 1 - 0.5 * x[2], -0.5 * x[1]).dot(n);
                             },
                             [](const Eigen::Vector3d& x) { return !dirichlet_side(x); }});
  const auto sol = fem::solve_poisson(c.mesh, c.space, problem, {});
  *nitsche_faces = sol.nitsche_faces;
  double worst = 0;
  for (int d = 0; d < c.space.num_dofs; ++d)
    worst = std::max(worst, std::abs(sol.u[d] - u(c.space.dof_points.row(d).transpose())));
  return worst;
}
}  // namespace

TEST(BoundaryTerms, PartialDirichletFacesByNitscheReproducePoissonExactly) {
  for (int p = 2; p <= 3; ++p) {  // u is quadratic
    int faces = 0;
    // Measured (largest nodal error): Nitsche 6.7e-14 (p 2), 4.0e-14 (p 3); nodal 5.6e-2, 1.0e-2.
    const double nitsche = poisson_cut_error(p, fem::PartialDirichlet::nitsche, &faces);
    EXPECT_LT(nitsche, 1e-10) << "p " << p;
    EXPECT_EQ(faces, 32) << "p " << p;  // x = 0.37 cuts 2 faces per cell row on 4 sides
    const double nodal = poisson_cut_error(p, fem::PartialDirichlet::nodal, &faces);
    EXPECT_GT(nodal, 1e-3) << "p " << p;
    EXPECT_EQ(faces, 0);
  }
}

TEST(BoundaryTerms, PartialDirichletFacesByNitscheReproduceLinearElasticityExactly) {
  // u = A x (+ a quadratic part at p = 2) with one component free on the Dirichlet side: the
  // mask is honoured on the cut faces too.
  const fem::ElasticMaterial m{3.0, 0.3};
  const Eigen::Matrix3d A =
      (Eigen::Matrix3d() << 0.1, 0.02, 0.0, -0.03, 0.05, 0.01, 0.02, 0.0, -0.04).finished();
  const Eigen::Matrix3d eps = 0.5 * (A + A.transpose());
  const Eigen::Matrix3d sigma =
      m.lambda() * eps.trace() * Eigen::Matrix3d::Identity() + 2 * m.mu() * eps;
  for (const auto mode : {fem::PartialDirichlet::nitsche, fem::PartialDirichlet::nodal}) {
    CutCube c(2);
    fem::ElasticityProblem problem;
    problem.material = m;
    problem.partial_dirichlet = mode;
    // x, z fixed on the Dirichlet side; y everywhere on the far side x = 1 (removes the rigid
    // motion along y that the free component would leave).
    problem.dirichlet.push_back({c.all,
                                 {true, false, true},
                                 [A](const Eigen::Vector3d& x) { return Eigen::Vector3d(A * x); },
                                 dirichlet_side});
    problem.dirichlet.push_back({c.all,
                                 {false, true, false},
                                 [A](const Eigen::Vector3d& x) { return Eigen::Vector3d(A * x); },
                                 [](const Eigen::Vector3d& x) { return x[0] > 1 - 1e-12; }});
    // Traction: the full σn off the Dirichlet side, and its y component on the Dirichlet side.
    problem.traction.push_back({c.all,
                                [sigma](const Eigen::Vector3d& x, const Eigen::Vector3d& n) {
                                  Eigen::Vector3d t = sigma * n;
                                  if (dirichlet_side(x)) t[0] = t[2] = 0;
                                  return t;
                                },
                                {}});
    const auto sol = fem::solve_linear_elasticity(c.mesh, c.space, problem, {});
    double worst = 0;
    for (int d = 0; d < c.space.num_dofs; ++d)
      worst = std::max(
          worst, (sol.u.segment<3>(3 * d) - A * c.space.dof_points.row(d).transpose()).norm());
    if (mode == fem::PartialDirichlet::nitsche) {
      EXPECT_EQ(sol.nitsche_faces, 32);
      EXPECT_LT(worst, 1e-10);  // measured 7.5e-16
    } else {
      EXPECT_EQ(sol.nitsche_faces, 0);
      EXPECT_GT(worst, 1e-3);  // measured 5.1e-3
    }
  }
}

namespace {
// Robin data for u: −∂u/∂n = h (u − u∞) holds with u∞ = u + (∇u · n) / h (κ = 1).
fem::ScalarRobin robin_for(const std::vector<char>& faces, const fem::BoundaryScalarField& h,
                           const fem::ScalarField& u,
                           const std::function<Eigen::Vector3d(const Eigen::Vector3d&)>& grad) {
  return {faces,
          h,
          [h, u, grad](const Eigen::Vector3d& x, const Eigen::Vector3d& n) {
            return u(x) + grad(x).dot(n) / h(x, n);
          },
          {}};
}
}  // namespace

TEST(BoundaryTerms, PoissonRobinEverywhereReproducesQuadraticWithoutANullSpace) {
  // No Dirichlet condition: the Robin term alone makes the problem definite (a pure Neumann
  // problem would be solved up to a constant), and P2 holds the quadratic exactly.
  const LagrangeMesh mesh = make_cube_tets(3);
  const fem::FunctionSpace space = fem::build_function_space(mesh, 2);
  auto u = [](const Eigen::Vector3d& x) { return x[0] * x[0] - 0.5 * x[1] * x[2] + x[1] + 3; };
  auto grad = [](const Eigen::Vector3d& x) -> Eigen::Vector3d {
    return Eigen::Vector3d(2 * x[0], -0.5 * x[2] + 1, -0.5 * x[1]);
  };
  fem::PoissonProblem problem;
  problem.rhs = [](const Eigen::Vector3d&) { return -2.0; };
  problem.robin.push_back(robin_for(
      std::vector<char>(space.boundary_faces.size(), 1),
      [](const Eigen::Vector3d&, const Eigen::Vector3d&) { return 2.5; }, u, grad));
  const auto sol = fem::solve_poisson(mesh, space, problem, {});
  EXPECT_EQ(sol.null_space_dim, 0);
  double worst = 0;
  for (int d = 0; d < space.num_dofs; ++d)
    worst = std::max(worst, std::abs(sol.u[d] - u(space.dof_points.row(d).transpose())));
  EXPECT_LT(worst, 1e-10);
}

TEST(BoundaryTerms, PoissonRobinWithAVaryingCoefficientConvergesAtOptimalRates) {
  // u = exp(x/2) sin(y + z/2), −Δu = u; Dirichlet on x = 0, Robin with h = 1 + x + y on the
  // other five sides. Rates from n = 4 → 8: L2 p + 1, H1 p (±0.25), p = 1..3.
  const auto u = &test::ExpSine::value;
  const auto grad = &test::ExpSine::gradient;
  const fem::BoundaryScalarField h = [](const Eigen::Vector3d& x, const Eigen::Vector3d&) {
    return 1 + x[0] + x[1];
  };
  for (int p = 1; p <= 3; ++p) {
    std::vector<fem::ErrorNorms> e;
    for (int n : {2, 4, 8}) {
      const LagrangeMesh mesh = make_cube_tets(n);
      const fem::FunctionSpace space = fem::build_function_space(mesh, p);
      std::vector<char> left, others;
      split_cube_faces(mesh, space, left, others);
      fem::PoissonProblem problem;
      problem.rhs = u;
      problem.dirichlet.push_back({left, u, {}});
      problem.robin.push_back(robin_for(others, h, u, grad));
      const auto sol = fem::solve_poisson(mesh, space, problem, {});
      e.push_back(fem::compute_errors(
          mesh, space, sol.u, 1, [&](const Eigen::Vector3d& x, double* v) { *v = u(x); },
          [&](const Eigen::Vector3d& x, double* g) {
            Eigen::Map<Eigen::Vector3d> m(g);
            m = grad(x);
          }));
    }
    const double r_l2 = std::log2(e[1].l2 / e[2].l2), r_h1 = std::log2(e[1].h1_semi / e[2].h1_semi);
    std::printf("robin p=%d  L2 %.3e %.3e %.3e (rate %.2f)  H1 %.3e %.3e %.3e (rate %.2f)\n", p,
                e[0].l2, e[1].l2, e[2].l2, r_l2, e[0].h1_semi, e[1].h1_semi, e[2].h1_semi, r_h1);
    EXPECT_NEAR(r_l2, p + 1, 0.25) << "p=" << p;
    EXPECT_NEAR(r_h1, p, 0.25) << "p=" << p;
  }
}

TEST(BoundaryTerms, PoissonRobinWithANonPositiveCoefficientIsAnInputError) {
  const LagrangeMesh mesh = make_cube_tets(2);
  const fem::FunctionSpace space = fem::build_function_space(mesh, 1);
  fem::PoissonProblem problem;
  problem.robin.push_back({std::vector<char>(space.boundary_faces.size(), 1),
                           [](const Eigen::Vector3d&, const Eigen::Vector3d&) { return 0.0; },
                           [](const Eigen::Vector3d&, const Eigen::Vector3d&) { return 1.0; },
                           {}});
  EXPECT_THROW(fem::solve_poisson(mesh, space, problem, {}), InputError);
}

// The load functional (issue 22's integral QoI) l(u_h) = ∫f u_h + ∫g u_h converges like h^2p:
// u = x sin πy sin πz on the unit cube, at rest on x = 0 and on the y, z sides, flux g = ∂u/∂x
// = sin πy sin πz on x = 1, f = 2π² u, so l(u) = 2π² ∫x² · ¼ + ¼ = π²/6 + ¼ exactly, of
// which the volume part ∫f u is π²/6.
TEST(BoundaryTerms, PoissonLoadFunctionalConvergesAtTwiceTheDegree) {
  const double pi = std::numbers::pi;
  const double exact = pi * pi / 6 + 0.25, exact_volume = pi * pi / 6;
  auto u = [pi](const Eigen::Vector3d& x) {
    return x[0] * std::sin(pi * x[1]) * std::sin(pi * x[2]);
  };
  for (int p = 1; p <= 3; ++p) {
    std::vector<double> err, err_volume;
    for (int n : {2, 4, 8}) {
      const LagrangeMesh mesh = make_cube_tets(n);
      const fem::FunctionSpace space = fem::build_function_space(mesh, p);
      std::vector<char> at_rest(space.boundary_faces.size(), 0), flux = at_rest;
      for (std::size_t f = 0; f < space.boundary_faces.size(); ++f) {
        const auto [cell, j] = space.boundary_faces[f];
        double xmin = 2;
        for (int i = 0; i < 4; ++i)
          if (i != j) xmin = std::min(xmin, mesh.nodes(mesh.cells(cell, i), 0));
        (xmin > 1 - 1e-12 ? flux : at_rest)[f] = 1;
      }
      fem::PoissonProblem problem;
      problem.rhs = [&](const Eigen::Vector3d& x) { return 2 * pi * pi * u(x); };
      problem.dirichlet.push_back({at_rest, u, {}});
      problem.neumann.push_back({flux,
                                 [pi](const Eigen::Vector3d& x, const Eigen::Vector3d&) {
                                   return std::sin(pi * x[1]) * std::sin(pi * x[2]);
                                 },
                                 {}});
      const auto sol = fem::solve_poisson(mesh, space, problem, {});
      err.push_back(std::abs(sol.load_functional - exact));
      err_volume.push_back(std::abs(sol.load_functional_volume - exact_volume));
    }
    const double r = test::rate(err[1], err[2]), rv = test::rate(err_volume[1], err_volume[2]);
    std::printf(
        "load functional p=%d  errors %.3e %.3e %.3e (rate %.2f), volume part %.3e %.3e "
        "%.3e (rate %.2f)\n",
        p, err[0], err[1], err[2], r, err_volume[0], err_volume[1], err_volume[2], rv);
    EXPECT_NEAR(r, 2 * p, 0.5) << "p = " << p;
    EXPECT_NEAR(rv, 2 * p, 0.5) << "p = " << p;
  }
}
