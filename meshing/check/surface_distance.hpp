// Distances between triangle surfaces, for verifying what other modules claim about them (a
// reconstruction on its input, nested cages apart): CGAL AABB trees of the triangles, closest
// points computed in double (EPICK constructions), independent of meshing/shell's own queries.
#pragma once

#include <Eigen/Core>

namespace curvefem::check {

/// For each row of P (#P × 3), the distance to the closest point of the triangles (V, F):
/// #P values. F must have at least one non-degenerate face.
Eigen::VectorXd distances_to_surface(const Eigen::MatrixXd& P, const Eigen::MatrixXd& V,
                                     const Eigen::MatrixXi& F);

/// The points a one-sided sampled Hausdorff distance uses on (V, F): every vertex, and on every
/// face the points of barycentric coordinates (i, j, k) / n with i + j + k = n, n = `density`
/// (≥ 1; corners included, so shared points repeat). #points × 3.
Eigen::MatrixXd surface_samples(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F, int density);

struct HausdorffEstimate {
  double a_to_b = 0;  ///< max over a's samples of the distance to b
  double b_to_a = 0;  ///< max over b's samples of the distance to a
  double mean_a_to_b = 0, mean_b_to_a = 0;
  double symmetric() const { return a_to_b > b_to_a ? a_to_b : b_to_a; }
};

/// A sampled (lower-bound) Hausdorff distance between (Va, Fa) and (Vb, Fb): both directions over
/// surface_samples(…, density). Exact up to the sampling: the true distance is at least this,
/// and at most this plus the largest sample spacing.
HausdorffEstimate sampled_hausdorff(const Eigen::MatrixXd& Va, const Eigen::MatrixXi& Fa,
                                    const Eigen::MatrixXd& Vb, const Eigen::MatrixXi& Fb,
                                    int density = 3);

/// The generalized winding number of the closed surface (V, F) at x: the faces' solid angles
/// (Van Oosterom–Strackee) over 4π; 1 inside, 0 outside, for x away from the surface.
double winding_number(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F, const Eigen::Vector3d& x);

}  // namespace curvefem::check
