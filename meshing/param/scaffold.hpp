// The scaffold (thesis §3.2.1, Fig. 3.2): a triangulation of a box around all charts that
// conforms to their boundaries, so that "every triangle, chart or scaffold, positively oriented"
// implies a bijective map. Rebuilt from scratch every iteration (§3.2.2 "Mesh improvement").
//
// Construction: CGAL's constrained Delaunay triangulation (exact predicates, EPICK) of the box
// boundary points and the charts' boundary vertices, with every chart boundary edge and box edge
// a constraint; the triangles between the box and the charts (nesting level 1 from the outside)
// are kept. Optional refinement rounds insert the centroid of every kept triangle larger than the
// area bound (a centroid lies strictly inside a scaffold triangle, so boundaries never change).
// Conventions: scaffold vertex ids continue after the chart UV vertices: id ≥ #U refers to row
// id − #U of `V`; the first `num_fixed` rows of V are the box boundary (held fixed by the
// solver), the rest are free Steiner points. Faces are counter-clockwise.
#pragma once

#include <Eigen/Core>
#include <vector>

namespace curvefem::meshing::param {

struct ScaffoldOptions {
  double box_scale = 3.0;  ///< box = the UV bounding square scaled by this about its centre
  int box_segments = 0;    ///< points per box side; 0: max(4, √(#boundary vertices) / 2)
  int refine_rounds = 2;   ///< centroid insertion rounds (0: boundary points only)
  double refine_area = 0;  ///< insert in scaffold triangles larger than this (0: auto, see .cpp)
};

struct Scaffold {
  Eigen::MatrixXd V;  ///< #S × 2: box boundary points (first num_fixed rows), then Steiner points
  Eigen::MatrixXi F;  ///< #SF × 3: counter-clockwise faces, ids into [chart UV ; V]
  int num_fixed = 0;
  Eigen::Vector2d box_lo, box_hi;
};

/// Scaffold around the charts whose UV positions are `uv` (#U × 2) and whose boundaries are the
/// closed `loops` (UV vertex ids). Throws MeshingError when the boundaries are not a set of
/// disjoint simple polygons (two boundary vertices at the same point, crossing or touching
/// boundary edges): the input map was not bijective.
Scaffold build_scaffold(const Eigen::MatrixXd& uv, const std::vector<std::vector<int>>& loops,
                        const ScaffoldOptions& options = {});

}  // namespace curvefem::meshing::param
