#pragma once
// Thin-part refinement of the input (issue 21): edge bisection, without moving the surface, where
// an input edge is much longer than the object is thick there.
//
// Why: the coarsening's thickness guard (SimplifyOptions::max_edge_per_thickness) keeps coarse
// edges within a multiple of the local thickness, but it can only refuse collapses: where the
// input's own edges are already that long (a CAD plate of two triangles per side, a bar whose
// sides are needle triangles) the slab tets under them are as flat as edge / thickness, whatever
// the later stages do (thin_plate_01: min scaled Jacobian 5e-4, every tet below 0.01).
//
// Thickness T is measured as the guard measures it, on the unrefined input, but at the middle of
// an edge rather than at its ends: the distance along the inward mean normal of the edge's two
// faces to the input beyond their own input faces. An edge (a, b) is *thin* when
// |ab| > max_edge_per_thickness · T(midpoint). (At the ends, a wedge's tip — thickness 0 —
// would ask for edges of length 0 next to it.)
// Rounds: every face whose longest edge is thin has that edge bisected at the midpoint (both
// faces of the edge split, so the mesh stays conforming), longest faces first, one split per face
// per round; the face across a bisected edge is bisected with it, whether or not that edge is its
// longest. Left alone: a face whose thin edge is not its longest (bisecting a shorter edge would
// spoil its shape), an edge whose bisection would not lower its ratio by `min_gain` (a wedge —
// knife edge, needle tip — is as thin at the midpoint as the edge is long, and halving it forever
// would not help), and the kept edges (input feature edges: the coarsening's feature chains need
// them whole). Stops at max_rounds, when a round splits nothing, or before the refinement would
// add more than max_added_faces faces.
//
// The result is a BeveledSurface (bevel.hpp): input vertices keep their ids, new vertices are
// edge midpoints (rounded to double), face_parent / corner_bary give every refined face's place
// in its input face, tags follow the parent. compose() chains it with a later refinement (the
// topological beveling of the refined surface).

#include <array>
#include <vector>

#include "meshing/core/surface_mesh.hpp"
#include "meshing/shell/bevel.hpp"

namespace curvefem::meshing::shell {

struct ThinRefineOptions {
  double max_edge_per_thickness = 8;  // <= 0: off
  double min_gain = 0.75;  // a split must bring the children's ratio below this × the edge's
  int max_rounds = 24;
  int max_added_faces = 20000;                 // the refinement adds at most this many faces
  std::vector<std::array<int, 2>> kept_edges;  // input vertex pairs never bisected
};

struct ThinRefineStats {
  int thin_edges_before = 0, thin_edges_after = 0;   // edges above the ratio
  double max_ratio_before = 0, max_ratio_after = 0;  // worst |ab| / min(T(a), T(b))
  int splits = 0, rounds = 0;
  int refined_faces = 0;  // input faces refined
  bool budget_reached = false;
  double seconds = 0;
};

/// The input refined where it is thin (see above); the input itself (identity parents) when no
/// edge is. The input must be a closed, consistently oriented, edge-manifold surface.
BeveledSurface refine_thin_parts(const SurfaceMesh& input, const ThinRefineOptions& options,
                                 ThinRefineStats& stats);

/// `outer` (a refinement of inner.mesh) as a refinement of inner's input: parents and
/// barycentric coordinates composed, counts of the input. Vertices keep outer's ids.
BeveledSurface compose(const BeveledSurface& inner, BeveledSurface outer);

}  // namespace curvefem::meshing::shell
