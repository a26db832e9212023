#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "fem/basis/lagrange_basis.hpp"
#include "meshing/core/error.hpp"
#include "meshing/core/lagrange_nodes.hpp"

using namespace curvefem;
using curvefem::fem::LagrangeBasis;

namespace {

constexpr CellKind k_kinds[] = {CellKind::triangle, CellKind::tetrahedron};

Eigen::Vector3d random_reference_point(std::mt19937& rng, CellKind kind) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Eigen::Vector3d x(u(rng), u(rng), kind == CellKind::tetrahedron ? u(rng) : 0.0);
  while (x.sum() > 1.0) x *= 0.5;
  return x;
}

Eigen::Vector3d node_point(const Eigen::MatrixXd& nodes, int i) {
  Eigen::Vector3d x = Eigen::Vector3d::Zero();
  x.head(nodes.cols()) = nodes.row(i).transpose();
  return x;
}

double monomial(const Eigen::Vector3d& x, int a, int b, int c) {
  return std::pow(x[0], a) * std::pow(x[1], b) * std::pow(x[2], c);
}

// max over random points of |Σ_i f(x_i) φ_i(x) − f(x)| for f = x^a y^b z^c.
double interpolation_error(const LagrangeBasis& basis, int a, int b, int c, std::mt19937& rng) {
  const Eigen::MatrixXd nodes = lagrange_reference_nodes(basis.kind(), basis.degree());
  Eigen::VectorXd f(basis.size());
  for (int i = 0; i < basis.size(); ++i) f[i] = monomial(node_point(nodes, i), a, b, c);
  double error = 0.0;
  for (int trial = 0; trial < 10; ++trial) {
    const Eigen::Vector3d x = random_reference_point(rng, basis.kind());
    error = std::max(error, std::abs(f.dot(basis.values(x)) - monomial(x, a, b, c)));
  }
  return error;
}

}  // namespace

TEST(LagrangeBasis, RejectsDegreesOutsideOneToFour) {
  for (CellKind kind : k_kinds) {
    EXPECT_THROW(LagrangeBasis(kind, 0), InputError);
    EXPECT_THROW(LagrangeBasis(kind, 5), InputError);
    EXPECT_THROW(LagrangeBasis(kind, -1), InputError);
  }
}

TEST(LagrangeBasis, SizesAndDimensions) {
  const int tri[] = {3, 6, 10, 15}, tet[] = {4, 10, 20, 35};
  for (int p = 1; p <= 4; ++p) {
    const LagrangeBasis t(CellKind::triangle, p), T(CellKind::tetrahedron, p);
    EXPECT_EQ(t.size(), tri[p - 1]);
    EXPECT_EQ(T.size(), tet[p - 1]);
    EXPECT_EQ(t.dim(), 2);
    EXPECT_EQ(T.dim(), 3);
    EXPECT_EQ(T.degree(), p);
    EXPECT_EQ(static_cast<int>(T.monomial_exponents().size()), tet[p - 1]);
  }
}

TEST(LagrangeBasis, GeneratedNodeOrderIsCoresCanonicalOrder) {
  // The generator re-implements the canonical rule; it must agree with core entry by entry.
  for (CellKind kind : k_kinds)
    for (int p = 1; p <= 4; ++p) {
      const LagrangeBasis basis(kind, p);
      EXPECT_EQ(basis.node_lattice(), lagrange_lattice(kind, p)) << "p=" << p;
      EXPECT_EQ(basis.reference_nodes(), lagrange_reference_nodes(kind, p)) << "p=" << p;
    }
}

TEST(LagrangeBasis, MonomialsAreGradedAndComplete) {
  for (CellKind kind : k_kinds)
    for (int p = 1; p <= 4; ++p) {
      const auto exps = LagrangeBasis(kind, p).monomial_exponents();
      int previous_degree = 0;
      for (std::size_t m = 0; m < exps.size(); ++m) {
        const int d = exps[m][0] + exps[m][1] + exps[m][2];
        EXPECT_LE(d, p);
        EXPECT_GE(d, previous_degree);
        if (kind == CellKind::triangle) {
          EXPECT_EQ(exps[m][2], 0);
        }
        for (std::size_t l = 0; l < m; ++l) EXPECT_NE(exps[l], exps[m]);
        previous_degree = d;
      }
    }
}

TEST(LagrangeBasis, KroneckerDeltaAtCoreNodes) {
  for (CellKind kind : k_kinds)
    for (int p = 1; p <= 4; ++p) {
      const LagrangeBasis basis(kind, p);
      const Eigen::MatrixXd nodes = lagrange_reference_nodes(kind, p);
      for (int i = 0; i < nodes.rows(); ++i) {
        const Eigen::VectorXd phi = basis.values(node_point(nodes, i));
        for (int j = 0; j < basis.size(); ++j)
          EXPECT_NEAR(phi[j], i == j ? 1.0 : 0.0, 1e-13) << "p=" << p << " node " << i;
      }
    }
}

TEST(LagrangeBasis, PartitionOfUnityAndGradientsSumToZero) {
  std::mt19937 rng(11);
  for (CellKind kind : k_kinds)
    for (int p = 1; p <= 4; ++p) {
      const LagrangeBasis basis(kind, p);
      for (int trial = 0; trial < 20; ++trial) {
        const Eigen::Vector3d x = random_reference_point(rng, kind);
        EXPECT_NEAR(basis.values(x).sum(), 1.0, 1e-13);
        EXPECT_LT(basis.gradients(x).colwise().sum().cwiseAbs().maxCoeff(), 1e-12);
      }
    }
}

TEST(LagrangeBasis, GradientsMatchCentralDifferences) {
  std::mt19937 rng(5);
  const double h = 1e-6;
  for (CellKind kind : k_kinds)
    for (int p = 1; p <= 4; ++p) {
      const LagrangeBasis basis(kind, p);
      for (int trial = 0; trial < 10; ++trial) {
        const Eigen::Vector3d x = random_reference_point(rng, kind);
        const Eigen::MatrixXd g = basis.gradients(x);
        ASSERT_EQ(g.rows(), basis.size());
        ASSERT_EQ(g.cols(), basis.dim());
        for (int d = 0; d < basis.dim(); ++d) {
          Eigen::Vector3d e = Eigen::Vector3d::Zero();
          e[d] = h;
          const Eigen::VectorXd fd = (basis.values(x + e) - basis.values(x - e)) / (2 * h);
          EXPECT_LT((fd - g.col(d)).cwiseAbs().maxCoeff(), 1e-7) << "p=" << p << " d=" << d;
        }
      }
    }
}

TEST(LagrangeBasis, ReproducesEveryMonomialOfDegreeAtMostP) {
  std::mt19937 rng(17);
  for (CellKind kind : k_kinds)
    for (int p = 1; p <= 4; ++p) {
      const LagrangeBasis basis(kind, p);
      const int cmax = kind == CellKind::tetrahedron ? p : 0;
      for (int a = 0; a <= p; ++a)
        for (int b = 0; a + b <= p; ++b)
          for (int c = 0; c <= cmax && a + b + c <= p; ++c)
            EXPECT_LT(interpolation_error(basis, a, b, c, rng), 1e-12)
                << "p=" << p << " monomial " << a << b << c;
    }
}

TEST(LagrangeBasis, DoesNotReproduceDegreePPlusOne) {
  // The reproduction check above can fail: x^(p+1) is not in the space.
  std::mt19937 rng(19);
  for (CellKind kind : k_kinds)
    for (int p = 1; p <= 4; ++p)
      EXPECT_GT(interpolation_error(LagrangeBasis(kind, p), p + 1, 0, 0, rng), 1e-4) << "p=" << p;
}

TEST(LagrangeBasis, AgreesWithCoreProductFormula) {
  std::mt19937 rng(23);
  for (CellKind kind : k_kinds)
    for (int p = 1; p <= 4; ++p) {
      const LagrangeBasis basis(kind, p);
      for (int trial = 0; trial < 20; ++trial) {
        const Eigen::Vector3d x = random_reference_point(rng, kind);
        EXPECT_LT((basis.values(x) - lagrange_shape_values(kind, p, x)).cwiseAbs().maxCoeff(),
                  1e-12);
        EXPECT_LT((basis.gradients(x) - lagrange_shape_gradients(kind, p, x)).cwiseAbs().maxCoeff(),
                  1e-12);
      }
    }
}

TEST(LagrangeBasis, RawPointerApiMatchesEigenApi) {
  std::mt19937 rng(29);
  const LagrangeBasis basis(CellKind::tetrahedron, 3);
  const Eigen::Vector3d x = random_reference_point(rng, CellKind::tetrahedron);
  std::vector<double> phi(basis.size()), grad(basis.size() * 3), phi2(basis.size());
  basis.values(x.data(), phi.data());
  basis.values_and_gradients(x.data(), phi2.data(), grad.data());
  const Eigen::VectorXd phi_e = basis.values(x);
  const Eigen::MatrixXd grad_e = basis.gradients(x);
  for (int i = 0; i < basis.size(); ++i) {
    EXPECT_EQ(phi[i], phi_e[i]);
    EXPECT_EQ(phi2[i], phi_e[i]);
    for (int d = 0; d < 3; ++d) EXPECT_EQ(grad[d * basis.size() + i], grad_e(i, d));
  }
}

TEST(LagrangeBasis, TabulateMatchesPointwiseEvaluation) {
  for (CellKind kind : k_kinds) {
    const LagrangeBasis basis(kind, 4);
    const auto& rule = kind == CellKind::tetrahedron ? fem::tetrahedron_quadrature(8)
                                                     : fem::triangle_quadrature(8);
    const fem::BasisTabulation t = basis.tabulate(rule);
    ASSERT_EQ(t.values.rows(), rule.size());
    ASSERT_EQ(t.values.cols(), basis.size());
    ASSERT_EQ(static_cast<int>(t.gradients.size()), rule.size());
    for (int q = 0; q < rule.size(); ++q) {
      Eigen::Vector3d x = Eigen::Vector3d::Zero();
      x.head(basis.dim()) = rule.points.row(q).transpose();
      EXPECT_LT((t.values.row(q).transpose() - basis.values(x)).cwiseAbs().maxCoeff(), 1e-15);
      EXPECT_LT((t.gradients[q] - basis.gradients(x)).cwiseAbs().maxCoeff(), 1e-15);
    }
    // Mass-matrix check: Σ_ij M_ij = |reference simplex| (partition of unity, exact rule).
    const double total = (t.values.transpose() * rule.weights).sum();
    EXPECT_NEAR(total, kind == CellKind::tetrahedron ? 1.0 / 6.0 : 0.5, 1e-15);
  }
  EXPECT_THROW(LagrangeBasis(CellKind::tetrahedron, 2).tabulate(fem::triangle_quadrature(4)),
               InputError);
}
