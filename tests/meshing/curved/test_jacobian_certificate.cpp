// Certified positivity of det J (meshing/curved/jacobian_certificate.hpp).
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <array>
#include <cfenv>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "meshing/core/error.hpp"
#include "meshing/core/lagrange_nodes.hpp"
#include "meshing/curved/jacobian_certificate.hpp"

namespace table {
#include "meshing/curved/generated/bernstein_tables.inc"
}  // namespace table

namespace {

using curvefem::CellKind;
using namespace curvefem::meshing::curved;

using Vertices = Eigen::Matrix<double, 4, 3>;

int num_nodes(int k) { return (k + 1) * (k + 2) * (k + 3) / 6; }

// Nodes of the straight (affine) order-k tet with the given vertices, canonical order.
Eigen::MatrixXd straight_tet(int k, const Vertices& v) {
  const auto& lattice = curvefem::lagrange_lattice(CellKind::tetrahedron, k);
  Eigen::MatrixXd x(lattice.size(), 3);
  for (std::size_t i = 0; i < lattice.size(); ++i) {
    Eigen::RowVector3d p = Eigen::RowVector3d::Zero();
    for (int a = 0; a < 4; ++a) p += v.row(a) * lattice[i][a];
    x.row(i) = p / k;
  }
  return x;
}

Vertices regular_vertices() {
  Vertices v;
  v << 0, 0, 0, 1, 0, 0, 0.5, std::sqrt(3.0) / 2, 0, 0.5, std::sqrt(3.0) / 6, std::sqrt(2.0 / 3.0);
  return v;
}

// Six times the signed volume, in long double.
long double six_volume(const Vertices& v) {
  long double e[3][3];
  for (int a = 0; a < 3; ++a)
    for (int c = 0; c < 3; ++c)
      e[a][c] = static_cast<long double>(v(a + 1, c)) - static_cast<long double>(v(0, c));
  return e[0][0] * (e[1][1] * e[2][2] - e[1][2] * e[2][1]) -
         e[0][1] * (e[1][0] * e[2][2] - e[1][2] * e[2][0]) +
         e[0][2] * (e[1][0] * e[2][1] - e[1][1] * e[2][0]);
}

double det_j(int k, const Eigen::MatrixXd& x, const Eigen::Vector3d& xi) {
  const Eigen::MatrixXd g = curvefem::lagrange_shape_gradients(CellKind::tetrahedron, k, xi);
  const Eigen::Matrix3d j = x.transpose() * g;
  return j.determinant();
}

// Uniform lattice of level L plus `extra` random interior points (fixed seed).
std::vector<Eigen::Vector3d> sample_points(int level, int extra, unsigned seed) {
  std::vector<Eigen::Vector3d> pts;
  for (int a = 0; a <= level; ++a)
    for (int b = 0; a + b <= level; ++b)
      for (int c = 0; a + b + c <= level; ++c)
        pts.emplace_back(double(a) / level, double(b) / level, double(c) / level);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  while (extra > 0) {
    const Eigen::Vector3d p(u(rng), u(rng), u(rng));
    if (p.sum() > 1.0) continue;
    pts.push_back(p);
    --extra;
  }
  return pts;
}

// Gradient matrices of the order-k basis at the given points (precomputed for speed).
std::vector<Eigen::MatrixXd> gradients_at(int k, const std::vector<Eigen::Vector3d>& pts) {
  std::vector<Eigen::MatrixXd> g;
  for (const auto& p : pts)
    g.push_back(curvefem::lagrange_shape_gradients(CellKind::tetrahedron, k, p));
  return g;
}

double sampled_min(const Eigen::MatrixXd& x, const std::vector<Eigen::MatrixXd>& grads) {
  double m = std::numeric_limits<double>::infinity();
  for (const auto& g : grads) {
    const Eigen::Matrix3d j = x.transpose() * g;
    m = std::min(m, j.determinant());
  }
  return m;
}

long long multinomial(const std::array<int, 4>& a) {
  auto f = [](int n) {
    long long r = 1;
    for (int i = 2; i <= n; ++i) r *= i;
    return r;
  };
  return f(a[0] + a[1] + a[2] + a[3]) / (f(a[0]) * f(a[1]) * f(a[2]) * f(a[3]));
}

// Σ_β b_β B_β(λ(ξ)) for the degree-d Bernstein basis labelled by `lattice`.
double bernstein_value(const Eigen::MatrixXi& lattice, const Eigen::VectorXd& b,
                       const Eigen::Vector3d& xi) {
  const double lambda[4] = {1.0 - xi.sum(), xi[0], xi[1], xi[2]};
  double s = 0.0;
  for (int a = 0; a < lattice.rows(); ++a) {
    std::array<int, 4> e{lattice(a, 0), lattice(a, 1), lattice(a, 2), lattice(a, 3)};
    double v = static_cast<double>(multinomial(e));
    for (int i = 0; i < 4; ++i) v *= std::pow(lambda[i], e[i]);
    s += b[a] * v;
  }
  return s;
}

// ---------------------------------------------------------------------------------------------
// Tables

TEST(JacobianTables, LatticeIsTheCanonicalOrderAtDegreeD) {
  EXPECT_EQ(jacobian_degree(1), 0);
  const Eigen::MatrixXi l1 = jacobian_lattice(1);
  ASSERT_EQ(l1.rows(), 1);
  EXPECT_EQ(l1.sum(), 0);
  for (int k = 2; k <= 4; ++k) {
    const int d = jacobian_degree(k);
    EXPECT_EQ(d, 3 * (k - 1));
    const Eigen::MatrixXi l = jacobian_lattice(k);
    const auto& core = curvefem::lagrange_lattice(CellKind::tetrahedron, d);
    ASSERT_EQ(static_cast<std::size_t>(l.rows()), core.size()) << "k=" << k;
    for (int j = 0; j < l.rows(); ++j)
      for (int i = 0; i < 4; ++i) ASSERT_EQ(l(j, i), core[j][i]) << "k=" << k << " j=" << j;
    // The first four points are the vertices (corner coefficients are vertex values).
    for (int v = 0; v < 4; ++v) EXPECT_EQ(l(v, v), d);
  }
}

TEST(JacobianTables, GradientsMatchTheCoreBasis) {
  for (const auto& t : table::k_bernstein_tables) {
    EXPECT_EQ(t.degree, 3 * (t.order - 1));
    EXPECT_EQ(t.num_nodes, num_nodes(t.order));
    double worst = 0.0;
    for (int j = 0; j < t.num_lattice; ++j) {
      const int* beta = t.lattice + 4 * j;
      const Eigen::Vector3d xi(double(beta[1]) / t.degree, double(beta[2]) / t.degree,
                               double(beta[3]) / t.degree);
      const Eigen::MatrixXd g =
          curvefem::lagrange_shape_gradients(CellKind::tetrahedron, t.order, xi);
      for (int i = 0; i < t.num_nodes; ++i)
        for (int c = 0; c < 3; ++c)
          worst = std::max(
              worst, std::abs(t.gradients[(j * t.num_nodes + i) * 3 + c] / t.gradient_denominator -
                              g(i, c)));
    }
    EXPECT_LT(worst, 1e-11) << "order " << t.order;
  }
}

// M · V = I with V the Bernstein Vandermonde: W = d^d V is an exact integer matrix, and
// Σ_j lower[a][j] W[j][c] ≤ d^d δ_ac ≤ Σ_j upper[a][j] W[j][c] (W ≥ 0). The sums run in long double
// with their rounding error bound subtracted, so a failure is a real enclosure failure.
TEST(JacobianTables, ConversionMatrixInvertsTheBernsteinVandermonde) {
  for (const auto& t : table::k_bernstein_tables) {
    const int m = t.num_lattice, d = t.degree;
    std::vector<long double> w(static_cast<std::size_t>(m) * m);  // w[j*m + c]
    for (int j = 0; j < m; ++j)
      for (int c = 0; c < m; ++c) {
        const int* beta = t.lattice + 4 * j;
        const int* alpha = t.lattice + 4 * c;
        long double v = multinomial({alpha[0], alpha[1], alpha[2], alpha[3]});
        for (int i = 0; i < 4; ++i) v *= std::pow(static_cast<long double>(beta[i]), alpha[i]);
        w[j * m + c] = v;
      }
    const long double scale = std::pow(static_cast<long double>(d), d);
    const long double eps = std::numeric_limits<long double>::epsilon();
    double worst_identity = 0.0;
    double max_abs_row = 0.0, max_width_row = 0.0;
    for (int a = 0; a < m; ++a) {
      double abs_row = 0.0, width_row = 0.0;
      for (int j = 0; j < m; ++j) {
        const double lo = t.l2b_lower[a * m + j], hi = t.l2b_upper[a * m + j];
        ASSERT_TRUE(lo == hi || std::nextafter(lo, INFINITY) == hi) << a << " " << j;
        abs_row += std::max(std::abs(lo), std::abs(hi));
        width_row += hi - lo;
      }
      max_abs_row = std::max(max_abs_row, abs_row);
      max_width_row = std::max(max_width_row, width_row);
      for (int c = 0; c < m; ++c) {
        long double slo = 0, shi = 0, sabs = 0;
        for (int j = 0; j < m; ++j) {
          slo += t.l2b_lower[a * m + j] * w[j * m + c];
          shi += t.l2b_upper[a * m + j] * w[j * m + c];
          sabs += std::abs(static_cast<long double>(t.l2b_upper[a * m + j])) * w[j * m + c];
        }
        const long double err = 2 * m * eps * sabs;
        const long double target = a == c ? scale : 0;
        EXPECT_LE(slo - err, target) << "d=" << d << " a=" << a << " c=" << c;
        EXPECT_GE(shi + err, target) << "d=" << d << " a=" << a << " c=" << c;
        worst_identity =
            std::max(worst_identity, static_cast<double>(std::abs(slo - target) / scale));
      }
    }
    EXPECT_LT(worst_identity, 1e-10) << "d=" << d;
    // The emitted row-sum bounds really bound the row sums (up to the rounding of this sum).
    EXPECT_GE(t.l2b_abs_row_sum, max_abs_row * (1 - 1e-12)) << "d=" << d;
    EXPECT_GE(t.l2b_width_row_sum, max_width_row * (1 - 1e-12)) << "d=" << d;
    EXPECT_GT(t.l2b_width_row_sum, 0.0);
  }
}

// ---------------------------------------------------------------------------------------------
// Straight tets

// Integer vertices, multiples of 12: every node of order 1..4 is an exact integer, the map is
// exactly affine and det J = 6·volume exactly; the proven enclosures must contain it.
TEST(JacobianCertificate, StraightTetsAreCertifiedAndEncloseSixVolume) {
  std::mt19937 rng(12);
  std::uniform_int_distribution<int> coord(-20, 20);
  int tested = 0;
  while (tested < 12) {
    Vertices v;
    for (int a = 0; a < 4; ++a)
      for (int c = 0; c < 3; ++c) v(a, c) = 12.0 * coord(rng);
    const long double vol6 = six_volume(v);
    if (vol6 <= 1000.0L) continue;  // keep positively oriented, non-degenerate ones
    ++tested;
    for (int k = 1; k <= 4; ++k) {
      const Eigen::MatrixXd x = straight_tet(k, v);
      const JacobianCertificate c = certify_tet_jacobian(k, x);
      ASSERT_EQ(c.verdict, JacobianVerdict::positive) << "k=" << k;
      EXPECT_EQ(c.depth_reached, 0);
      EXPECT_EQ(c.subtets_visited, 0);
      EXPECT_LE(c.min_lattice_lower, vol6) << "k=" << k;
      EXPECT_GE(c.min_lattice_upper, vol6) << "k=" << k;
      EXPECT_LE(c.lower_bound, vol6) << "k=" << k;
      EXPECT_GE(c.min_upper_bound, vol6) << "k=" << k;
      EXPECT_GT(c.lower_bound, 0.0);
      // Tight enough: the a priori bounds lose < 1e-4 relative even on these flattish tets.
      EXPECT_GT(c.lower_bound, static_cast<double>(vol6) * (1 - 1e-4)) << "k=" << k;
      EXPECT_NEAR(c.min_lattice_estimate, static_cast<double>(vol6), 1e-12 * vol6) << "k=" << k;
    }
  }
}

TEST(JacobianCertificate, StraightRealTetsAreCertified) {
  std::mt19937 rng(3);
  std::normal_distribution<double> n(0.0, 0.1);
  for (int trial = 0; trial < 20; ++trial) {
    Vertices v = regular_vertices();
    for (int a = 0; a < 4; ++a)
      for (int c = 0; c < 3; ++c) v(a, c) = 1e3 + v(a, c) + n(rng);  // far from the origin
    const double vol6 = static_cast<double>(six_volume(v));
    for (int k = 1; k <= 4; ++k) {
      const JacobianCertificate c = certify_tet_jacobian(k, straight_tet(k, v));
      ASSERT_EQ(c.verdict, JacobianVerdict::positive) << "k=" << k;
      EXPECT_NEAR(c.min_lattice_estimate, vol6, 1e-9 * vol6);
      EXPECT_LE(c.lower_bound, vol6 * (1 + 1e-9));
      EXPECT_GT(c.lower_bound, vol6 * (1 - 1e-6));
    }
  }
}

TEST(JacobianCertificate, InvertedStraightTetsAreNonPositive) {
  Vertices v = regular_vertices();
  v.row(1).swap(v.row(2));  // negative orientation
  for (int k = 1; k <= 4; ++k) {
    const JacobianCertificate c = certify_tet_jacobian(k, straight_tet(k, v));
    EXPECT_EQ(c.verdict, JacobianVerdict::non_positive) << "k=" << k;
    EXPECT_LT(c.min_upper_bound, 0.0);
    EXPECT_NEAR(c.min_lattice_estimate, -std::sqrt(0.5), 1e-12);
  }
}

TEST(JacobianCertificate, FlatTetIsNeverPositive) {
  Vertices v;
  v << 0, 0, 0, 12, 0, 0, 0, 12, 0, 12, 12, 0;  // coplanar: det J = 0 exactly
  for (int k = 1; k <= 4; ++k) {
    CertificateOptions opts;
    opts.max_depth = 2;
    const JacobianCertificate c = certify_tet_jacobian(k, straight_tet(k, v), opts);
    EXPECT_NE(c.verdict, JacobianVerdict::positive) << "k=" << k;
    EXPECT_LE(c.min_lattice_lower, 0.0);
    EXPECT_GE(c.min_lattice_upper, 0.0);
  }
}

TEST(JacobianCertificate, NonFiniteInputIsUndecided) {
  Eigen::MatrixXd x = straight_tet(2, regular_vertices());
  x(5, 1) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(certify_tet_jacobian(2, x).verdict, JacobianVerdict::undecided);
  x(5, 1) = std::numeric_limits<double>::infinity();
  EXPECT_EQ(certify_tet_jacobian(2, x).verdict, JacobianVerdict::undecided);
}

TEST(JacobianCertificate, BadInputThrows) {
  const Eigen::MatrixXd x = straight_tet(2, regular_vertices());
  EXPECT_THROW(certify_tet_jacobian(5, x), curvefem::InputError);
  EXPECT_THROW(certify_tet_jacobian(0, x), curvefem::InputError);
  EXPECT_THROW(certify_tet_jacobian(3, x), curvefem::InputError);  // 10 nodes for order 3
  EXPECT_THROW(certify_tet_jacobian(2, Eigen::MatrixXd(10, 2)), curvefem::InputError);
}

// ---------------------------------------------------------------------------------------------
// Curved tets

// The reference tet with edge nodes pushed so that det J stays positive at every degree-d lattice
// point but becomes negative inside: the certificate must not say positive. P3/P4 push one node of
// edge (0,1); P2 (a cubic det J, harder to fool) pushes all six edge nodes. Parameters come from a
// random scan; the test re-checks both properties independently of the certificate.
struct HiddenFold {
  int order;
  std::vector<std::pair<int, Eigen::Vector3d>> shifts;  // (node, displacement)
};

TEST(JacobianCertificate, NegativeBetweenLatticePointsIsNotPositive) {
  const double t2 = 0.47;
  const std::vector<HiddenFold> cases = {
      {2,
       {{4, t2 * Eigen::Vector3d(-0.545322, -0.362056, 0.956446)},
        {5, t2 * Eigen::Vector3d(-0.0888302, -0.383974, -0.472258)},
        {6, t2 * Eigen::Vector3d(-0.826513, -0.161256, -0.968179)},
        {7, t2 * Eigen::Vector3d(0.0555296, 0.737603, -0.338322)},
        {8, t2 * Eigen::Vector3d(-0.214115, 0.348661, 0.344635)},
        {9, t2 * Eigen::Vector3d(0.388063, -0.308054, 0.859056)}}},
      {3, {{5, 0.46 * Eigen::Vector3d(-0.696, -0.072, -0.394)}}},
      {4, {{4, 0.17 * Eigen::Vector3d(0.171, 0.887, -0.153)}}},
  };
  const auto pts = sample_points(24, 0, 1);
  for (const HiddenFold& h : cases) {
    const int k = h.order, d = 3 * (k - 1);
    Eigen::MatrixXd x = curvefem::lagrange_reference_nodes(CellKind::tetrahedron, k);
    for (const auto& [node, shift] : h.shifts) x.row(node) += shift.transpose();
    // Positive at every lattice point (computed independently of the certificate) ...
    const Eigen::MatrixXi lat = jacobian_lattice(k);
    double lattice_min = std::numeric_limits<double>::infinity();
    for (int j = 0; j < lat.rows(); ++j)
      lattice_min = std::min(
          lattice_min,
          det_j(k, x, Eigen::Vector3d(lat(j, 1), lat(j, 2), lat(j, 3)) / static_cast<double>(d)));
    ASSERT_GT(lattice_min, 0.0) << "k=" << k;
    // ... negative somewhere inside.
    double inside_min = std::numeric_limits<double>::infinity();
    for (const auto& p : pts) inside_min = std::min(inside_min, det_j(k, x, p));
    ASSERT_LT(inside_min, 0.0) << "k=" << k;

    const JacobianCertificate c = certify_tet_jacobian(k, x);
    EXPECT_NE(c.verdict, JacobianVerdict::positive) << "k=" << k;
    EXPECT_GT(c.min_lattice_lower, 0.0) << "k=" << k;  // the lattice alone cannot reject it
    EXPECT_GE(c.depth_reached, 1) << "k=" << k;
    EXPECT_EQ(c.verdict, JacobianVerdict::non_positive) << "k=" << k;
    EXPECT_LE(c.min_upper_bound, 0.0) << "k=" << k;
  }
}

// Mildly curved random tets (fixed seed): node noise of several amplitudes. Whenever the
// certificate says positive, no sample is ≤ 0; whenever a sample is ≤ 0, it does not say positive;
// non_positive is a proof too (min_upper_bound ≤ 0). Both outcomes must occur.
TEST(JacobianCertificate, AgreesWithDenseSampling) {
  const auto pts = sample_points(12, 300, 5);
  std::mt19937 rng(2024);
  std::normal_distribution<double> n(0.0, 1.0);
  for (int k = 2; k <= 4; ++k) {
    const auto grads = gradients_at(k, pts);
    const Eigen::MatrixXd ref = straight_tet(k, regular_vertices());
    int positive = 0, non_positive = 0, sampled_negative = 0, refined_positive = 0;
    for (int trial = 0; trial < 120; ++trial) {
      const double amp = (0.02 + 0.01 * (trial % 12)) * (k == 2 ? 3.0 : 1.0) / k;
      Eigen::MatrixXd x = ref;
      for (int i = 4; i < x.rows(); ++i)
        for (int c = 0; c < 3; ++c) x(i, c) += amp * n(rng);
      const JacobianCertificate cert = certify_tet_jacobian(k, x);
      const double smin = sampled_min(x, grads);
      if (cert.verdict == JacobianVerdict::positive) {
        ++positive;
        if (cert.depth_reached > 0) ++refined_positive;
        EXPECT_GT(smin, 0.0) << "k=" << k << " trial " << trial;
        EXPECT_LE(cert.lower_bound, smin) << "k=" << k << " trial " << trial;
      }
      if (cert.verdict == JacobianVerdict::non_positive) {
        ++non_positive;
        EXPECT_LE(cert.min_upper_bound, 0.0);
      }
      if (smin <= 0.0) {
        ++sampled_negative;
        EXPECT_NE(cert.verdict, JacobianVerdict::positive) << "k=" << k << " trial " << trial;
      }
      EXPECT_LE(cert.min_lattice_lower, cert.min_lattice_estimate);
      EXPECT_GE(cert.min_lattice_upper, cert.min_lattice_estimate);
    }
    EXPECT_GT(positive, 20) << "k=" << k;
    EXPECT_GT(non_positive, 5) << "k=" << k;
    EXPECT_GT(sampled_negative, 0) << "k=" << k;
    if (k > 2) EXPECT_GT(refined_positive, 0) << "k=" << k << ": no case needed subdivision";
    RecordProperty("k" + std::to_string(k) + "_positive_nonpositive_sampledneg_refined",
                   std::to_string(positive) + "/" + std::to_string(non_positive) + "/" +
                       std::to_string(sampled_negative) + "/" + std::to_string(refined_positive));
  }
}

// Smoothly curved tets (a smooth displacement field, as curved meshes are): all certified.
TEST(JacobianCertificate, SmoothlyCurvedTetsArePositive) {
  for (int k = 2; k <= 4; ++k) {
    Eigen::MatrixXd x = straight_tet(k, regular_vertices());
    for (int i = 0; i < x.rows(); ++i) {
      const Eigen::RowVector3d p = x.row(i);
      x(i, 0) += 0.08 * std::sin(2.0 * p[1]);
      x(i, 1) += 0.08 * std::sin(2.0 * p[2] + 1.0);
      x(i, 2) += 0.08 * std::cos(2.0 * p[0]);
    }
    const JacobianCertificate c = certify_tet_jacobian(k, x);
    EXPECT_EQ(c.verdict, JacobianVerdict::positive) << "k=" << k;
    EXPECT_GT(c.lower_bound, 0.3);
  }
}

TEST(JacobianCertificate, BernsteinFormReproducesDetJ) {
  std::mt19937 rng(9);
  std::normal_distribution<double> n(0.0, 1.0);
  const auto pts = sample_points(2, 40, 11);
  for (int k = 1; k <= 4; ++k) {
    Eigen::MatrixXd x = straight_tet(k, regular_vertices());
    for (int i = 4; i < x.rows(); ++i)
      for (int c = 0; c < 3; ++c) x(i, c) += 0.05 * n(rng);
    const Eigen::VectorXd b = jacobian_bernstein_coefficients(k, x);
    const Eigen::MatrixXi lat = jacobian_lattice(k);
    ASSERT_EQ(b.size(), lat.rows());
    double scale = 0.0, worst = 0.0;
    for (const auto& p : pts) {
      const double exact = det_j(k, x, p);
      scale = std::max(scale, std::abs(exact));
      worst = std::max(worst, std::abs(bernstein_value(lat, b, p) - exact));
    }
    EXPECT_LT(worst, 1e-10 * scale) << "k=" << k;
    // Corner coefficients are the vertex values.
    for (int v = 0; v < (k > 1 ? 4 : 0); ++v) {
      Eigen::Vector3d xi = Eigen::Vector3d::Zero();
      if (v > 0) xi[v - 1] = 1.0;
      EXPECT_NEAR(b[v], det_j(k, x, xi), 1e-10 * scale);
    }
  }
}

// The same answer bit for bit in another thread and under another rounding mode.
TEST(JacobianCertificate, ReentrantAndRoundingModeIndependent) {
  Eigen::MatrixXd x = straight_tet(4, regular_vertices());
  x.row(7) += Eigen::RowVector3d(0.05, -0.03, 0.02);
  const JacobianCertificate a = certify_tet_jacobian(4, x);
  JacobianCertificate b, c;
  std::thread th1([&] { b = certify_tet_jacobian(4, x); });
  std::thread th2([&] {
    std::fesetround(FE_UPWARD);
    c = certify_tet_jacobian(4, x);
    EXPECT_EQ(std::fegetround(), FE_UPWARD);  // restored
    std::fesetround(FE_TONEAREST);
  });
  th1.join();
  th2.join();
  for (const JacobianCertificate* o : {&b, &c}) {
    EXPECT_EQ(o->verdict, a.verdict);
    EXPECT_EQ(o->lower_bound, a.lower_bound);
    EXPECT_EQ(o->min_lattice_lower, a.min_lattice_lower);
    EXPECT_EQ(o->subtets_visited, a.subtets_visited);
  }
}

// ---------------------------------------------------------------------------------------------
// Affine path (nearly straight tets)

// Long double reference: order-k basis gradients and det J, independent of the certificate.
using Vec3L = std::array<long double, 3>;

// ∇N_i at ξ for every node (canonical order), from the product form
// N_α = Π_i Π_{t<α_i} (k λ_i − t)/(t + 1), in long double.
std::vector<Vec3L> gradients_ld(int k, const Vec3L& xi) {
  const auto& lattice = curvefem::lagrange_lattice(CellKind::tetrahedron, k);
  const long double lam[4] = {1.0L - xi[0] - xi[1] - xi[2], xi[0], xi[1], xi[2]};
  std::vector<Vec3L> g(lattice.size());
  for (std::size_t n = 0; n < lattice.size(); ++n) {
    long double val[4], der[4];
    for (int i = 0; i < 4; ++i) {
      long double v = 1.0L, d = 0.0L;
      for (int t = 0; t < lattice[n][i]; ++t) {
        const long double f = (k * lam[i] - t) / (t + 1),
                          df = static_cast<long double>(k) / (t + 1);
        d = d * f + v * df;
        v *= f;
      }
      val[i] = v;
      der[i] = d;
    }
    long double dlam[4];
    for (int i = 0; i < 4; ++i) {
      dlam[i] = der[i];
      for (int j = 0; j < 4; ++j)
        if (j != i) dlam[i] *= val[j];
    }
    for (int c = 0; c < 3; ++c) g[n][c] = dlam[c + 1] - dlam[0];
  }
  return g;
}

// Gradients at the level-L lattice plus `extra` random interior points (fixed seed).
std::vector<std::vector<Vec3L>> gradients_ld_at(int k, int level, int extra, unsigned seed) {
  std::vector<std::vector<Vec3L>> out;
  for (const Eigen::Vector3d& p : sample_points(level, extra, seed))
    out.push_back(gradients_ld(k, {p[0], p[1], p[2]}));
  return out;
}

// min over the sample points of det J, J = Σ_i (x_i − x_0) ∇N_iᵀ in long double.
long double sampled_min_ld(const Eigen::MatrixXd& x, const std::vector<std::vector<Vec3L>>& grads) {
  long double best = std::numeric_limits<long double>::infinity();
  for (const auto& g : grads) {
    long double j[3][3] = {};
    for (int i = 1; i < x.rows(); ++i)
      for (int r = 0; r < 3; ++r) {
        const long double d = static_cast<long double>(x(i, r)) - static_cast<long double>(x(0, r));
        for (int c = 0; c < 3; ++c) j[r][c] += d * g[i][c];
      }
    const long double det = j[0][0] * (j[1][1] * j[2][2] - j[1][2] * j[2][1]) -
                            j[0][1] * (j[1][0] * j[2][2] - j[1][2] * j[2][0]) +
                            j[0][2] * (j[1][0] * j[2][1] - j[1][1] * j[2][0]);
    best = std::min(best, det);
  }
  return best;
}

std::string sci(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g", v);
  return buf;
}

CertificateOptions without_affine_path() {
  CertificateOptions o;
  o.affine_path = false;
  return o;
}

// A fixed rotation (not axis-aligned, so rounding deviations leave the plane of a flat tet).
Eigen::Matrix3d tilted_frame() {
  return (Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()) *
          Eigen::AngleAxisd(-0.4, Eigen::Vector3d(-2, 1, 0.5).normalized()))
      .toRotationMatrix();
}

// Flat tet: base triangle (edges ~1) in a tilted plane, apex at height h above it, all moved by
// `offset`; vertices rounded to doubles, nodes interpolated in floating point (straight_tet).
Vertices flat_vertices(double h, const Eigen::Vector3d& offset) {
  Eigen::Matrix<double, 4, 3> local;
  local << 0.1, 0.2, 0.0, 1.3, 0.1, 0.0, 0.45, 1.1, 0.0, 0.5, 0.4, h;
  const Eigen::Matrix3d rot = tilted_frame();
  Vertices v;
  for (int a = 0; a < 4; ++a) v.row(a) = (rot * local.row(a).transpose() + offset).transpose();
  return v;
}

// Λ_c really bounds Σ_{i≥4} |∂N_i/∂ξ_c| (sampled, long double), and is not far above it.
TEST(JacobianTables, GradientBoundsDominateTheBasisGradientSums) {
  const auto pts = sample_points(30, 2000, 17);
  for (int k = 1; k <= 4; ++k) {
    double sampled[3] = {0.0, 0.0, 0.0};
    for (const Eigen::Vector3d& p : pts) {
      const std::vector<Vec3L> g = gradients_ld(k, {p[0], p[1], p[2]});
      for (int c = 0; c < 3; ++c) {
        long double s = 0.0L;
        for (std::size_t i = 4; i < g.size(); ++i) s += std::abs(g[i][c]);
        sampled[c] = std::max(sampled[c], static_cast<double>(s));
      }
    }
    for (int c = 0; c < 3; ++c) {
      const double lambda = table::k_gradient_bernstein_bounds[k - 1][c];
      EXPECT_LE(sampled[c], lambda * (1 + 1e-12)) << "k=" << k << " c=" << c;
      if (k == 1) EXPECT_EQ(lambda, 0.0);
      if (k == 2) EXPECT_NEAR(sampled[c], lambda, 1e-12);  // linear gradients: exact at vertices
      if (k > 2) EXPECT_GT(sampled[c], 0.75 * lambda) << "k=" << k << " c=" << c;
    }
  }
}

// (1) Straight tets made extremely flat (height/edge 1e-6 .. 1e-12; P1 1e-14), nodes interpolated
// in floating point: the Bernstein / subdivision path alone is undecided on the flattest ones, the
// affine path certifies all of them without subdivision, with a lower bound within 1e-4
// (h ≥ 1e-8) or 1e-2 (h ≥ 1e-10) of 6·volume.
TEST(JacobianAffinePath, FlatStraightTetsArePositive) {
  const Eigen::Vector3d offsets[2] = {Eigen::Vector3d::Zero(), Eigen::Vector3d(3.0, -2.0, 5.0)};
  // Flatness at and below which the path without step 3 gives up on this geometry (measured).
  const double old_undecided_below[5] = {0, 1e-14, 1e-12, 1e-10, 1e-8};
  for (int k = 1; k <= 4; ++k) {
    int old_undecided = 0;
    for (const Eigen::Vector3d& offset : offsets)
      for (double h : {1e-6, 1e-8, 1e-10, 1e-11, 1e-12, 1e-14}) {
        if (h < 1e-11 && offset.norm() > 0 && k > 1) continue;  // beyond the affine path's reach
        if (h < 1e-12 && k > 1) continue;
        const Vertices v = flat_vertices(h, offset);
        const long double vol6 = six_volume(v);
        ASSERT_GT(vol6, 0.0L);
        const Eigen::MatrixXd x = straight_tet(k, v);
        const JacobianCertificate old = certify_tet_jacobian(k, x, without_affine_path());
        const JacobianCertificate c = certify_tet_jacobian(k, x);
        const std::string where =
            "k=" + std::to_string(k) + " h=" + sci(h) + " offset=" + sci(offset.norm());
        EXPECT_NE(old.verdict, JacobianVerdict::non_positive) << where;
        if (h <= old_undecided_below[k] && offset.norm() == 0) {
          EXPECT_EQ(old.verdict, JacobianVerdict::undecided) << where;
          EXPECT_EQ(old.decided_by, CertificatePath::none) << where;
        }
        if (old.verdict == JacobianVerdict::undecided) ++old_undecided;
        ASSERT_EQ(c.verdict, JacobianVerdict::positive) << where;
        if (old.verdict != JacobianVerdict::positive) {
          EXPECT_EQ(c.decided_by, CertificatePath::affine) << where;
        } else {
          EXPECT_EQ(c.decided_by, CertificatePath::bernstein) << where;
          EXPECT_GE(c.lower_bound, old.lower_bound) << where;  // the larger proven bound
        }
        EXPECT_EQ(c.subtets_visited, 0) << where;
        EXPECT_EQ(c.depth_reached, 0) << where;
        EXPECT_LE(c.lower_bound, static_cast<double>(vol6)) << where;
        const double slack = h >= 1e-8 ? 1e-4 : h >= 1e-10 ? 1e-2 : 1.0;
        EXPECT_GT(c.lower_bound, static_cast<double>(vol6) * (1 - slack)) << where;
        EXPECT_LE(c.min_upper_bound, c.min_lattice_upper) << where;
        EXPECT_GE(c.min_upper_bound, c.lower_bound) << where;
      }
    EXPECT_GT(old_undecided, 0) << "k=" << k << ": no case needed the affine path";
  }
}

// Inverted flat straight tets: the affine path proves det J ≤ 0 everywhere (det J_a + δ ≤ 0).
TEST(JacobianAffinePath, InvertedFlatStraightTetsAreNonPositive) {
  for (int k = 1; k <= 4; ++k) {
    Vertices v = flat_vertices(1e-10, Eigen::Vector3d::Zero());
    v.row(1).swap(v.row(2));
    const JacobianCertificate c = certify_tet_jacobian(k, straight_tet(k, v));
    EXPECT_EQ(c.verdict, JacobianVerdict::non_positive) << "k=" << k;
    EXPECT_LE(c.min_upper_bound, 0.0) << "k=" << k;
    EXPECT_NE(certify_tet_jacobian(k, straight_tet(k, v), without_affine_path()).verdict,
              JacobianVerdict::positive);
  }
}

// (2) A flat tet (height 1e-9, P2: 1e-12) with the first node of edge (0,3) pushed along the
// normal, through the base face, by s·h: det J turns negative somewhere once s is large enough
// (checked by dense long double sampling). Whenever it does, the verdict is not positive (the
// affine path's δ exceeds det J_a); small pushes are still certified by the affine path.
TEST(JacobianAffinePath, FlatTetWithAFoldIsNotPositive) {
  const Eigen::Vector3d normal = tilted_frame().col(2);
  for (int k = 2; k <= 4; ++k) {
    const double h = k == 2 ? 1e-12 : 1e-9;  // where the path without the affine step gives up
    const Vertices v = flat_vertices(h, Eigen::Vector3d(0.5, 0.25, -1.0));
    const auto grads = gradients_ld_at(k, 3 * k, 300, 23);
    const long double vol6 = six_volume(v);
    const int node = 4 + 2 * (k - 1);  // edge (0,3), next to vertex 0
    double largest_certified = 0.0, largest_by_affine = 0.0;
    double smallest_negative = std::numeric_limits<double>::infinity();
    int negative = 0;
    for (int step = 0; step <= 80; ++step) {
      const double s = step == 0 ? 0.0 : std::pow(10.0, -4.0 + step * 0.05);  // 1e-4 .. 1e0
      Eigen::MatrixXd x = straight_tet(k, v);
      x.row(node) -= (s * h) * normal.transpose();
      const long double smin = sampled_min_ld(x, grads);
      const JacobianCertificate c = certify_tet_jacobian(k, x);
      const std::string where = "k=" + std::to_string(k) + " s=" + sci(s);
      if (smin < -1e-9L * vol6) {
        ++negative;
        smallest_negative = std::min(smallest_negative, s);
        EXPECT_NE(c.verdict, JacobianVerdict::positive) << where;
        EXPECT_NE(certify_tet_jacobian(k, x, without_affine_path()).verdict,
                  JacobianVerdict::positive)
            << where;
      }
      if (c.verdict == JacobianVerdict::positive) {
        largest_certified = std::max(largest_certified, s);
        if (c.decided_by == CertificatePath::affine)
          largest_by_affine = std::max(largest_by_affine, s);
        EXPECT_GT(smin, 0.0L) << where;
        EXPECT_LE(c.lower_bound, static_cast<double>(smin)) << where;
      }
      if (c.verdict == JacobianVerdict::non_positive) EXPECT_LE(c.min_upper_bound, 0.0) << where;
    }
    // Pushed by 2h through the base face: negative, and not positive.
    Eigen::MatrixXd x = straight_tet(k, v);
    x.row(node) -= (2.0 * h) * normal.transpose();
    ASSERT_LT(sampled_min_ld(x, grads), 0.0L) << "k=" << k;
    EXPECT_NE(certify_tet_jacobian(k, x).verdict, JacobianVerdict::positive) << "k=" << k;
    EXPECT_GT(negative, 10) << "k=" << k;
    EXPECT_GT(largest_by_affine, 1e-3) << "k=" << k;  // tiny pushes: the affine path certifies
    EXPECT_LT(largest_certified, smallest_negative) << "k=" << k;
    RecordProperty("k" + std::to_string(k) + "_largest_certified_push_over_h",
                   std::to_string(largest_certified));
    RecordProperty("k" + std::to_string(k) + "_largest_push_over_h_certified_by_affine",
                   std::to_string(largest_by_affine));
    RecordProperty("k" + std::to_string(k) + "_smallest_negative_push_over_h",
                   std::to_string(smallest_negative));
  }
}

// (3) A sweep of 3000 nearly straight tets (flat and well-shaped, random perturbations of the
// non-corner nodes of the order of what makes det J change sign) against dense long double
// sampling: no positive verdict where a sample is negative, lower_bound below every sample,
// non_positive only with min_upper_bound ≤ 0, and never a contradiction with the path without the
// affine step.
TEST(JacobianAffinePath, NearlyStraightSweepAgreesWithLongDoubleSampling) {
  std::mt19937 rng(77);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  std::normal_distribution<double> normal(0.0, 1.0);
  const Eigen::Matrix3d rot = tilted_frame();
  for (int k = 1; k <= 4; ++k) {
    const auto grads = gradients_ld_at(k, k == 1 ? 1 : 2 * k, k == 1 ? 0 : 40, 31 + k);
    int by_affine = 0, positive = 0, negative = 0, non_positive = 0, old_undecided_now_positive = 0;
    for (int trial = 0; trial < 750; ++trial) {
      // height/edge 1e-2 .. 1e-11 (P1, P2, where the path without the affine step reaches
      // further: 1e-15, 1e-13)
      const double decades[5] = {0, 13, 11, 9, 9};
      const double h = std::pow(10.0, -2.0 - decades[k] * uni(rng));
      Eigen::Matrix<double, 4, 3> local;
      for (int a = 0; a < 3; ++a) local.row(a) << uni(rng), uni(rng), 0.0;
      local.row(3) << uni(rng), uni(rng), h;
      const double area2 = (local(1, 0) - local(0, 0)) * (local(2, 1) - local(0, 1)) -
                           (local(2, 0) - local(0, 0)) * (local(1, 1) - local(0, 1));
      if (std::abs(area2) < 0.05) {
        --trial;
        continue;
      }
      if (area2 < 0) local.row(1).swap(local.row(2));
      Vertices v;
      const Eigen::Vector3d offset(normal(rng), normal(rng), normal(rng));
      for (int a = 0; a < 4; ++a) v.row(a) = (rot * local.row(a).transpose() + offset).transpose();
      Eigen::MatrixXd x = straight_tet(k, v);
      // Perturbation: 10^-4 .. 10^0.5 times h, along random directions.
      const double amp = h * std::pow(10.0, -4.0 + 4.5 * uni(rng));
      for (int i = 4; i < x.rows(); ++i)
        for (int c = 0; c < 3; ++c) x(i, c) += amp * normal(rng);
      const long double smin = sampled_min_ld(x, grads);
      const long double scale = 1.0L;  // |J|³ ~ 1: edges ~1
      const JacobianCertificate c = certify_tet_jacobian(k, x);
      const JacobianCertificate old = certify_tet_jacobian(k, x, without_affine_path());
      const std::string where = "k=" + std::to_string(k) + " trial " + std::to_string(trial);
      if (smin < -1e-15L * scale) {
        ++negative;
        EXPECT_NE(c.verdict, JacobianVerdict::positive) << where;
      }
      if (c.verdict == JacobianVerdict::positive) {
        ++positive;
        if (c.decided_by == CertificatePath::affine) ++by_affine;
        if (old.verdict == JacobianVerdict::undecided) ++old_undecided_now_positive;
        EXPECT_GT(smin, 0.0L) << where;
        EXPECT_LE(c.lower_bound, static_cast<double>(smin + 1e-17L * scale)) << where;
      }
      if (c.verdict == JacobianVerdict::non_positive) {
        ++non_positive;
        EXPECT_LE(c.min_upper_bound, 0.0) << where;
      }
      // Two proofs never contradict each other.
      EXPECT_FALSE(c.verdict == JacobianVerdict::positive &&
                   old.verdict == JacobianVerdict::non_positive)
          << where;
      EXPECT_FALSE(c.verdict == JacobianVerdict::non_positive &&
                   old.verdict == JacobianVerdict::positive)
          << where;
      if (old.verdict != JacobianVerdict::undecided) EXPECT_EQ(c.verdict, old.verdict) << where;
    }
    EXPECT_GT(positive, 100) << "k=" << k;
    EXPECT_GT(by_affine, 50) << "k=" << k;
    if (k > 1) EXPECT_GT(negative, 50) << "k=" << k;
    EXPECT_GT(old_undecided_now_positive, 20) << "k=" << k;
    RecordProperty("k" + std::to_string(k) + "_positive_affine_negative_nonpositive_rescued",
                   std::to_string(positive) + "/" + std::to_string(by_affine) + "/" +
                       std::to_string(negative) + "/" + std::to_string(non_positive) + "/" +
                       std::to_string(old_undecided_now_positive));
  }
}

// (4) The affine path decides without subdivision; the path without it examines the whole
// sub-tet budget before giving up. Times are recorded (benchmarks own timings), not asserted.
TEST(JacobianAffinePath, DecidesWithoutSubdivision) {
  const Eigen::MatrixXd x = straight_tet(4, flat_vertices(1e-9, Eigen::Vector3d(1.0, 2.0, 3.0)));
  const JacobianCertificate old = certify_tet_jacobian(4, x, without_affine_path());
  EXPECT_EQ(old.verdict, JacobianVerdict::undecided);
  EXPECT_GT(old.subtets_visited, 0);
  const JacobianCertificate c = certify_tet_jacobian(4, x);
  EXPECT_EQ(c.verdict, JacobianVerdict::positive);
  EXPECT_EQ(c.decided_by, CertificatePath::affine);
  EXPECT_EQ(c.subtets_visited, 0);
  EXPECT_EQ(c.depth_reached, 0);
  auto time_us = [&](const CertificateOptions& o, int reps) {
    const auto t0 = std::chrono::steady_clock::now();
    for (int r = 0; r < reps; ++r) certify_tet_jacobian(4, x, o);
    return std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0)
               .count() /
           reps;
  };
  RecordProperty("p4_flat_affine_us", std::to_string(time_us(CertificateOptions{}, 200)));
  RecordProperty("p4_flat_without_affine_us", std::to_string(time_us(without_affine_path(), 20)));
  RecordProperty("p4_flat_without_affine_subtets", std::to_string(old.subtets_visited));
}

TEST(JacobianAffinePath, PathNames) {
  EXPECT_STREQ(to_string(CertificatePath::none), "none");
  EXPECT_STREQ(to_string(CertificatePath::affine), "affine");
  EXPECT_STREQ(to_string(CertificatePath::subdivision), "subdivision");
  // Decided paths of the classic cases.
  EXPECT_EQ(certify_tet_jacobian(2, straight_tet(2, regular_vertices())).decided_by,
            CertificatePath::bernstein);
  Vertices inv = regular_vertices();
  inv.row(1).swap(inv.row(2));
  EXPECT_EQ(certify_tet_jacobian(2, straight_tet(2, inv)).decided_by, CertificatePath::lattice);
}

// ---------------------------------------------------------------------------------------------
// Quality estimates

TEST(JacobianQuality, ScaledJacobianAndMips) {
  for (int k = 1; k <= 4; ++k) {
    const Eigen::MatrixXd regular = straight_tet(k, regular_vertices());
    EXPECT_NEAR(min_scaled_jacobian(k, regular), 1.0, 1e-12) << "k=" << k;
    const Eigen::MatrixXd right = curvefem::lagrange_reference_nodes(CellKind::tetrahedron, k);
    EXPECT_NEAR(min_scaled_jacobian(k, right), std::sqrt(0.5), 1e-12) << "k=" << k;
    EXPECT_NEAR(curved_mips(k, right), 9.0, 1e-10) << "k=" << k;
    // The regular tet, from the right reference: J = edge vectors, ‖J‖² = 3, ‖J⁻¹‖² = tr(Gram⁻¹)
    // = 4.5.
    EXPECT_NEAR(curved_mips(k, regular), 13.5, 1e-10) << "k=" << k;
    Vertices inv = regular_vertices();
    inv.row(1).swap(inv.row(2));
    EXPECT_LT(min_scaled_jacobian(k, straight_tet(k, inv)), 0.0);
    EXPECT_TRUE(std::isinf(curved_mips(k, straight_tet(k, inv))));
  }
  // Curving lowers the scaled Jacobian and raises MIPS.
  Eigen::MatrixXd x = straight_tet(3, regular_vertices());
  x.row(4) += Eigen::RowVector3d(0.0, 0.1, 0.1);
  EXPECT_LT(min_scaled_jacobian(3, x), 0.999);
  EXPECT_GT(curved_mips(3, x), 13.5);
}

// The definitions, evaluated the plain way (shape gradients at each point, the four corner frames
// as matrix products, a division per frame), against the library's tabulated and shortened
// evaluation, on curved tets from mild to folded.
TEST(JacobianQuality, ScaledJacobianAndMipsMatchTheirDefinitions) {
  const std::array<Eigen::Vector3d, 4> v = {Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX(),
                                            Eigen::Vector3d::UnitY(), Eigen::Vector3d::UnitZ()};
  std::array<Eigen::Matrix3d, 4> frames;  // edges from corner a, det +1
  for (int a = 0; a < 4; ++a) {
    int col = 0;
    for (int b = 0; b < 4; ++b)
      if (b != a) frames[a].col(col++) = v[b] - v[a];
    if (frames[a].determinant() < 0) frames[a].col(0).swap(frames[a].col(1));
  }
  std::mt19937 rng(11);
  int inverted = 0, compared = 0;
  for (int k = 1; k <= 4; ++k) {
    const Eigen::MatrixXd ref = curvefem::lagrange_reference_nodes(CellKind::tetrahedron, k);
    // det J has degree 3(k − 1): the library samples J on that lattice (one point for k = 1).
    const Eigen::MatrixXd sj_points =
        k == 1 ? Eigen::MatrixXd(Eigen::RowVector3d(0.25, 0.25, 0.25))
               : curvefem::lagrange_reference_nodes(CellKind::tetrahedron, 3 * (k - 1));
    const Eigen::MatrixXd mips_points =
        curvefem::lagrange_reference_nodes(CellKind::tetrahedron, 5);
    for (int trial = 0; trial < 300; ++trial) {
      const double amp = std::pow(10.0, -3.0 + 2.5 * (trial % 30) / 30.0);
      std::uniform_real_distribution<double> shape(-2, 2), bump(-amp, amp);
      Eigen::Matrix3d A;
      for (int i = 0; i < 9; ++i) A(i / 3, i % 3) = shape(rng);
      Eigen::MatrixXd x = ref * A.transpose();
      for (Eigen::Index r = 0; r < x.rows(); ++r)
        for (int c = 0; c < 3; ++c) x(r, c) += bump(rng);
      double sj = std::numeric_limits<double>::infinity();
      for (Eigen::Index p = 0; p < sj_points.rows(); ++p) {
        const Eigen::Matrix3d J =
            x.transpose() * curvefem::lagrange_shape_gradients(CellKind::tetrahedron, k,
                                                               Eigen::Vector3d(sj_points.row(p)));
        for (const Eigen::Matrix3d& T : frames) {
          const Eigen::Matrix3d E = J * T;
          const double len = E.col(0).norm() * E.col(1).norm() * E.col(2).norm();
          sj = std::min(sj, len > 0 ? std::sqrt(2.0) * J.determinant() / len : 0.0);
        }
      }
      double mips = 0;
      for (Eigen::Index p = 0; p < mips_points.rows() && std::isfinite(mips); ++p) {
        const Eigen::Matrix3d J =
            x.transpose() * curvefem::lagrange_shape_gradients(CellKind::tetrahedron, k,
                                                               Eigen::Vector3d(mips_points.row(p)));
        mips = J.determinant() > 0
                   ? mips + J.squaredNorm() * J.inverse().squaredNorm() / double(mips_points.rows())
                   : std::numeric_limits<double>::infinity();
      }
      const std::string at = "k=" + std::to_string(k) + " trial " + std::to_string(trial);
      EXPECT_NEAR(min_scaled_jacobian(k, x), sj, 1e-11 * std::max(1.0, std::abs(sj))) << at;
      // The single-point evaluation (the worst-cell search's quick rejection): at the argmin it
      // gives the minimum up to rounding, and nowhere less.
      int argmin = -1;
      const double minimum = min_scaled_jacobian(k, x, &argmin);
      ASSERT_GE(argmin, 0) << at;
      ASSERT_LT(argmin, sj_points.rows()) << at;
      EXPECT_NEAR(scaled_jacobian_at(k, x, argmin), minimum,
                  1e-14 * std::max(1.0, std::abs(minimum)))
          << at;
      for (Eigen::Index p = 0; p < sj_points.rows(); ++p)
        EXPECT_GE(scaled_jacobian_at(k, x, int(p)),
                  minimum - 1e-14 * std::max(1.0, std::abs(minimum)))
            << at << " point " << p;
      if (std::isfinite(mips)) {
        EXPECT_NEAR(curved_mips(k, x), mips, 1e-9 * mips) << at;
      } else {
        EXPECT_TRUE(std::isinf(curved_mips(k, x))) << at;
      }
      inverted += sj < 0;
      ++compared;
    }
  }
  // Both kinds were compared.
  EXPECT_GT(inverted, 50);
  EXPECT_GT(compared - inverted, 300);
  RecordProperty("inverted", std::to_string(inverted));
}

}  // namespace
