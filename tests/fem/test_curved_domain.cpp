// Why curved meshes exist: on the unit ball with u = 0 on the true sphere, straight-sided
// geometry (k = 1) caps the L2 rate near 2 whatever p is, while isoparametric geometry (k = p)
// keeps the optimal rate p + 1 (reference-notes/fem-and-formats.md §5).
#include <gtest/gtest.h>

#include <cmath>

#include "fem/problems/error_norms.hpp"
#include "fem/problems/poisson.hpp"
#include "meshing/io/cad_part.hpp"

using namespace curvefem;

namespace {

// u = (1 − r²) cos(x + 2y + 3z);  −Δu = 6 cos(s) + 4 (x + 2y + 3z)·(−sin s)·(−1)... computed below.
double u_exact(const Eigen::Vector3d& x) {
  return (1 - x.squaredNorm()) * std::cos(x[0] + 2 * x[1] + 3 * x[2]);
}
Eigen::Vector3d grad_exact(const Eigen::Vector3d& x) {
  const double s = x[0] + 2 * x[1] + 3 * x[2], w = 1 - x.squaredNorm();
  return -2 * x * std::cos(s) - w * std::sin(s) * Eigen::Vector3d(1, 2, 3);
}
double minus_laplacian(const Eigen::Vector3d& x) {
  // Δ(w c) = c Δw + 2 ∇w·∇c + w Δc with w = 1 − r², c = cos s, |∇s|² = 14.
  const double s = x[0] + 2 * x[1] + 3 * x[2], w = 1 - x.squaredNorm();
  const double lap = -6 * std::cos(s) + 2 * (-2 * x).dot(-std::sin(s) * Eigen::Vector3d(1, 2, 3)) -
                     14 * w * std::cos(s);
  return -lap;
}

struct Level {
  double h;
  int dofs;
  double l2, h1;
};

Level solve_ball(double h, int p, int k) {
  const LagrangeMesh mesh = io::make_ball_mesh(1.0, h, k);
  const fem::FunctionSpace space = fem::build_function_space(mesh, p);
  fem::PoissonProblem problem;
  problem.rhs = minus_laplacian;
  // Data of the true domain: u = 0 on the sphere, imposed on the mesh boundary.
  problem.dirichlet.push_back({std::vector<char>(space.boundary_faces.size(), 1),
                               [](const Eigen::Vector3d&) { return 0.0; },
                               {}});
  const auto sol = fem::solve_poisson(mesh, space, problem, {});
  const auto e = fem::compute_errors(
      mesh, space, sol.u, 1, [](const Eigen::Vector3d& x, double* v) { *v = u_exact(x); },
      [](const Eigen::Vector3d& x, double* g) {
        Eigen::Map<Eigen::Vector3d> m(g);
        m = grad_exact(x);
      });
  return {h, space.num_dofs, e.l2, e.h1_semi};
}

// Gmsh does not halve the element size exactly: the effective h is (#DOFs)^(-1/3).
double l2_rate(const Level& a, const Level& b) {
  return std::log(a.l2 / b.l2) / std::log(std::cbrt(static_cast<double>(b.dofs) / a.dofs));
}

}  // namespace

TEST(CurvedDomain, SuperparametricGeometryKeepsOptimalRate) {
  // p = 1 on order-2 geometry (k > p): optimal L2 rate 2, and never worse than straight geometry.
  std::vector<Level> iso, super;
  for (double h : {0.3, 0.15}) {
    iso.push_back(solve_ball(h, 1, 1));
    super.push_back(solve_ball(h, 1, 2));
  }
  const double r = l2_rate(super[0], super[1]);
  std::printf("p=1 k=2: dofs %d %d  L2 %.3e %.3e  rate %.2f (k=1: %.3e %.3e)\n", super[0].dofs,
              super[1].dofs, super[0].l2, super[1].l2, r, iso[0].l2, iso[1].l2);
  EXPECT_GT(r, 2 - 0.3);
  EXPECT_LT(super[1].l2, iso[1].l2);
}

TEST(CurvedDomain, StraightGeometryCapsRateIsoparametricKeepsIt) {
  for (int p = 2; p <= 3; ++p) {
    double finest_straight = 0;
    const std::vector<double> hs =
        p == 2 ? std::vector<double>{0.2, 0.1} : std::vector<double>{0.3, 0.15};
    for (int k : {1, p}) {
      std::vector<Level> L;
      for (double h : hs) L.push_back(solve_ball(h, p, k));
      const double r = l2_rate(L[0], L[1]);
      std::printf("p=%d k=%d: dofs %d %d  L2 %.3e %.3e  rate %.2f\n", p, k, L[0].dofs, L[1].dofs,
                  L[0].l2, L[1].l2, r);
      if (k == 1) {
        finest_straight = L[1].l2;
        EXPECT_LT(r, 2.4) << "p=" << p << ": straight geometry should cap the L2 rate near 2";
        EXPECT_GT(r, 1.6);
      } else {
        EXPECT_GT(r, p + 1 - 0.3) << "p=" << p << ": isoparametric geometry should keep p+1";
        // Measured: 3.6× (p = 2) and 36× (p = 3) smaller than straight geometry on the same mesh.
        EXPECT_LT(L[1].l2 * 3, finest_straight) << "p=" << p;
      }
    }
  }
}
