#include "pipeline/mesh_validity.hpp"

#include <algorithm>
#include <cstdio>

#include "mapping/boundary_inverse.hpp"
#include "meshing/core/timer.hpp"

namespace curvefem::pipeline {

MapRoundtrip map_roundtrip(const BoundaryMap& map, const ShellFibers& fibers,
                           const SurfaceMesh& input) {
  Stopwatch watch;
  MapRoundtrip r;
  r.checked = true;
  const mapping::BoundaryInverse inverse(map, fibers, input);
  const double unit = bbox_longest_edge(input.V);
  for (int v = 0; v < map.num_input_vertices(); ++v) {
    if (map.vertex_face[v] < 0) continue;
    const auto back = inverse(map.image(v));
    if (!back) {
      if (r.failures++ == 0) r.first_failure = v;
      continue;
    }
    const double error = (back->position - input.V.row(v).transpose()).norm() / unit;
    if (r.worst_vertex < 0 || error > r.max_error_rel) r.max_error_rel = error, r.worst_vertex = v;
  }
  r.seconds = watch.seconds();
  return r;
}

bool curved_mesh_valid(const meshing::curved::CurvedValidation& v, double eps_rel,
                       const MapRoundtrip& roundtrip) {
  return v.valid(eps_rel) && roundtrip.checked && roundtrip.failures == 0 &&
         roundtrip.max_error_rel <= k_roundtrip_tolerance;
}

std::vector<std::string> curved_mesh_defects(const meshing::curved::CurvedValidation& v,
                                             double eps_rel, const MapRoundtrip& roundtrip) {
  std::vector<std::string> out;
  auto add = [&](const char* format, auto... values) {
    char text[256];
    std::snprintf(text, sizeof text, format, values...);
    out.emplace_back(text);
  };
  if (v.non_positive_tets > 0 || v.undecided_tets > 0)
    add("%d tets not certified positive and %d undecided (first: tet %d)", v.non_positive_tets,
        v.undecided_tets, v.first_bad_tet);
  if (v.boundary_faces_missing > 0 || v.boundary_faces_extra > 0)
    add("%d boundary faces of the map missing from the mesh and %d extra", v.boundary_faces_missing,
        v.boundary_faces_extra);
  if (v.boundary_node_mismatches > 0)
    add("%d boundary nodes differ between the mesh and the map", v.boundary_node_mismatches);
  if (v.boundary_self_intersections > 0)
    add("%d self-intersections of the curved boundary", v.boundary_self_intersections);
  if (v.exterior_faces_off_box > 0)
    add("%d outer boundary faces off the exterior box", v.exterior_faces_off_box);
  if (v.unmapped_vertices > 0) add("%d input vertices with no image", v.unmapped_vertices);
  if (v.max_scaled_distance_rel > eps_rel)
    add("input vertex %d is %.3g from the boundary (eps %.3g)", v.max_scaled_distance_vertex,
        v.max_scaled_distance_rel, eps_rel);
  if (v.bad_distance_points > 0)
    add("%d distance points name no input face", v.bad_distance_points);
  if (v.points_max_scaled_distance_rel > eps_rel)
    add("distance point %d is %.3g from the boundary (eps %.3g)", v.points_max_distance_point,
        v.points_max_scaled_distance_rel, eps_rel);
  if (v.features_off_edges > 0)
    add("%d feature edges off the boundary edges (first: map feature edge %d)",
        v.features_off_edges, v.first_feature_off);
  if (!roundtrip.checked) add("the map round trip was not checked (no shell fibers)");
  if (roundtrip.failures > 0)
    add("the map round trip could not pull back %d input vertices (first: %d)", roundtrip.failures,
        roundtrip.first_failure);
  if (roundtrip.max_error_rel > k_roundtrip_tolerance)
    add("the map round trip misses input vertex %d by %.3g of the bounding box (limit %.0e)",
        roundtrip.worst_vertex, roundtrip.max_error_rel, k_roundtrip_tolerance);
  return out;
}

}  // namespace curvefem::pipeline
