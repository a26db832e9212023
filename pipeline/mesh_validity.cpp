#include "pipeline/mesh_validity.hpp"

#include <algorithm>

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
      ++r.failures;
      continue;
    }
    r.max_error_rel =
        std::max(r.max_error_rel, (back->position - input.V.row(v).transpose()).norm() / unit);
  }
  r.seconds = watch.seconds();
  return r;
}

bool curved_mesh_valid(const meshing::curved::CurvedValidation& v, double eps_rel,
                       const MapRoundtrip& roundtrip) {
  return v.valid(eps_rel) && roundtrip.checked && roundtrip.failures == 0 &&
         roundtrip.max_error_rel <= k_roundtrip_tolerance;
}

}  // namespace curvefem::pipeline
