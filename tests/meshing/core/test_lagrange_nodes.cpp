#include <gtest/gtest.h>

#include <random>
#include <set>

#include "meshing/core/lagrange_mesh.hpp"
#include "meshing/core/lagrange_nodes.hpp"

using namespace curvefem;

namespace {
Eigen::Vector3d random_ref(std::mt19937& rng, CellKind kind) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Eigen::Vector3d x(u(rng), u(rng), kind == CellKind::tetrahedron ? u(rng) : 0.0);
  while (x.sum() > 1.0) x *= 0.5;
  return x;
}
}  // namespace

TEST(LagrangeNodes, CountsAndOrderFromCount) {
  const int tri[] = {3, 6, 10, 15}, tet[] = {4, 10, 20, 35};
  for (int k = 1; k <= 4; ++k) {
    EXPECT_EQ(num_lagrange_nodes(CellKind::triangle, k), tri[k - 1]);
    EXPECT_EQ(num_lagrange_nodes(CellKind::tetrahedron, k), tet[k - 1]);
    EXPECT_EQ(order_from_node_count(CellKind::tetrahedron, tet[k - 1]), k);
    EXPECT_EQ(lagrange_lattice(CellKind::tetrahedron, k).size(), static_cast<size_t>(tet[k - 1]));
  }
  EXPECT_EQ(order_from_node_count(CellKind::tetrahedron, 11), -1);
}

TEST(LagrangeNodes, CanonicalOrderOfQuadraticTet) {
  // Documented rule: vertices, then edges (0,1) (0,2) (0,3) (1,2) (1,3) (2,3).
  const auto x = lagrange_reference_nodes(CellKind::tetrahedron, 2);
  Eigen::MatrixXd expected(10, 3);
  expected << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1,  //
      .5, 0, 0, 0, .5, 0, 0, 0, .5, .5, .5, 0, .5, 0, .5, 0, .5, .5;
  EXPECT_EQ(x, expected);
}

TEST(LagrangeNodes, CubicEdgesWalkFromLowToHighVertex) {
  const auto x = lagrange_reference_nodes(CellKind::tetrahedron, 3);
  // Edge (0,1): first node near v0.
  EXPECT_NEAR(x(4, 0), 1.0 / 3.0, 1e-15);
  EXPECT_NEAR(x(5, 0), 2.0 / 3.0, 1e-15);
  // Edge (1,2): first node near v1 = (1,0,0).
  EXPECT_NEAR(x(10, 0), 2.0 / 3.0, 1e-15);
  EXPECT_NEAR(x(10, 1), 1.0 / 3.0, 1e-15);
  // First face node is face (0,1,2) centroid, last is face (1,2,3).
  EXPECT_NEAR(x(16, 2), 0.0, 1e-15);
  EXPECT_NEAR(x(19, 0) + x(19, 1) + x(19, 2), 1.0, 1e-15);
}

TEST(LagrangeNodes, KroneckerPartitionOfUnityAndGradients) {
  std::mt19937 rng(7);
  for (CellKind kind : {CellKind::triangle, CellKind::tetrahedron}) {
    const int dim = cell_dimension(kind);
    for (int k = 1; k <= 4; ++k) {
      const auto nodes = lagrange_reference_nodes(kind, k);
      for (int i = 0; i < nodes.rows(); ++i) {
        Eigen::Vector3d xi = Eigen::Vector3d::Zero();
        xi.head(dim) = nodes.row(i).transpose();
        const auto phi = lagrange_shape_values(kind, k, xi);
        for (int j = 0; j < phi.size(); ++j) EXPECT_NEAR(phi[j], i == j ? 1.0 : 0.0, 1e-13);
      }
      for (int trial = 0; trial < 5; ++trial) {
        const Eigen::Vector3d xi = random_ref(rng, kind);
        EXPECT_NEAR(lagrange_shape_values(kind, k, xi).sum(), 1.0, 1e-13);
        const auto g = lagrange_shape_gradients(kind, k, xi);
        const double h = 1e-6;
        for (int d = 0; d < dim; ++d) {
          Eigen::Vector3d e = Eigen::Vector3d::Zero();
          e[d] = h;
          const Eigen::VectorXd fd =
              (lagrange_shape_values(kind, k, xi + e) - lagrange_shape_values(kind, k, xi - e)) /
              (2 * h);
          EXPECT_LT((fd - g.col(d)).cwiseAbs().maxCoeff(), 1e-7) << "k=" << k << " d=" << d;
        }
      }
    }
  }
}

TEST(LagrangeMesh, CurvedTetReproducesPolynomialMapOfItsDegree) {
  // Nodes placed by a degree-k polynomial map: the Lagrange map must reproduce it exactly.
  std::mt19937 rng(3);
  for (int k = 1; k <= 4; ++k) {
    auto f = [k](const Eigen::Vector3d& x) {
      Eigen::Vector3d y = x;
      y[0] += 0.1 * std::pow(x[1], k);
      y[1] += 0.05 * std::pow(x[0] + x[2], k);
      y[2] += 0.07 * std::pow(x[0], k - 1) * x[1];
      return y;
    };
    LagrangeMesh m;
    m.order = k;
    const auto ref = lagrange_reference_nodes(CellKind::tetrahedron, k);
    m.nodes.resize(ref.rows(), 3);
    m.cells.resize(1, ref.rows());
    for (int i = 0; i < ref.rows(); ++i) {
      m.nodes.row(i) = f(ref.row(i).transpose()).transpose();
      m.cells(0, i) = i;
    }
    validate_structure(m);
    for (int t = 0; t < 10; ++t) {
      const Eigen::Vector3d xi = random_ref(rng, CellKind::tetrahedron);
      EXPECT_LT((m.map(0, xi) - f(xi)).norm(), 1e-13) << "k=" << k;
    }
  }
}

// The area-element ratio of a curved triangle (the curving's distortion floor): 1 for any
// straight triangle at any order; below 1 when the nodes are bunched toward one side; 0 when the
// patch folds over (its normal turns against its corners' plane).
TEST(LagrangeNodes, AreaElementRatioOfCurvedTriangles) {
  const Eigen::Vector3d a(0, 0, 0), b(2, 0, 0.5), c(0.3, 1.5, 0);
  for (int k = 1; k <= k_max_order; ++k) {
    const auto& lattice = lagrange_lattice(CellKind::triangle, k);
    std::vector<Eigen::Vector3d> x(lattice.size());
    for (std::size_t n = 0; n < lattice.size(); ++n)
      x[n] = (lattice[n][0] * a + lattice[n][1] * b + lattice[n][2] * c) / double(k);
    EXPECT_NEAR(triangle_area_element_ratio(k, x), 1.0, 1e-12) << "order " << k;
  }
  // Quadratic, canonical order: corners 0, 1, 2, then edges (0,1), (0,2), (1,2).
  const Eigen::Vector3d p0(0, 0, 0), p1(1, 0, 0), p2(0, 1, 0);
  std::vector<Eigen::Vector3d> x{p0, p1, p2, (p0 + p1) / 2, (p0 + p2) / 2, (p1 + p2) / 2};
  // Edge (0,1)'s node moved along the edge to t: at the corner p1 the area element is 3 − 4t
  // (x_ξ = (3 − 4t, 0, 0), x_η = (2 − 4t, 1, 0) there), 1.8 at p0's end of the edge: bunched at
  // t = 0.7, folded past t = 3/4.
  x[3] = Eigen::Vector3d(0.7, 0, 0);
  const double bunched = triangle_area_element_ratio(2, x);
  EXPECT_GT(bunched, 0.0);
  EXPECT_LT(bunched, 0.5);
  x[3] = Eigen::Vector3d(0.8, 0, 0);
  EXPECT_EQ(triangle_area_element_ratio(2, x), 0.0);
  // The mid-edge node lifted out of the plane keeps the normal's side: curved, not folded.
  x[3] = Eigen::Vector3d(0.5, 0, 0.3);
  EXPECT_GT(triangle_area_element_ratio(2, x), 0.0);
}
