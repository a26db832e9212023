// Null spaces of pure Neumann problems: the constants of Poisson without Dirichlet data, the six
// rigid motions of linear elasticity with tractions only (issue 24).
//
// Modes r_k about a center c (the mean of the DOF points). One component: r_0 = 1. Three:
// r_0..2 = e_x, e_y, e_z and r_3..5 = e_x × (x − c), e_y × (x − c), e_z × (x − c). They are
// linear, so the Lagrange space of a mesh whose order k ≤ p holds them exactly (nodal values R,
// DOF-major like the solution) and K R = 0. K u = F is then solvable iff Rᵀ F = 0 — ∫f + ∫g = 0
// (Poisson), zero total force and zero total moment about c (elasticity) — and fixes u up to R θ.
// The solution reported is the one with ∫ r_k · u = 0 for every k (mean zero; no mean translation
// or rotation): u ← u − R G⁻¹ Bᵀ u, with B (column k = ∫ r_k · φ_i e_j, the load vector of r_k)
// and the Gram matrix G = Bᵀ R = ∫ r_k · r_l. Data that are not compatible (by quadrature, or a
// modelling error) are made so by removing the modes' part of the load, F ← F − B G⁻¹ Rᵀ F: for
// Poisson that replaces f by f − (∫f + ∫g)/|Ω|.
#pragma once

#include <Eigen/Core>

#include "fem/problems/error_norms.hpp"
#include "fem/solvers/linear_solver.hpp"
#include "fem/space/function_space.hpp"
#include "meshing/core/lagrange_mesh.hpp"

namespace curvefem::fem {

/// Relative imbalance of the load above which it counts as incompatible. Quadrature alone leaves
/// ~5e-7 on a 3 × 3 × 3 cube at P1 with exponential data (tests/fem/test_null_space.cpp), a
/// forgotten flux or an unbalanced load O(1).
constexpr double k_compatibility_tolerance = 1e-4;

struct NullSpaceModes {
  int components = 1;  ///< 1 (constants) or 3 (rigid motions)
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  Eigen::MatrixXd nodal;    ///< (c·#dofs) × m: the modes at the DOF points (R)
  Eigen::MatrixXd moments;  ///< (c·#dofs) × m: column k = ∫ r_k · φ_i e_j (B)
  Eigen::MatrixXd gram;     ///< m × m: ∫ r_k · r_l (G)
  int size() const { return static_cast<int>(nodal.cols()); }
  /// Σ θ_k r_k at x: `value` gets c entries, `gradient` (if set) c × 3 row-major (∂_j of entry i).
  void evaluate(const Eigen::VectorXd& theta, const Eigen::Vector3d& x, double* value,
                double* gradient = nullptr) const;
};

/// components = 1: m = 1 constant; components = 3: m = 6 rigid motions. The moments are
/// integrated on the curved cells with default_quadrature_degree(p, k, mass).
NullSpaceModes null_space_modes(const LagrangeMesh& mesh, const FunctionSpace& space,
                                int components);

/// Rᵀ F and its scale. One component: resultant = (Σ F) = ∫f + ∫g; three: total force, then
/// total moment about the center.
struct LoadCompatibility {
  Eigen::VectorXd resultant;
  Eigen::Vector3d center = Eigen::Vector3d::Zero();  ///< the moments' reference point
  double force_scale = 0.0;   ///< Σ over DOFs of |F_i| (the per-DOF load vector's norm)
  double moment_scale = 0.0;  ///< Σ over DOFs of |x_i − c| |F_i| (three components)
  double relative = 0.0;      ///< max(|force| / force_scale, |moment| / moment_scale)
  bool compatible() const { return relative <= k_compatibility_tolerance; }
};

LoadCompatibility load_compatibility(const NullSpaceModes& modes, const FunctionSpace& space,
                                     const Eigen::VectorXd& F);

/// F ← F − B G⁻¹ Rᵀ F (afterwards Rᵀ F = 0 up to round-off).
void make_compatible(const NullSpaceModes& modes, Eigen::VectorXd& F);

/// u ← u − R G⁻¹ Bᵀ u (afterwards ∫ r_k · u_h = 0 for every k).
void remove_null_component(const NullSpaceModes& modes, Eigen::VectorXd& u);

/// Solves K u = F for a K whose kernel is spanned by the modes (no Dirichlet data): F is made
/// compatible, K u = F solved with options.null_space = R (linear_solver.hpp) and u's null-space
/// part removed. Returns the compatibility of F as given (the caller warns about it: it knows
/// what the load is made of). Warns through the log when K R is not zero to round-off (a mesh of
/// order k > p: the modes are not in the space, and the solve is ill-conditioned, not singular).
Eigen::VectorXd solve_modulo_null_space(const SparseMatrix& K, Eigen::VectorXd F,
                                        const NullSpaceModes& modes, const FunctionSpace& space,
                                        const LinearSolverOptions& options, LinearSolveInfo* info,
                                        LoadCompatibility* compatibility);

/// Errors of u_h against u up to the null space: the norms of u_h − u − r with the mode
/// r = Σ θ_k r_k for which ∫ r_k · (u_h − u − r) = 0 (one component: r = the mean of u_h − u).
/// θ is returned in `offset` if set (modes.evaluate(θ, x) is r). Same quadrature as
/// compute_errors. `modes`: null_space_modes(mesh, space, components).
ErrorNorms compute_errors_modulo_null_space(const LagrangeMesh& mesh, const FunctionSpace& space,
                                            const NullSpaceModes& modes, const Eigen::VectorXd& u,
                                            const ExactValue& exact,
                                            const ExactGradient& exact_gradient,
                                            Eigen::VectorXd* offset = nullptr,
                                            int quadrature_degree = -1);

}  // namespace curvefem::fem
