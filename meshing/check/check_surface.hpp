// Validity of a triangle surface for meshing (DESIGN.md §1, first stage).
//
// A surface is acceptable when it is non-empty, closed (no boundary edge), edge- and
// vertex-manifold, consistently oriented with positive signed volume (outward), has no degenerate
// face (repeated vertex index or exactly collinear corners, exact predicates) and no pair of faces
// that intersect other than in their shared vertices/edge (CGAL PMP, exact predicates).
// Small angles, unreferenced and coincident vertices are reported but do not by themselves make a
// surface unacceptable (real CAD tessellations have slivers down to 1e-3 degrees).
#pragma once

#include <string>
#include <vector>

#include "meshing/core/progress.hpp"
#include "meshing/core/surface_mesh.hpp"

namespace curvefem::check {

struct CheckOptions {
  bool self_intersections = true;  ///< the most expensive test; off = not checked (reported)
  int max_listed_ids = 10;         ///< ids named per defect
};

/// One defect class; `ids` lists up to max_listed_ids offending ids (vertices, faces, or face
/// pairs flattened as a0,b0,a1,b1,...) of kind `id_kind`.
struct Defect {
  std::string kind;     ///< open | non_manifold_edge | non_manifold_vertex | orientation |
                        ///< inward | degenerate | self_intersection | empty
  long long count = 0;  ///< how many edges / vertices / faces / pairs
  std::string id_kind;  ///< "edge" (vertex pairs), "vertex", "face", "face_pair"
  std::vector<long long> ids;
  std::string message;  ///< one line, e.g. "4 boundary edges (surface is open): 3-7, ..."
};

struct CheckReport {
  long long vertices = 0, faces = 0;
  long long referenced_vertices = 0, unreferenced_vertices = 0;
  long long components = 0;              ///< connected components of faces (by shared vertex)
  long long boundary_edges = 0;          ///< edges with one incident face
  long long non_manifold_edges = 0;      ///< edges with more than two incident faces
  long long non_manifold_vertices = 0;   ///< vertices whose face fan is not one disk/half-disk
  long long inconsistent_edges = 0;      ///< manifold edges traversed twice in the same direction
  bool closed = false, edge_manifold = false, vertex_manifold = false;
  bool consistently_oriented = false;
  double signed_volume = 0.0;
  int orientation_sign = 0;              ///< +1 outward, -1 inward, 0 undefined (open/inconsistent)
  long long genus = -1;                  ///< per closed manifold oriented surface: sum over comps
  long long euler_characteristic = 0;
  long long degenerate_faces = 0;        ///< repeated index or exactly collinear
  double min_angle_deg = 0.0, max_angle_deg = 0.0;
  long long duplicate_vertices = 0;      ///< referenced vertices at bit-identical positions
  long long duplicate_faces = 0;         ///< faces with the same vertex set
  bool self_intersections_checked = false;
  long long self_intersecting_pairs = 0;
  bool volume_bounded = false;           ///< closed, manifold, oriented, no self-intersection
  bool acceptable = false;
  double bbox_longest_edge = 0.0;
  std::vector<Defect> defects;
  double time_s = 0.0;
};

CheckReport check_surface(const SurfaceMesh& mesh, const CheckOptions& options = {},
                          const ProgressFn& progress = {});

}  // namespace curvefem::check
