#pragma once
// Independent validation of a curved mesh and its boundary map (DESIGN.md §2–3; the `validate`
// subcommand and every `mesh` report). Code paths separate from the mesher check:
//   positivity   every tet's det J certified positive (certify_tet_jacobian: lattice values,
//                Bernstein coefficients, subdivision, interval arithmetic);
//   boundary     the faces used by exactly one tet are exactly the map's boundary triangles, and
//                the map's node copy equals the volume nodes it points to;
//   patches      diagnostic: the area element of each curved boundary triangle, smallest over
//                largest (folded where its normal turns against its corners' plane);
//   embedding    the boundary, subdivided into flat triangles at `subdivision` per edge, has no
//                self-intersecting pair (exact predicates);
//   distance     max over input vertices of |x - φ(x)|, relative to the bbox edge;
//   features     both ends of every feature edge of the map (BoundaryMap::feature_edges) map
//                onto one edge of the boundary (a corner of it, or its interior: a barycentric
//                coordinate within 1e-9 of 0), so each input chain lies along boundary edges;
//   orientation  diagnostic: input triangles whose three vertices map into the same boundary
//                triangle and whose straight (u, v) triangle is not positively oriented. The
//                shell projection is only piecewise linear (3 tets per half-prism), so a sliver
//                whose corners fall in different split tets can show up without any fold of φ;
//                the count is reported, not part of `valid` (φ's bijectivity rests on the shell's
//                verified section property, the embedded boundary and the roundtrip).

#include <cmath>
#include <map>
#include <vector>

#include "meshing/core/boundary_map.hpp"
#include "meshing/core/lagrange_mesh.hpp"
#include "meshing/core/surface_mesh.hpp"
#include "meshing/curved/boundary_limits.hpp"

namespace curvefem::meshing::curved {

struct CurvedValidation {
  int tets = 0, non_positive_tets = 0, undecided_tets = 0;
  int first_bad_tet = -1;
  double min_scaled_jacobian = 0, mean_mips = 0, max_mips = 0;
  int tets_sj_below_1e2 = 0, tets_sj_below_1e3 = 0;  // sampled scaled Jacobian < 0.01, < 0.001
  // Distortion of the element maps (element_distortion.hpp): worst and mean over the tets.
  double min_jacobian_ratio = 1, max_d2 = 0, mean_d2 = 0, max_d3 = 0, mean_d3 = 0;
  struct Quality {
    int tets = 0;
    double min_scaled_jacobian = HUGE_VAL, mean_mips = 0, max_mips = 0;
    int tets_sj_below_1e2 = 0, tets_sj_below_1e3 = 0;
    double min_jacobian_ratio = HUGE_VAL, max_d2 = 0, mean_d2 = 0, max_d3 = 0, mean_d3 = 0;
  };
  std::map<int, Quality> quality_by_tag;  // by LagrangeMesh::cell_tags (1 slab, 2 interior)
  // Per tet: certificate (1 positive, 0 undecided, -1 not positive), sampled min scaled Jacobian
  // and curved MIPS (estimates, see jacobian_certificate.hpp).
  std::vector<int> cell_certificate;
  std::vector<double> cell_scaled_jacobian, cell_mips;
  std::vector<double> cell_jacobian_ratio, cell_d2, cell_d3;  // element_distortion.hpp
  int boundary_faces = 0, boundary_faces_missing = 0, boundary_faces_extra = 0;
  int boundary_node_mismatches = 0;
  // --exterior meshes: the boundary of the whole mesh must lie on its bounding box.
  bool exterior = false;
  int exterior_boundary_faces = 0, exterior_faces_off_box = 0;
  int subdivision = 0, boundary_self_intersections = 0;
  // Diagnostic, not part of `valid`: per boundary triangle, its smallest area element over its
  // largest (0 where its normal turns against its corners' plane: a folded patch, which makes
  // flat boundary tets); the worst, the folded ones and those below 0.1.
  double min_boundary_area_ratio = 1;
  int boundary_faces_folded = 0, boundary_faces_distorted = 0;
  // Diagnostic, not part of `valid`: what the boundary's straight corner triangles allow any
  // straight tet on them (boundary_limits.hpp): a floor for the max MIPS, a ceiling for the min
  // scaled Jacobian. With an exterior, the curved surface (the inside region's boundary).
  BoundaryLimits boundary_limits;
  int unmapped_vertices = 0;
  double max_distance_rel = 0;
  int max_distance_vertex = -1;
  // Against the map's spatially varying ε (BoundaryMap::eps_scale): the largest distance divided
  // by the point's factor, so valid(ε) holds when every point is within ε · its factor. Equal
  // to max_distance_rel / points_max_distance_rel without a field.
  bool eps_field = false;
  double max_scaled_distance_rel = 0, points_max_scaled_distance_rel = 0;
  int max_scaled_distance_vertex = -1;
  // Distance points of the map (constraint points, samples): how many, the largest distance from
  // the input point to its image (relative), where, and ids that do not name an input face.
  int distance_points = 0, bad_distance_points = 0;
  double points_max_distance_rel = 0;
  int points_max_distance_point = -1;
  int input_faces_checked = 0, flipped_input_faces = 0;
  int feature_edges = 0, features_off_edges = 0, first_feature_off = -1;  // index in the map's list
  double seconds = 0;
  bool certified() const { return non_positive_tets == 0 && undecided_tets == 0; }
  bool boundary_ok() const {
    return boundary_faces_missing == 0 && boundary_faces_extra == 0 &&
           boundary_node_mismatches == 0 && boundary_self_intersections == 0 &&
           exterior_faces_off_box == 0;
  }
  bool valid(double eps_rel) const {
    return certified() && boundary_ok() && unmapped_vertices == 0 &&
           max_scaled_distance_rel <= eps_rel && bad_distance_points == 0 &&
           points_max_scaled_distance_rel <= eps_rel && features_off_edges == 0;
  }
};

// subdivision 0: 2·order.
CurvedValidation validate_curved_mesh(const LagrangeMesh& mesh, const BoundaryMap& map,
                                      const SurfaceMesh& input, int subdivision = 0);

}  // namespace curvefem::meshing::curved
