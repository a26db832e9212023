#pragma once
// Certified positivity of the Jacobian determinant of curved Lagrange tetrahedra, k = 1..4
// (DESIGN.md §2 "Certified positivity"; reference-notes shell-and-curved §4.5).
//
// A tet of order k is given by its n = (k+1)(k+2)(k+3)/6 nodes, an n × 3 matrix in the canonical
// order of meshing/core/lagrange_nodes.hpp; it maps the reference tet (v0 = 0, v1 = e_x,
// v2 = e_y, v3 = e_z) by x(ξ) = Σ N_i(ξ) x_i. J(ξ) = ∂x/∂ξ (column c = ∂x/∂ξ_c) and det J is a
// polynomial of degree d = 3(k−1), measured against the *right reference tet* (a straight tet
// has det J = 6·volume everywhere).
//
// Certificate (Johnen-style, but rigorous in floating point):
//   1. det J at the m points of the uniform degree-d lattice; any value certainly ≤ 0 →
//      non_positive (a proof: det J ≤ 0 at that point);
//   2. Bernstein coefficients b = M·v (M the exact Lagrange-to-Bernstein matrix of
//      tools/gen_bernstein_tables.py, committed in generated/bernstein_tables.inc);
//      all certainly > 0 → positive (a proof: det J ≥ min b > 0 on the whole tet);
//   3. affine path (CertificateOptions::affine_path), for nearly straight tets: J(ξ) = J_a + E(ξ)
//      with J_a = [x1 − x0, x2 − x0, x3 − x0] (the corner rows) and E(ξ) = Σ_i d_i ∇N_i(ξ)ᵀ,
//      d_i = x_i − aff(ξ_i) the deviation of node i from the affine map of the corners (the basis
//      reproduces affine maps). With ‖d_i‖ ≤ dmax and the generated constants
//      Λ_c ≥ max_ξ Σ_i |∂N_i/∂ξ_c| (k = 1..4: 0, 8, 31.5, 98), every column of E is bounded by
//      ε_c = Λ_c dmax on the whole tet, and (multilinearity + Hadamard, A_c = ‖column c of J_a‖)
//        |det J(ξ) − det J_a| ≤ Π_c (A_c + ε_c) − Π_c A_c =: δ.
//      det J_a − δ > 0 (everything with proven rounding bounds) → positive; det J_a + δ ≤ 0 →
//      non_positive (det J ≤ 0 everywhere). No subdivision, O(n) flops;
//   4. otherwise red refinement (4 corner tets + 4 around the diagonal between the midpoints of
//      edges 02 and 13), child coefficients by exact dyadic subdivision matrices; a child corner
//      coefficient is a point value (certainly ≤ 0 → non_positive); recurse up to
//      CertificateOptions::max_depth; anything left → undecided. Callers treat undecided as
//      invalid.
// Every step carries a proven error bound from the exact double node coordinates onwards (a priori
// bounds of round-to-nearest dot products, outward-rounded comparisons), so "positive" and
// "non_positive" are proofs, not tolerances. The computation runs in round-to-nearest; a caller
// inside another rounding mode (e.g. CGAL's protected scopes) is switched to nearest for the call
// and restored. Coordinates must satisfy |x| < 1e90 (NaN, inf or larger → undecided), and det J
// must exceed ~1e-280 (absolute underflow guards), i.e. tets not smaller than ~1e-90.
// Slack: steps 2 and 4 bound rounding errors like |J|³ (table-wide row sums, not per-entry ones),
// so for straight tets their proven lower bound is within ~1e-9 (well-shaped) to ~1e-5 (flat P4)
// of det J, relative to |J|³; alone they leave straight tets undecided below a min scaled Jacobian
// of ~1e-7 (P4; P3 ~1e-9, P2 ~1e-11; measured on random slivers, needles and caps). Step 3 has
// slack δ ≈ (A0A1 + A0A2 + A1A2)·Λ·dmax plus 16u·perm|J_a|; for nodes that are floating-point
// affine interpolations of the corners (dmax ~ 20u·|x − x0| from the rounding bounds), it certifies
// straight tets down to height/edge ~3e-12 (P4; P2 ~3e-13, P1 ~1e-16; every random P4 sliver,
// needle or cap with min scaled Jacobian ≥ 1e-11) when the coordinates are of the size of the tet,
// ~2e-10 (P4) when they are 1000× larger. It cannot help curved tets: dmax is then of the size of
// the curving, and it gives up on a flat tet whose nodes deviate by more than ~h/(3Λ) (e.g. P4,
// height h: one edge node pushed by 0.005h is still certified, det J turns negative at ~0.06h).
//
// Thread safety: all functions are reentrant (the tables are built once, thread-safely, on first
// use and are immutable afterwards); call them from a oneTBB loop freely.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <Eigen/LU>
#include <limits>
#include <vector>

namespace curvefem::meshing::curved {

enum class JacobianVerdict { positive, non_positive, undecided };

/// "positive", "non_positive", "undecided".
const char* to_string(JacobianVerdict verdict);

/// The step of the certificate that decided the verdict (see above): lattice point values (1),
/// the element's Bernstein coefficients (2), the affine path (3), red subdivision (4); none when
/// undecided.
enum class CertificatePath { none, lattice, bernstein, affine, subdivision };

/// "none", "lattice", "bernstein", "affine", "subdivision".
const char* to_string(CertificatePath path);

struct CertificateOptions {
  /// Red-refinement levels below the element (0 = no subdivision). Each level shrinks a sub-tet
  /// by 2, so the gap between Bernstein coefficients and det J values shrinks about 4×; level 4
  /// resolves a gap 256× smaller than the element's own control net, at a worst-case cost of
  /// 4680 sub-tets (a few ms at P4); tets that need more are almost degenerate and are better
  /// reported as invalid. The thesis stops after 3 levels.
  int max_depth = 4;
  /// Hard budget on the number of sub-tets examined (children created); reaching it → undecided.
  int max_subtets = 4680;
  /// Step 3, the affine path (nearly straight tets). Off: the Bernstein/subdivision proof alone
  /// (for tests and comparisons).
  bool affine_path = true;
};

struct JacobianCertificate {
  JacobianVerdict verdict = JacobianVerdict::undecided;
  /// Floating-point estimate of min det J over the degree-d lattice (k = 1: the constant det J).
  double min_lattice_estimate = std::numeric_limits<double>::quiet_NaN();
  /// Proven enclosure [lower, upper] of min over the degree-d lattice of det J.
  double min_lattice_lower = -std::numeric_limits<double>::infinity();
  double min_lattice_upper = std::numeric_limits<double>::infinity();
  /// Proven: det J ≥ lower_bound on the whole tet. > 0 when positive (the larger of the element's
  /// Bernstein bound and the affine bound when both are computed); −∞ otherwise.
  double lower_bound = -std::numeric_limits<double>::infinity();
  /// Proven: min det J over the tet ≤ min_upper_bound (from all point values evaluated: the
  /// lattice and the sub-tet corners; and from the affine path's det J_a + δ). ≤ 0 when
  /// non_positive.
  double min_upper_bound = std::numeric_limits<double>::infinity();
  CertificatePath decided_by = CertificatePath::none;
  int depth_reached = 0;    ///< deepest refinement level examined (0 = the element only)
  int subtets_visited = 0;  ///< sub-tets (children) examined; 0 when decided at the element
};

/// Certifies det J > 0 on the whole tet. order = k ∈ 1..4; nodes: n × 3, canonical order.
/// Throws InputError for an order outside 1..4 or a wrong node count / column count.
JacobianCertificate certify_tet_jacobian(int order, const Eigen::Ref<const Eigen::MatrixXd>& nodes,
                                         const CertificateOptions& opts = {});

/// d = 3(k − 1), the polynomial degree of det J (0 for k = 1).
int jacobian_degree(int order);

/// m × 4 barycentric multi-indices β (|β| = d) of the degree-d lattice, point ξ = (β1, β2, β3)/d,
/// in the canonical order of lagrange_nodes.hpp at degree d (k = 1: one row of zeros). The same
/// rows label the Bernstein coefficients: B_β(λ) = d!/(β0!β1!β2!β3!) λ^β.
Eigen::MatrixXi jacobian_lattice(int order);

/// Floating-point Bernstein coefficients of det J (m entries, rows of jacobian_lattice): an
/// estimate for inspection and tests; the certificate uses the enclosures internally.
Eigen::VectorXd jacobian_bernstein_coefficients(int order,
                                                const Eigen::Ref<const Eigen::MatrixXd>& nodes);

/// Sampled quality ESTIMATE, not a certificate: the minimum over the degree-d lattice points
/// (k = 1: the one constant J) and over the four corner frames of the reference tet of
///   √2 · det(J T_v) / (‖J t_v1‖ ‖J t_v2‖ ‖J t_v3‖),
/// T_v = (t_v1, t_v2, t_v3) the reference edge vectors leaving vertex v, ordered so det T_v = 1.
/// For a straight tet this is Knupp's minimum corner scaled Jacobian: 1 for the regular tet,
/// ≤ 0 iff inverted or flat. A zero tangent counts as 0.
/// `argmin`, if given, receives the index of a lattice point where the minimum is reached.
double min_scaled_jacobian(int order, const Eigen::Ref<const Eigen::MatrixXd>& nodes,
                           int* argmin = nullptr);
/// The value min_scaled_jacobian takes at one point of its lattice (index as from `argmin`),
/// computed alone: equal to it up to rounding (the same terms, summed in the same order, but
/// not necessarily with the same instructions). For a quick rejection: a value clearly at or
/// below a bar there means the minimum is too.
double scaled_jacobian_at(int order, const Eigen::Ref<const Eigen::MatrixXd>& nodes, int point);

/// J(r, c) = Σ_i X(i, r) G(i, c): the Jacobian at a point of the map with nodes X (n × 3) and
/// shape gradients G (n × 3) there. For n ≥ 14 (orders 3, 4) a plain loop over i in order: the
/// order in which Eigen's general product kernel, which Xᵀ G used there, sums (the same bits with
/// Debian's Eigen 3.4 on 400,000 random tets), without its packing, 2-3× faster. Below, Eigen's
/// coefficient-based product as before (it sums in another order).
inline Eigen::Matrix3d jacobian_at(const Eigen::Ref<const Eigen::MatrixXd>& X,
                                   const Eigen::MatrixXd& G) {
  if (X.rows() < 14) return X.transpose() * G;
  Eigen::Matrix3d J = Eigen::Matrix3d::Zero();
  for (Eigen::Index i = 0; i < X.rows(); ++i)
    for (int c = 0; c < 3; ++c)
      for (int r = 0; r < 3; ++r) J(r, c) += X(i, r) * G(i, c);
  return J;
}

/// Curved MIPS in the thesis convention (reference-notes §3.9): the mean over the 56 points of the
/// uniform level-5 lattice of ‖J‖²_F ‖J⁻¹‖²_F, J taken with respect to the RIGHT reference tet, so
/// the reference tet itself scores 9 (a regular tet scores more; the thesis threshold 100 refers
/// to this convention). +∞ when det J ≤ 0 at a sample. An estimate, not a certificate.
double curved_mips(int order, const Eigen::Ref<const Eigen::MatrixXd>& nodes);

/// The order-k shape gradients (n × 3) at curved_mips' 56 sample points, in its order: for callers
/// that update the Jacobians there in place (a move of some nodes changes each by a rank-one term).
const std::vector<Eigen::MatrixXd>& curved_mips_gradients(int order);
/// curved_mips' term at one sample, ‖J‖²_F ‖J⁻¹‖²_F (+∞ when det J ≤ 0): their mean is curved_mips.
inline double curved_mips_term(const Eigen::Matrix3d& J) {
  const double det = J.determinant();
  if (!(det > 0.0)) return std::numeric_limits<double>::infinity();
  Eigen::Matrix3d cof;
  cof.col(0) = J.col(1).cross(J.col(2));
  cof.col(1) = J.col(2).cross(J.col(0));
  cof.col(2) = J.col(0).cross(J.col(1));
  return J.squaredNorm() * cof.squaredNorm() / (det * det);
}

}  // namespace curvefem::meshing::curved
