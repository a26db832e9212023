// Bounds on the elements a boundary allows (boundary_limits.hpp), checked against the quality
// measures of jacobian_certificate.hpp on straight tets: every tet's curved MIPS is at least the
// floor of each of its faces, and its min scaled Jacobian at most each face's and each edge's
// ceiling.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <numbers>
#include <random>

#include "meshing/curved/boundary_limits.hpp"
#include "meshing/curved/jacobian_certificate.hpp"

namespace cv = curvefem::meshing::curved;
using V3 = Eigen::Vector3d;

namespace {
// The 4 faces of a positively oriented tet, outward.
std::vector<std::array<int, 3>> tet_faces() { return {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}}; }
}  // namespace

TEST(BoundaryLimits, EveryStraightTetMeetsTheBoundsOfItsOwnFacesAndEdges) {
  std::mt19937 rng(7);
  std::normal_distribution<double> n(0, 1);
  std::uniform_real_distribution<double> u(-8, 0);
  int tested = 0, needles = 0;
  for (int i = 0; i < 4000; ++i) {
    Eigen::MatrixXd X(4, 3);
    for (int r = 0; r < 4; ++r) X.row(r) = V3(n(rng), n(rng), n(rng)).transpose();
    // Squash or stretch along random directions: needles, caps, slivers, wedges down to 1e-8.
    for (int s = 0; s < 2; ++s) {
      const V3 d = V3(n(rng), n(rng), n(rng)).normalized();
      const double f = std::pow(10.0, u(rng));
      for (int r = 0; r < 4; ++r) {
        const V3 x = X.row(r).transpose();
        X.row(r) = (x - (1 - f) * x.dot(d) * d).transpose();
      }
    }
    const double det = (V3(X.row(1)) - V3(X.row(0)))
                           .cross(V3(X.row(2)) - V3(X.row(0)))
                           .dot(V3(X.row(3)) - V3(X.row(0)));
    if (det == 0) continue;
    if (det < 0) X.row(0).swap(X.row(1));
    const double mips = cv::curved_mips(1, X);
    const double sj = cv::min_scaled_jacobian(1, X);
    const cv::BoundaryLimits b = cv::boundary_limits(X, tet_faces());
    ASSERT_EQ(b.faces, 4);
    ASSERT_EQ(b.edges, 6);
    EXPECT_GE(mips * (1 + 1e-9), b.mips_floor) << i;
    EXPECT_LE(sj, b.sj_ceiling * (1 + 1e-9) + 1e-15) << i;
    for (const auto& f : tet_faces()) {
      const V3 a = X.row(f[0]), c = X.row(f[1]), d = X.row(f[2]);
      EXPECT_GE(mips * (1 + 1e-9), cv::triangle_mips_floor(a, c, d)) << i;
      EXPECT_LE(sj, cv::triangle_sj_ceiling(a, c, d) * (1 + 1e-9) + 1e-15) << i;
    }
    // A tet's own edges are all convex, with interior angles below 180°.
    EXPECT_LT(b.min_dihedral_deg, 180);
    needles += b.mips_floor > 1e4;
    ++tested;
  }
  EXPECT_GT(tested, 3900);
  EXPECT_GT(needles, 100);  // the bound is exercised where it matters
}

TEST(BoundaryLimits, TheRegularTetAndANeedleFace) {
  // Regular tet: every face equilateral ((ℓ / 2h)² = 1/3), dihedral angles acos(1/3).
  Eigen::MatrixXd X(4, 3);
  X << 0, 0, 0, 1, 0, 0, 0.5, std::sqrt(3.0) / 2, 0, 0.5, std::sqrt(3.0) / 6, std::sqrt(2.0 / 3);
  const cv::BoundaryLimits b = cv::boundary_limits(X, tet_faces());
  EXPECT_NEAR(b.mips_floor, 1.0 / 3, 1e-12);
  EXPECT_NEAR(b.min_dihedral_deg, std::acos(1.0 / 3) * 180 / std::numbers::pi, 1e-9);
  EXPECT_NEAR(b.sj_ceiling, std::numbers::sqrt2 * std::sin(std::numbers::pi / 3), 1e-12);
  EXPECT_EQ(b.faces_mips_floor_above_1e4, 0);
  // cgal femur's coarse boundary face (edges 9.1e-3 and 1e-4): any tet on it has a MIPS of at
  // least 2,070; the best apex found numerically gives 8,466 (2026-12-07), above the bound.
  const V3 p(0, 0, 0), q(9.1e-3, 0, 0), r(9.1e-3, 1e-4, 0);
  const double floor = cv::triangle_mips_floor(p, q, r);
  EXPECT_GT(floor, 2000);
  EXPECT_LT(floor, 8466);
  EXPECT_NEAR(cv::triangle_sj_ceiling(p, q, r),
              std::numbers::sqrt2 * 1e-4 / q.norm() / r.norm() * 9.1e-3, 1e-9);
  EXPECT_TRUE(std::isinf(cv::triangle_mips_floor(p, q, 2 * q)));
  EXPECT_EQ(cv::triangle_sj_ceiling(p, q, 2 * q), 0.0);
}

TEST(BoundaryLimits, AKnifeEdgeIsFoundByItsDihedralAngleAndAReflexEdgeIsNot) {
  // A closed wedge: a triangular prism whose cross-section has a 0.1° angle at the knife edge
  // (x = 0), extruded along z; 8 outward triangles. Its caps have that angle too.
  const double angle = 0.1 * std::numbers::pi / 180, t = std::tan(angle);
  Eigen::MatrixXd X(6, 3);
  X << 0, 0, 0, 1, 0, 0, 1, t, 0, 0, 0, 1, 1, 0, 1, 1, t, 1;
  // bottom (z = 0) and top, then the three sides
  const std::vector<std::array<int, 3>> faces{{0, 2, 1}, {3, 4, 5}, {0, 1, 4}, {0, 4, 3},
                                              {1, 2, 5}, {1, 5, 4}, {2, 0, 3}, {2, 3, 5}};
  const cv::BoundaryLimits b = cv::boundary_limits(X, faces);
  EXPECT_EQ(b.edges, 12);
  EXPECT_NEAR(b.min_dihedral_deg, 0.1, 1e-9);
  EXPECT_NEAR(b.sj_ceiling, std::numbers::sqrt2 * std::sin(angle), 1e-12);  // 0.0025
  EXPECT_EQ(b.edges_sj_ceiling_below_1e2, 1);                               // the knife edge alone
  EXPECT_EQ(b.edges_sj_ceiling_below_1e3, 0);
  EXPECT_EQ(b.faces_sj_ceiling_below_1e2, 4);  // the caps and the 0.0017-wide back strip
  // The same surface bounding the outside (faces reversed): the knife edge is reflex (359.9°)
  // and bounds nothing; the smallest interior angle is the 180° of the side rectangles'
  // diagonals (the other edges are at 270° and more). The faces' bounds do not depend on the
  // side.
  std::vector<std::array<int, 3>> reversed;
  for (const auto& f : faces) reversed.push_back({f[0], f[2], f[1]});
  const cv::BoundaryLimits o = cv::boundary_limits(X, reversed);
  EXPECT_NEAR(o.min_dihedral_deg, 180.0, 1e-6);
  EXPECT_EQ(o.edges_sj_ceiling_below_1e2, 0);
  EXPECT_EQ(o.faces_sj_ceiling_below_1e2, 4);
  EXPECT_NEAR(o.mips_floor, b.mips_floor, 1e-9 * b.mips_floor);
}
