// SLIM reweighting of the symmetric Dirichlet energy (see the header for the formulas).
#include "meshing/param/symmetric_dirichlet.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>

namespace curvefem::meshing::param {

Eigen::Matrix4d symmetric_dirichlet_hessian(const Eigen::Matrix2d& J, bool project) {
  const Eigen::Vector4d f(J(0, 0), J(0, 1), J(1, 0), J(1, 1));
  const Eigen::Vector4d g(J(1, 1), -J(1, 0), -J(0, 1), J(0, 0));
  const double det = J.determinant(), n = f.squaredNorm();
  const double i1 = 1.0 / det, i2 = i1 * i1, i3 = i2 * i1, i4 = i2 * i2;
  Eigen::Matrix4d d2;  // ∂²δ
  d2.setZero();
  d2(0, 3) = d2(3, 0) = 1.0;
  d2(1, 2) = d2(2, 1) = -1.0;
  Eigen::Matrix4d H = 2.0 * (1.0 + i2) * Eigen::Matrix4d::Identity() -
                      4.0 * i3 * (f * g.transpose() + g * f.transpose()) +
                      6.0 * n * i4 * g * g.transpose() - 2.0 * n * i3 * d2;
  if (!project) return H;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d> eig(H);
  const Eigen::Vector4d lambda = eig.eigenvalues().cwiseMax(0.0);
  return eig.eigenvectors() * lambda.asDiagonal() * eig.eigenvectors().transpose();
}

void slim_weights(const Eigen::Matrix2d& J, Eigen::Matrix2d& W, Eigen::Matrix2d& R) {
  const Eigen::JacobiSVD<Eigen::Matrix2d> svd(J, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::Matrix2d& U = svd.matrixU();
  const Eigen::Vector2d s = svd.singularValues();
  // det J > 0: det U = det V, so U Vᵀ is a rotation; W does not depend on the signs of U's columns.
  R = U * svd.matrixV().transpose();
  Eigen::Vector2d w;
  for (int i = 0; i < 2; ++i)
    w[i] = std::sqrt((1 + s[i]) * (1 + s[i] * s[i]) / (s[i] * s[i] * s[i]));
  W = U * w.asDiagonal() * U.transpose();
}

}  // namespace curvefem::meshing::param

namespace curvefem::meshing::param {

void slim_weights_3d(const Eigen::Matrix3d& J, Eigen::Matrix3d& W, Eigen::Matrix3d& R,
                     Eigen::Vector3d* singular_values) {
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(J, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d U = svd.matrixU(), V = svd.matrixV();
  Eigen::Vector3d s = svd.singularValues();
  // det J > 0 gives det U = det V; make both rotations (flipping the same column of each keeps
  // U Σ Vᵀ), so that R = U Vᵀ is the closest rotation.
  if (U.determinant() < 0) {
    U.col(2) *= -1;
    V.col(2) *= -1;
  }
  R = U * V.transpose();
  Eigen::Vector3d w;
  for (int i = 0; i < 3; ++i)
    w[i] = std::sqrt((1 + s[i]) * (1 + s[i] * s[i]) / (s[i] * s[i] * s[i]));
  W = U * w.asDiagonal() * U.transpose();
  if (singular_values) *singular_values = s;
}

}  // namespace curvefem::meshing::param
