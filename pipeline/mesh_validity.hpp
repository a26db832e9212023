// The one definition of a valid curved mesh, shared by `curvefem mesh`, `curvefem validate` and
// `curvefem run` (issue 23): every check of the independent validation (certified Jacobians,
// boundary faces, embedding, ε at every input vertex and distance point, feature edges; see
// meshing/curved/curved_validate.hpp) at the mesh's ε, and the map round trip φ⁻¹(φ(v)) = v within
// k_roundtrip_tolerance of the bounding box for every referenced input vertex, φ⁻¹ evaluated from
// the saved shell fibers (what a later run reusing the mesh uses).
#pragma once

#include <string>
#include <vector>

#include "meshing/core/boundary_map.hpp"
#include "meshing/core/shell_fibers.hpp"
#include "meshing/core/surface_mesh.hpp"
#include "meshing/curved/curved_validate.hpp"

namespace curvefem::pipeline {

inline constexpr double k_roundtrip_tolerance = 1e-6;

struct MapRoundtrip {
  bool checked = false;        ///< false: no fibers to evaluate φ⁻¹ with
  double max_error_rel = 0.0;  ///< max |φ⁻¹(φ(v)) − v| / bbox edge
  int failures = 0;            ///< vertices whose φ(v) could not be pulled back
  int worst_vertex = -1;       ///< the input vertex of max_error_rel (-1: none checked)
  int first_failure = -1;      ///< the first input vertex that could not be pulled back
  double seconds = 0.0;
};

/// φ⁻¹(φ(v)) for every input vertex: φ(v) is located on the curved boundary from its position
/// alone (mapping::TriangleLocator) and pulled back along the shell fibers; where the map puts
/// φ(v) on an edge or a corner of its triangle, also from just inside every other triangle there.
MapRoundtrip map_roundtrip(const BoundaryMap& map, const ShellFibers& fibers,
                           const SurfaceMesh& input);

/// The validity of report.json "valid" / "mesh_valid" (an unchecked round trip fails).
bool curved_mesh_valid(const meshing::curved::CurvedValidation& v, double eps_rel,
                       const MapRoundtrip& roundtrip);

/// Each failed check of curved_mesh_valid as one phrase naming where (tet, input vertex, map
/// feature edge), e.g. "the map round trip misses input vertex 31 by 7.4e-3 of the bounding box
/// (limit 1e-6)"; empty when valid.
std::vector<std::string> curved_mesh_defects(const meshing::curved::CurvedValidation& v,
                                             double eps_rel, const MapRoundtrip& roundtrip);

}  // namespace curvefem::pipeline
