// Validity of a triangle surface for meshing (DESIGN.md §1, first stage).
//
// A surface is acceptable when it is non-empty, closed (no boundary edge), edge- and
// vertex-manifold, consistently oriented with positive signed volume (outward), has no degenerate
// face (repeated vertex index or exactly collinear corners, exact predicates) and no pair of faces
// that intersect other than in their shared vertices/edge (CGAL PMP, exact predicates).
// Small angles, unreferenced and coincident vertices and duplicate faces are reported but do not by
// themselves make a surface unacceptable (real CAD tessellations have slivers down to 1e-3
// degrees; a duplicate face also shows up as a non-manifold/misoriented edge or a
// self-intersection).
//
// Definitions (all combinatorial notions use vertex *ids*; coincident unwelded vertices are
// distinct):
//   - edge: unordered pair of distinct vertex ids used by a face corner; its "faces" are its face
//     corners (half-edges), so a face appearing twice on one edge counts twice.
//   - boundary edge: one half-edge; non-manifold edge: three or more; inconsistently oriented
//     edge: exactly two half-edges with the same direction.
//   - non-manifold vertex: the faces around it split into several fans, faces being linked through
//     the edges at the vertex that have two or more faces (a pinch: two cones touching at the apex,
//     a bow-tie). Edges with > 2 faces link their faces: the ends of a non-manifold edge are not
//     counted again unless they are pinched as well.
//   - component: faces linked through shared edges (not through a lone shared vertex: the
//     hourglass of two cones touching at one vertex has 2 components).
//   - orientable: faces can be flipped so that every two-face edge is consistent (parity
//     propagation through the edges with two faces); faces_to_flip is the minimum number of flips
//     per edge-connected patch, summed.
//   - genus: only for a closed, edge- and vertex-manifold, orientable surface (-1 otherwise):
//     Σ over components of (2 − χ_c)/2 with χ_c = V_c − E_c + F_c over referenced vertices.
//   - orientation_sign: sign of the signed volume when closed, edge-manifold and consistently
//     oriented (pinched vertices do not prevent it), else 0.
//   - self-intersections: see meshing/check/self_intersections.hpp (degenerate faces are excluded
//     from pairs; PMP on a CGAL::Surface_mesh when the surface is an oriented manifold, the same
//     rule on the indexed soup otherwise).
#pragma once

#include <Eigen/Core>
#include <string>
#include <utility>
#include <vector>

#include "meshing/core/progress.hpp"
#include "meshing/core/surface_mesh.hpp"

namespace curvefem::check {

struct CheckOptions {
  bool self_intersections = true;  ///< the most expensive test; off = not checked (reported)
  int max_listed_ids = 10;         ///< ids named per defect
  /// Warnings (CheckReport::warnings): faces with a corner angle below needle_angle_deg, and
  /// oriented manifold edges whose two face normals turn by more than fold_angle_deg (the surface
  /// doubles back: an interior angle below 180 − fold_angle_deg between the two faces).
  double needle_angle_deg = 1.0;
  double fold_angle_deg = 170.0;
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
  long long components = 0;             ///< connected components of faces (by shared edge)
  long long boundary_edges = 0;         ///< edges with one incident face
  long long non_manifold_edges = 0;     ///< edges with more than two incident faces
  long long non_manifold_vertices = 0;  ///< vertices whose faces form several fans (pinches)
  long long inconsistent_edges = 0;     ///< manifold edges traversed twice in the same direction
  bool closed = false, edge_manifold = false, vertex_manifold = false;
  bool consistently_oriented = false;
  bool orientable = false;      ///< consistent orientation reachable by flipping faces
  long long faces_to_flip = 0;  ///< minimum flips for consistency (orientable patches)
  double signed_volume = 0.0;
  int orientation_sign = 0;  ///< +1 outward, -1 inward, 0 undefined (open/inconsistent)
  long long genus = -1;      ///< closed orientable manifold: sum over components, else -1
  long long euler_characteristic = 0;
  long long degenerate_faces = 0;  ///< repeated index or exactly collinear
  double min_angle_deg = 0.0, max_angle_deg = 0.0;
  long long duplicate_vertices = 0;  ///< referenced, at the exact (==) position of a lower id
  long long duplicate_faces = 0;     ///< faces with the vertex set of a lower-id face
  bool self_intersections_checked = false;
  bool self_intersections_mesh_api = false;  ///< PMP mesh API (true) or soup rule (false)
  long long self_intersecting_pairs = 0;
  bool volume_bounded = false;  ///< closed, manifold, oriented, no self-intersection
  bool acceptable = false;      ///< non-empty and `defects` is empty
  double bbox_longest_edge = 0.0;
  std::vector<Defect> defects;
  /// Not defects (the surface stays acceptable): what bounds the quality of any mesh whose
  /// boundary keeps it where the coarsening cannot remove it (seen on unseen scans: a fold of 2.1°
  /// and a needle of 0.63° kept as coarse faces gave slab tets of curved MIPS 4.4e6 and 1.5e4).
  /// Kinds: `needle` (faces, CheckOptions::needle_angle_deg), `near_fold` (edges,
  /// CheckOptions::fold_angle_deg); ids sorted worst first; the message names the worst one and
  /// where it is.
  std::vector<Defect> warnings;
  double time_s = 0.0;
};

/// Faces of (V, F) with a corner angle below `angle_deg`, with that smallest angle (degrees);
/// exactly degenerate faces (exactly_degenerate_faces) are left out. Ids ascending.
std::vector<std::pair<int, double>> needle_faces(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F,
                                                 double angle_deg);

/// Edges with exactly two faces traversing them in opposite directions whose face normals turn by
/// more than `angle_deg` (degrees; 180 where the faces fold flat onto each other), as
/// (lo, hi, turn); faces of zero area are left out. Sorted by (lo, hi).
struct FoldEdge {
  int lo = 0, hi = 0;
  double turn_deg = 0;
};
std::vector<FoldEdge> near_fold_edges(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F,
                                      double angle_deg);

/// Checks `mesh` (V #V × 3, F #F × 3). Throws InputError if a face index is out of range.
/// `progress` receives the stages "check topology" and "check self-intersections".
CheckReport check_surface(const SurfaceMesh& mesh, const CheckOptions& options = {},
                          const ProgressFn& progress = {});

}  // namespace curvefem::check
