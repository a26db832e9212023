// Symmetric Dirichlet energy of a 2 × 2 Jacobian and SLIM's reweighting (thesis §3.2.1 "Solver";
// Smith & Schaefer 2015; Rabinovich et al. 2017).
//
// D(J) = ‖J‖²_F + ‖J⁻¹‖²_F = σ₁² + σ₂² + σ₁⁻² + σ₂⁻² ≥ 4 (= 4 iff J is a rotation); for 2 × 2
// matrices ‖J⁻¹‖_F = ‖J‖_F / |det J|. D = +∞ when det J ≤ 0 (flipped or degenerate).
// SLIM weights: with J = U Σ Vᵀ (signed SVD, det U = det V = 1), the proxy ‖W (J − R)‖²_F with
// R = U Vᵀ and W = U diag(w₁, w₂) Uᵀ, w_i² = D'(σ_i) / (2 (σ_i − 1)) = (1 + σ_i)(1 + σ_i²) / σ_i³
// has the gradient of D at J.
#pragma once

#include <Eigen/Core>
#include <Eigen/LU>
#include <cmath>
#include <limits>

namespace curvefem::meshing::param {

inline double symmetric_dirichlet(const Eigen::Matrix2d& J) {
  const double det = J.determinant();
  if (!(det > 0)) return std::numeric_limits<double>::infinity();
  const double f2 = J.squaredNorm();
  return f2 * (1.0 + 1.0 / (det * det));
}

/// ∂D/∂J = 2J − 2 J⁻ᵀ J⁻¹ J⁻ᵀ (det J > 0).
inline Eigen::Matrix2d symmetric_dirichlet_gradient(const Eigen::Matrix2d& J) {
  const Eigen::Matrix2d Jit = J.inverse().transpose();
  return 2.0 * J - 2.0 * Jit * Jit.transpose() * Jit;
}

/// Hessian of D in vec(J) = (J₀₀, J₀₁, J₁₀, J₁₁) (det J > 0). With N = ‖J‖²_F, δ = det J and
/// g = ∂δ/∂vec(J) = (J₁₁, −J₁₀, −J₀₁, J₀₀), D = N (1 + δ⁻²) gives
///   H = 2 (1 + δ⁻²) I − 4 δ⁻³ (vec(J) gᵀ + g vec(J)ᵀ) + 6 N δ⁻⁴ g gᵀ − 2 N δ⁻³ ∂²δ,
/// ∂²δ having 1 at (0, 3), (3, 0) and −1 at (1, 2), (2, 1). `project`: its eigenvalues clamped
/// at 0 (the nearest positive semi-definite matrix), for a Newton step that descends.
Eigen::Matrix4d symmetric_dirichlet_hessian(const Eigen::Matrix2d& J, bool project);

/// Singular values σ₁ ≥ σ₂ > 0 (det J > 0) in closed form.
inline Eigen::Vector2d singular_values(const Eigen::Matrix2d& J) {
  const double e = 0.5 * (J(0, 0) + J(1, 1)), f = 0.5 * (J(0, 0) - J(1, 1));
  const double g = 0.5 * (J(1, 0) + J(0, 1)), h = 0.5 * (J(1, 0) - J(0, 1));
  const double q = std::hypot(e, h), r = std::hypot(f, g);
  return {q + r, std::abs(q - r)};
}

/// SLIM's weight matrix W and closest rotation R of J (det J > 0).
void slim_weights(const Eigen::Matrix2d& J, Eigen::Matrix2d& W, Eigen::Matrix2d& R);

}  // namespace curvefem::meshing::param

namespace curvefem::meshing::param {

// The same for 3 × 3 Jacobians (the tet scaffold of thesis §3.2.3): D(J) = ‖J‖²_F + ‖J⁻¹‖²_F
// = Σ σ_i² + σ_i⁻² ≥ 6 (= 6 iff J is a rotation), +∞ when det J ≤ 0; the SLIM weights have the
// same per-singular-value formula.
inline double symmetric_dirichlet_3d(const Eigen::Matrix3d& J) {
  const double det = J.determinant();
  if (!(det > 0)) return std::numeric_limits<double>::infinity();
  return J.squaredNorm() + J.inverse().squaredNorm();
}

/// ∂D/∂J = 2J − 2 J⁻ᵀ J⁻¹ J⁻ᵀ (det J > 0).
inline Eigen::Matrix3d symmetric_dirichlet_gradient_3d(const Eigen::Matrix3d& J) {
  const Eigen::Matrix3d Jit = J.inverse().transpose();
  return 2.0 * J - 2.0 * Jit * Jit.transpose() * Jit;
}

/// Signed SVD of J (det J > 0): σ₁ ≥ σ₂ ≥ σ₃ > 0, U and V rotations. SLIM's W and R = U Vᵀ.
void slim_weights_3d(const Eigen::Matrix3d& J, Eigen::Matrix3d& W, Eigen::Matrix3d& R,
                     Eigen::Vector3d* singular_values = nullptr);

}  // namespace curvefem::meshing::param
