// Certified positivity of det J (meshing/curved/jacobian_certificate.hpp).
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <array>
#include <cfenv>
#include <cmath>
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

}  // namespace
