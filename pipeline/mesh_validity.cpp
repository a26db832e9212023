#include "pipeline/mesh_validity.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <optional>
#include <unordered_map>
#include <utility>
#include <vector>

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
  // Boundary triangles around each corner node: a φ(v) on an edge or a corner of its triangle
  // is also pulled back from just inside (1e-13) every other triangle holding that edge or
  // corner, since a point located from its position may land on either side (CGAL's part.off:
  // the located side came back to v at K = 3 and 3e-3 away at K = 4).
  const Eigen::MatrixXi& cells = map.boundary.cells;
  std::unordered_map<int, std::vector<int>> around;
  for (Eigen::Index f = 0; f < cells.rows(); ++f)
    for (int c = 0; c < 3; ++c) around[cells(f, c)].push_back(int(f));
  // Each vertex alone (the inverse's queries are thread-safe), then the counts in vertex order.
  const int nv = map.num_input_vertices();
  std::vector<double> error(std::size_t(nv), 0.0);
  std::vector<char> failed(std::size_t(nv), 0), checked(std::size_t(nv), 0);
  auto pull_back = [&](int v) {
    const int f = map.vertex_face[v];
    if (f < 0) return;
    checked[std::size_t(v)] = 1;
    std::vector<std::optional<mapping::InputPoint>> backs{inverse(map.image(v))};
    const double u = map.vertex_uv(v, 0), w = map.vertex_uv(v, 1);
    const std::array<double, 3> bary{1 - u - w, u, w};
    std::vector<std::pair<int, double>> weights;  // (corner node, weight), zero weights dropped
    for (int c = 0; c < 3; ++c)
      if (bary[std::size_t(c)] != 0) weights.emplace_back(cells(f, c), bary[std::size_t(c)]);
    const auto ring = weights.empty() ? around.end() : around.find(weights.front().first);
    if (weights.size() < 3 && ring != around.end())
      for (int g : ring->second) {
        std::array<double, 3> b{1e-13, 1e-13, 1e-13};
        int held = 0;
        for (const auto& [node, weight] : weights)
          for (int c = 0; c < 3; ++c)
            if (cells(g, c) == node) b[std::size_t(c)] += weight, ++held;
        if (g == f || held < int(weights.size())) continue;
        const double sum = b[0] + b[1] + b[2];
        backs.push_back(inverse.from_boundary(g, b[1] / sum, b[2] / sum));
      }
    for (const auto& back : backs) {
      if (!back) {
        failed[std::size_t(v)] = 1;
        continue;
      }
      error[std::size_t(v)] = std::max(error[std::size_t(v)],
                                       (back->position - input.V.row(v).transpose()).norm() / unit);
    }
  };
  tbb::parallel_for(tbb::blocked_range<int>(0, nv, 256), [&](const tbb::blocked_range<int>& range) {
    for (int v = range.begin(); v < range.end(); ++v) pull_back(v);
  });
  for (int v = 0; v < nv; ++v) {
    if (!checked[std::size_t(v)]) continue;
    if (failed[std::size_t(v)] && r.failures++ == 0) r.first_failure = v;
    if (r.worst_vertex < 0 || error[std::size_t(v)] > r.max_error_rel)
      r.max_error_rel = error[std::size_t(v)], r.worst_vertex = v;
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
