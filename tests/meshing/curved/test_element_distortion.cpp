// element_distortion.hpp: exact derivatives of the element map against hand-computed values.
#include <gtest/gtest.h>

#include <Eigen/SVD>
#include <cmath>

#include "meshing/core/error.hpp"
#include "meshing/core/lagrange_nodes.hpp"
#include "meshing/curved/element_distortion.hpp"

using namespace curvefem;
namespace cv = curvefem::meshing::curved;

namespace {
template <class Map>
Eigen::MatrixXd nodes_of(int k, const Map& F) {
  const Eigen::MatrixXd ref = lagrange_reference_nodes(CellKind::tetrahedron, k);
  Eigen::MatrixXd X(ref.rows(), 3);
  for (Eigen::Index i = 0; i < ref.rows(); ++i)
    X.row(i) = F(Eigen::Vector3d(ref.row(i))).transpose();
  return X;
}
}  // namespace

TEST(ElementDistortion, StraightTetsAreUndistortedAtEveryOrder) {
  const Eigen::Matrix3d A{{2, 0.3, -0.1}, {0.1, 1.5, 0.2}, {0, -0.4, 0.7}};
  for (int k = 1; k <= 4; ++k) {
    const auto e = cv::element_distortion(
        k, nodes_of(k, [&](const Eigen::Vector3d& x) { return Eigen::Vector3d(A * x); }));
    EXPECT_NEAR(e.jacobian_ratio, 1.0, 1e-12) << k;
    EXPECT_LT(e.d2, 1e-10) << k;
    EXPECT_LT(e.d3, 1e-10) << k;
  }
}

TEST(ElementDistortion, BentTetHasTheSecondDerivativeOfItsMap) {
  // F(ξ) = (ξ, η, ζ + a ξ²): ‖D²F‖ = 2a, det J = 1, largest ‖DF⁻¹‖ at ξ = 1 (a corner sample).
  const double a = 0.1;
  const auto F = [&](const Eigen::Vector3d& x) {
    return Eigen::Vector3d(x[0], x[1], x[2] + a * x[0] * x[0]);
  };
  Eigen::Matrix2d J2{{1, 0}, {2 * a, 1}};
  const double sigma = Eigen::JacobiSVD<Eigen::Matrix2d>(J2).singularValues()[1];
  for (int k = 2; k <= 4; ++k) {
    const auto e = cv::element_distortion(k, nodes_of(k, F));
    EXPECT_NEAR(e.jacobian_ratio, 1.0, 1e-12);
    EXPECT_NEAR(e.d2, 2 * a / sigma, 1e-10) << k;
    EXPECT_LT(e.d3, 1e-10) << k;
  }
  // A cubic term shows in d3 only from k = 3: F + (0, 0, b ξ³), ‖D³F‖ = 6b.
  const double b = 0.05;
  const auto G = [&](const Eigen::Vector3d& x) {
    return Eigen::Vector3d(F(x) + Eigen::Vector3d(0, 0, b * x[0] * x[0] * x[0]));
  };
  for (int k = 3; k <= 4; ++k) {
    const auto e = cv::element_distortion(k, nodes_of(k, G));
    EXPECT_GE(e.d3, 6 * b - 1e-10) << k;
    EXPECT_LE(e.d3, 6 * b / 0.5) << k;
  }
  EXPECT_THROW(cv::element_distortion(5, Eigen::MatrixXd::Zero(56, 3)), InputError);
  EXPECT_THROW(cv::element_distortion(2, Eigen::MatrixXd::Zero(9, 3)), InputError);
}
