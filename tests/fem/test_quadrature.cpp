#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <thread>
#include <vector>

#include "fem/quadrature/simplex_quadrature.hpp"
#include "meshing/core/error.hpp"

using namespace curvefem;
using namespace curvefem::fem;

namespace {

double factorial(int n) {
  double f = 1.0;
  for (int i = 2; i <= n; ++i) f *= i;
  return f;
}

// ∫ x^a y^b z^c over the reference tetrahedron (dim 3) or ∫ x^a y^b over the triangle (dim 2).
double exact_integral(int dim, int a, int b, int c) {
  return factorial(a) * factorial(b) * factorial(c) / factorial(a + b + c + dim);
}

// Largest relative error of `rule` over every monomial of total degree ≤ max_degree.
double max_relative_error(const QuadratureRule& rule, int max_degree) {
  const int dim = rule.dimension();
  const int nq = rule.size();
  // powers[q][d][e] = x_{q,d}^e
  std::vector<double> powers(static_cast<std::size_t>(nq) * 3 * (max_degree + 1), 1.0);
  auto pw = [&](int q, int d, int e) -> double& {
    return powers[(static_cast<std::size_t>(q) * 3 + d) * (max_degree + 1) + e];
  };
  for (int q = 0; q < nq; ++q)
    for (int d = 0; d < dim; ++d)
      for (int e = 1; e <= max_degree; ++e) pw(q, d, e) = pw(q, d, e - 1) * rule.points(q, d);
  double worst = 0.0;
  for (int a = 0; a <= max_degree; ++a)
    for (int b = 0; a + b <= max_degree; ++b)
      for (int c = 0; c <= (dim == 3 ? max_degree - a - b : 0); ++c) {
        double sum = 0.0;
        for (int q = 0; q < nq; ++q)
          sum += rule.weights[q] * pw(q, 0, a) * pw(q, 1, b) * pw(q, 2, c);
        const double exact = exact_integral(dim, a, b, c);
        worst = std::max(worst, std::abs(sum - exact) / exact);
      }
  return worst;
}

int expected_points_per_direction(int degree) { return (degree + 2) / 2; }

int collapsed_points(int dim, int degree) {
  const int n = expected_points_per_direction(degree);
  return dim == 3 ? n * n * n : n * n;
}

// Point counts of the rules in use, by degree 0, 1, ..: the generated symmetric rule
// (fem/quadrature/generated/symmetric_rules.inc) where it has fewer points than the collapsed one,
// else the collapsed n^dim (degree 0: 1 point; tetrahedron 1 and 3, triangle 1 and 3: collapsed
// equals or beats the symmetric rule). Beyond the tables: collapsed.
constexpr std::array k_tet_points = {1, 1, 4, 8, 14, 14, 24, 35, 46, 61, 79, 102, 134};
constexpr std::array k_tri_points = {1,  1,  3,  4,  6,  7,  12, 15, 16, 19, 25,
                                     28, 33, 37, 42, 49, 55, 60, 69, 73, 79};

int expected_points(int dim, int degree) {
  if (dim == 3 && degree < static_cast<int>(k_tet_points.size())) return k_tet_points[degree];
  if (dim == 2 && degree < static_cast<int>(k_tri_points.size())) return k_tri_points[degree];
  return collapsed_points(dim, degree);
}

bool uses_symmetric_rule(int dim, int degree) {
  return expected_points(dim, degree) < collapsed_points(dim, degree);
}

const QuadratureRule& rule_of(int dim, int degree) {
  return dim == 3 ? tetrahedron_quadrature(degree) : triangle_quadrature(degree);
}

// Barycentric coordinates (l0 = 1 - x - y - z, l1 = x, ..) of point q.
std::vector<double> barycentric(const QuadratureRule& rule, int q) {
  const int dim = rule.dimension();
  std::vector<double> lambda(dim + 1);
  lambda[0] = 1.0;
  for (int d = 0; d < dim; ++d) {
    lambda[d + 1] = rule.points(q, d);
    lambda[0] -= rule.points(q, d);
  }
  return lambda;
}

// Largest distance from a permuted point to the nearest rule point of the same weight (relative
// 1e-12), over every point and every permutation of the barycentric coordinates; infinity when a
// permuted point has no partner of that weight.
double symmetry_defect(const QuadratureRule& rule) {
  const int dim = rule.dimension();
  std::vector<int> perm(dim + 1);
  for (int i = 0; i <= dim; ++i) perm[i] = i;
  double worst = 0.0;
  do {
    for (int q = 0; q < rule.size(); ++q) {
      const std::vector<double> lambda = barycentric(rule, q);
      double nearest = std::numeric_limits<double>::infinity();
      for (int r = 0; r < rule.size(); ++r) {
        if (std::abs(rule.weights[r] - rule.weights[q]) > 1e-12 * rule.weights[q]) continue;
        double dist = 0.0;
        for (int d = 0; d < dim; ++d)
          dist = std::max(dist, std::abs(rule.points(r, d) - lambda[perm[d + 1]]));
        nearest = std::min(nearest, dist);
      }
      worst = std::max(worst, nearest);
    }
  } while (std::next_permutation(perm.begin(), perm.end()));
  return worst;
}

}  // namespace

TEST(SimplexQuadrature, TetrahedronExactOnEveryMonomialUpToDegree20) {
  for (int degree = 0; degree <= 20; ++degree) {
    const QuadratureRule& rule = tetrahedron_quadrature(degree);
    EXPECT_EQ(rule.degree, degree);
    EXPECT_LT(max_relative_error(rule, degree), 1e-13) << "degree " << degree;
  }
}

TEST(SimplexQuadrature, TetrahedronExactUpToMaxDegree) {
  for (int degree = 21; degree <= k_max_quadrature_degree; ++degree)
    EXPECT_LT(max_relative_error(tetrahedron_quadrature(degree), degree), 1e-13)
        << "degree " << degree;
}

TEST(SimplexQuadrature, TriangleExactOnEveryMonomialUpToMaxDegree) {
  for (int degree = 0; degree <= k_max_quadrature_degree; ++degree) {
    const QuadratureRule& rule = triangle_quadrature(degree);
    EXPECT_EQ(rule.degree, degree);
    EXPECT_LT(max_relative_error(rule, degree), 1e-13) << "degree " << degree;
  }
}

TEST(SimplexQuadrature, NotExactBeyondTheConstruction) {
  // Collapsed rules: n points per direction integrate u^(2n-1) but not u^(2n), so x^(2n) must
  // fail. This proves the exactness check above can fail (for even degree d, 2n = d + 2).
  for (int degree : {1, 3, 20}) {
    const int n = expected_points_per_direction(degree);
    ASSERT_FALSE(uses_symmetric_rule(3, degree));
    EXPECT_GT(max_relative_error(tetrahedron_quadrature(degree), 2 * n), 1e-8) << degree;
  }
  for (int degree : {1, 3, 25}) {
    const int n = expected_points_per_direction(degree);
    ASSERT_FALSE(uses_symmetric_rule(2, degree));
    EXPECT_GT(max_relative_error(triangle_quadrature(degree), 2 * n), 1e-8) << degree;
  }
}

TEST(SimplexQuadrature, SymmetricRulesFailWhenPerturbedOrBeyondTheirDegree) {
  // Moving one point of a symmetric rule by 1e-6 breaks exactness: the check above can fail on
  // these rules too. And none of the committed rules happens to be exact one degree above its
  // own, so degree + 1 must fail as well.
  int checked = 0;
  for (int dim : {2, 3})
    for (int degree = 1; degree <= k_max_quadrature_degree; ++degree) {
      if (!uses_symmetric_rule(dim, degree)) continue;
      ++checked;
      QuadratureRule moved = rule_of(dim, degree);
      moved.points(0, 0) += 1e-6;
      EXPECT_GT(max_relative_error(moved, degree), 1e-10) << dim << "D degree " << degree;
      EXPECT_GT(max_relative_error(rule_of(dim, degree), degree + 1), 1e-8)
          << dim << "D degree " << degree;
    }
  EXPECT_GE(checked, 25);
}

TEST(SimplexQuadrature, SymmetricRulesKeepAwayFromTheFacesAndWasteNoPoint) {
  // The generator's acceptance margins: every barycentric coordinate ≥ 1e-3 (a point next to a
  // face samples a curved element's geometry where it is worst: a first table had points 1e-13
  // from a face and made a Neo-Hookean Newton fail on a k = 4 torus), every weight ≥ 1e-2 of the
  // mean weight.
  for (int dim : {2, 3})
    for (int degree = 0; degree <= k_max_quadrature_degree; ++degree) {
      if (!uses_symmetric_rule(dim, degree)) continue;
      const QuadratureRule& rule = rule_of(dim, degree);
      double nearest_face = 1.0;
      for (int q = 0; q < rule.size(); ++q)
        for (double lambda : barycentric(rule, q)) nearest_face = std::min(nearest_face, lambda);
      EXPECT_GE(nearest_face, 1e-3 - 1e-15) << dim << "D degree " << degree;
      EXPECT_GE(rule.weights.minCoeff(), 1e-2 * rule.weights.mean())
          << dim << "D degree " << degree;
    }
}

TEST(SimplexQuadrature, SymmetricRulesAreInvariantUnderVertexPermutations) {
  int checked = 0;
  for (int dim : {2, 3})
    for (int degree = 0; degree <= k_max_quadrature_degree; ++degree) {
      if (!uses_symmetric_rule(dim, degree)) continue;
      EXPECT_LT(symmetry_defect(rule_of(dim, degree)), 1e-14) << dim << "D degree " << degree;
      ++checked;
    }
  EXPECT_GE(checked, 25);
  // The check can fail: the collapsed rule of degree 20 is not symmetric.
  EXPECT_GT(symmetry_defect(rule_of(3, 20)), 1e-3);
}

TEST(SimplexQuadrature, PointCountsWeightsAndInteriorPoints) {
  for (int degree = 0; degree <= k_max_quadrature_degree; ++degree) {
    const QuadratureRule& tet = tetrahedron_quadrature(degree);
    const QuadratureRule& tri = triangle_quadrature(degree);
    ASSERT_EQ(tet.size(), expected_points(3, degree)) << "degree " << degree;
    ASSERT_EQ(tri.size(), expected_points(2, degree)) << "degree " << degree;
    EXPECT_LE(tet.size(), collapsed_points(3, degree));
    EXPECT_LE(tri.size(), collapsed_points(2, degree));
    ASSERT_EQ(tet.dimension(), 3);
    ASSERT_EQ(tri.dimension(), 2);
    EXPECT_NEAR(tet.weights.sum(), 1.0 / 6.0, 1e-15);
    EXPECT_NEAR(tri.weights.sum(), 0.5, 1e-15);
    EXPECT_GT(tet.weights.minCoeff(), 0.0);
    EXPECT_GT(tri.weights.minCoeff(), 0.0);
    EXPECT_GT(tet.points.minCoeff(), 0.0);
    EXPECT_GT(tri.points.minCoeff(), 0.0);
    EXPECT_LT(tet.points.rowwise().sum().maxCoeff(), 1.0);
    EXPECT_LT(tri.points.rowwise().sum().maxCoeff(), 1.0);
  }
}

TEST(SimplexQuadrature, GaussLegendreAndJacobiKnownValues) {
  Eigen::VectorXd x, w;
  gauss_jacobi_01(2, 0, x, w);  // Gauss–Legendre on [0, 1]
  EXPECT_NEAR(x[0], 0.5 - 0.5 / std::sqrt(3.0), 1e-15);
  EXPECT_NEAR(x[1], 0.5 + 0.5 / std::sqrt(3.0), 1e-15);
  EXPECT_NEAR(w[0], 0.5, 1e-15);
  EXPECT_NEAR(w[1], 0.5, 1e-15);
  gauss_jacobi_01(1, 2, x, w);  // ∫ (1-u)^2 = 1/3, ∫ u (1-u)^2 = 1/12 → node 1/4
  EXPECT_NEAR(x[0], 0.25, 1e-15);
  EXPECT_NEAR(w[0], 1.0 / 3.0, 1e-15);
}

TEST(SimplexQuadrature, RejectsUnsupportedDegrees) {
  EXPECT_THROW(tetrahedron_quadrature(-1), InputError);
  EXPECT_THROW(tetrahedron_quadrature(k_max_quadrature_degree + 1), InputError);
  EXPECT_THROW(triangle_quadrature(-1), InputError);
  EXPECT_THROW(triangle_quadrature(k_max_quadrature_degree + 1), InputError);
}

TEST(SimplexQuadrature, CachedAndThreadSafe) {
  // Two threads race to build rules; both must see the same objects as the main thread.
  std::vector<const QuadratureRule*> seen[2];
  std::vector<std::thread> threads;
  for (int t = 0; t < 2; ++t)
    threads.emplace_back([&seen, t] {
      for (int d = 0; d <= k_max_quadrature_degree; ++d) {
        seen[t].push_back(&tetrahedron_quadrature(d));
        seen[t].push_back(&triangle_quadrature(d));
      }
    });
  for (auto& thread : threads) thread.join();
  ASSERT_EQ(seen[0].size(), seen[1].size());
  for (std::size_t i = 0; i < seen[0].size(); ++i) EXPECT_EQ(seen[0][i], seen[1][i]);
  EXPECT_EQ(&tetrahedron_quadrature(7), &tetrahedron_quadrature(7));
  EXPECT_NE(static_cast<const void*>(&tetrahedron_quadrature(7)),
            static_cast<const void*>(&triangle_quadrature(7)));
}

TEST(SimplexQuadrature, DefaultDegrees) {
  // Affine (k = 1): stiffness 2p, mass 2p (exact), error 2p + 6.
  EXPECT_EQ(default_quadrature_degree(1, 1, QuadratureUse::stiffness), 2);
  EXPECT_EQ(default_quadrature_degree(3, 1, QuadratureUse::mass), 6);
  EXPECT_EQ(default_quadrature_degree(2, 1, QuadratureUse::error), 10);
  // Curved: stiffness 2p + 2(k-1), mass 2p + 3(k-1), error 2p + 4 + max(2k, 3(k-1)).
  EXPECT_EQ(default_quadrature_degree(2, 2, QuadratureUse::stiffness), 6);
  EXPECT_EQ(default_quadrature_degree(2, 3, QuadratureUse::mass), 10);
  EXPECT_EQ(default_quadrature_degree(3, 2, QuadratureUse::error), 14);
  EXPECT_EQ(default_quadrature_degree(4, 4, QuadratureUse::error), 21);
  EXPECT_EQ(default_quadrature_degree(10, 10, QuadratureUse::error), k_max_quadrature_degree);
  for (int p = 1; p <= 4; ++p)
    for (int k = 1; k <= 4; ++k) {
      const int mass = default_quadrature_degree(p, k, QuadratureUse::mass);
      EXPECT_GE(mass, 2 * p + 3 * (k - 1));  // mass integrand is a polynomial: must be exact
      EXPECT_GE(default_quadrature_degree(p, k, QuadratureUse::error), mass);
      EXPECT_GE(default_quadrature_degree(p, k, QuadratureUse::stiffness), 2 * (p - 1));
    }
  EXPECT_THROW(default_quadrature_degree(0, 1, QuadratureUse::mass), InputError);
  EXPECT_THROW(default_quadrature_degree(1, 0, QuadratureUse::mass), InputError);
}

TEST(SimplexQuadrature, TheFreeUpgradeKeepsThePointCountAndRaisesTheDegree) {
  // Degree 4 and 5 share a 14-point symmetric rule; 14 and 15 a collapsed 8^3 one.
  EXPECT_EQ(tetrahedron_degree_at_same_cost(4), 5);
  EXPECT_EQ(tetrahedron_degree_at_same_cost(5), 5);
  EXPECT_EQ(tetrahedron_degree_at_same_cost(2), 2);
  EXPECT_EQ(tetrahedron_degree_at_same_cost(10), 10);
  EXPECT_EQ(tetrahedron_degree_at_same_cost(14), 15);
  for (int d = 1; d <= 30; ++d) {
    const int up = tetrahedron_degree_at_same_cost(d);
    EXPECT_GE(up, d);
    EXPECT_LE(up, 30);
    EXPECT_EQ(tetrahedron_quadrature(up).size(), tetrahedron_quadrature(d).size()) << d;
    if (up < 30) EXPECT_GT(tetrahedron_quadrature(up + 1).size(), tetrahedron_quadrature(d).size());
  }
}
