// Weak boundary terms: Neumann flux and traction reproduce exact polynomial solutions, and the
// curved face quadrature satisfies the divergence theorem on the discrete geometry.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "fem/assembly/element_geometry.hpp"
#include "fem/assembly/face_integration.hpp"
#include "fem/problems/elasticity.hpp"
#include "fem/problems/error_norms.hpp"
#include "fem/problems/poisson.hpp"
#include "fem/quadrature/simplex_quadrature.hpp"
#include "meshing/core/primitives.hpp"
#include "meshing/io/cad_part.hpp"

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
