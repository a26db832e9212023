// Independent verification of a UV map (not the optimizer's code paths): is it bijective?
//
// Works from the UV faces alone (#F × 3 ids into #U × 2 positions), recomputing boundaries and
// components itself. All decisions use CGAL's exact predicates (EPICK) on the double
// coordinates:
//   flips           faces whose orientation is not counter-clockwise (clockwise or collinear);
//   overlaps        pairs of boundary edges that intersect other than at a shared endpoint, plus
//                   pairs sharing an endpoint that overlap along a segment (uniform grid broad
//                   phase, then CGAL::do_intersect / collinearity tests);
//   nested_charts   components one of whose boundary vertices lies in a face of another component
//                   (a chart inside another without any boundary crossing);
//   areas           the sum of the triangles' signed areas against the sum of the shoelace areas
//                   of the boundary loops (equal for a consistent, closed set of loops).
// With no flip, no overlap and no nesting the map of every disk chart is bijective and the charts
// are pairwise disjoint (Lipman 2013; thesis §3.2.1).
#pragma once

#include <Eigen/Core>

namespace curvefem::meshing::param {

struct UvCheck {
  long long flips = 0;
  long long overlaps = 0;
  long long nested_charts = 0;
  int components = 0;
  long long boundary_edges = 0;
  double triangle_area = 0;  ///< Σ signed triangle areas
  double boundary_area = 0;  ///< Σ shoelace areas of the boundary loops
  double area_rel_error = 0;
  bool bijective() const { return flips == 0 && overlaps == 0 && nested_charts == 0; }
};

UvCheck check_uv_map(const Eigen::MatrixXd& uv, const Eigen::MatrixXi& F);

}  // namespace curvefem::meshing::param
