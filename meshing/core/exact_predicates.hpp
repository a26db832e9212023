#pragma once
// Exact orientation predicates on double coordinates, without CGAL (meshing/core is Eigen only):
// a floating-point filter with a proven error bound, and exact expansion arithmetic (error-free
// sums and products) where the filter cannot decide. The signs are those of CGAL's
// Exact_predicates_inexact_constructions_kernel (tests/meshing/core compares them), so code in
// meshing/core can take the same decisions as meshing/shell's CGAL-based searches.
//
// Exact for finite coordinates whose products neither overflow nor underflow (magnitudes between
// ~1e-90 and ~1e90, far beyond any mesh coordinate).
#include <Eigen/Core>

namespace curvefem::exact {

/// Sign (−1, 0, 1) of det[b − a, c − a, d − a]: 1 when d lies on the positive side of the plane
/// through a, b, c oriented by (b − a) × (c − a) (CGAL::orientation(a, b, c, d)).
int orient3d(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
             const Eigen::Vector3d& d);

/// Sign of det[b − a, c − a] in the plane (CGAL::orientation of 2-D points).
int orient2d(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c);

/// Are a, b, c exactly collinear (or coincident)?
bool collinear(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c);

/// Does the closed segment [p, q] meet the closed triangle (a, b, c)? False for a degenerate
/// (collinear) triangle or p == q. The decision of CGAL::do_intersect(Segment_3, Triangle_3).
bool segment_meets_triangle(const Eigen::Vector3d& p, const Eigen::Vector3d& q,
                            const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                            const Eigen::Vector3d& c);

/// Is x a point of the closed triangle (a, b, c)? False for a degenerate triangle.
bool triangle_contains(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                       const Eigen::Vector3d& x);

}  // namespace curvefem::exact
