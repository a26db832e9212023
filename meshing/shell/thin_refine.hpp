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
// per round. Longest-edge closure: where the face across has a longer edge, the end of that
// longest-edge path (Rivara) is bisected instead and the thin edge waits for a later round, so a
// face is cut across its longest edge only where that edge is kept; such a split must leave the
// child along the kept edge no worse than max(max_child_mips, its parent) (without it, faces next
// to a CAD edge were halved again and again along it: refined faces of 2-D MIPS 1e6-1e9, and on
// shape_occt at ratio 3 a coarse face 90 long and 1.6e-4 high, min scaled Jacobian 2.5e-7).
// Left alone: a face whose thin edge is not its longest (bisecting a shorter edge would spoil its
// shape), an edge whose bisection would not lower its ratio by `min_gain` (a wedge — knife edge,
// needle tip — is as thin at the midpoint as the edge is long, and halving it forever would not
// help), and the kept edges (input feature edges: the coarsening's feature chains need them
// whole). Stops at max_rounds, when a round splits nothing, or before the refinement would add
// more than max_added_faces faces.
//
// The result is a BeveledSurface (bevel.hpp): input vertices keep their ids, new vertices are
// edge midpoints (rounded to double), face_parent / corner_bary give every refined face's place
// in its input face, tags follow the parent. compose() chains it with a later refinement (the
// topological beveling of the refined surface).

#include <array>
#include <cmath>
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
  // A bisection is left out when, in a face of the edge whose longest edge is a kept one, the
  // child along that kept edge would have a 2-D MIPS above max(this, its parent's)
  // (thin_refine.cpp children_shaped); <= 0: no check.
  double max_child_mips = 20;
  // The longest-edge closure above (false: the face across a thin edge is bisected with it,
  // whatever its longest edge).
  bool longest_edge_closure = true;
};

struct ThinRefineStats {
  int thin_edges_before = 0, thin_edges_after = 0;   // edges above the ratio
  double max_ratio_before = 0, max_ratio_after = 0;  // worst |ab| / min(T(a), T(b))
  int splits = 0, rounds = 0;
  int shape_refusals = 0;  // bisections left out by max_child_mips
  int closure_splits = 0;  // bisections of longer edges first (longest-edge closure), in `splits`
  int refined_faces = 0;   // input faces refined
  bool budget_reached = false;
  double seconds = 0;
};

/// The input refined where it is thin (see above); the input itself (identity parents) when no
/// edge is. The input must be a closed, consistently oriented, edge-manifold surface.
BeveledSurface refine_thin_parts(const SurfaceMesh& input, const ThinRefineOptions& options,
                                 ThinRefineStats& stats);

// Shape refinement of the input (issue 21): edge bisection, without moving the surface, of the
// badly shaped faces of CAD tessellations.
//
// Why: the coarse surface keeps input vertices (the coarsening has no tangential moves), and a CAD
// tessellation has vertices almost only on its curves: its flat and ruled faces are fans of
// needles and caps (hinge: 488 of 1,212 faces with an angle below 5 degrees). The coarsening then
// has no vertex to place inside such a face, its coarse triangles stay caps and needles, and so do
// the slab tets on them, which no later edit of the volume removes (hinge, K = 3: slab tets of
// scaled Jacobian 1.6e-3 on a coarse face with angles 0.5 and 160 degrees).
// Rounds of longest-edge bisection, longest first: a face whose 2-D MIPS energy
// (|e0|² + |e1|² + |e2|²) / (2√3 · area), 2 for the equilateral triangle, is above max_mips and
// whose longest edge is longer than min_edge has that edge bisected at its midpoint (both faces of
// the edge, so the mesh stays conforming). Feature edges are bisected too (bisect_features): a
// needle strip between two feature curves has its long edges on them. Their halves are returned,
// so the coarsening's feature chains run through the new vertices (which it may collapse again).
// Stops when no face qualifies or before more than max_added_faces faces would be added.
// Spikes may be left alone (min_cone_angle > 0): a face whose sharpest corner is an input vertex of
// total face angle below min_cone_angle (radians; 2π on a flat surface, 3π/2 at a box corner,
// about 0.04 at the tip of a needle leaning 0.4°) is a side of a thin cone, not of a CAD fan, and
// bisecting it only adds needles to the spike (needle_sphere_32: min scaled Jacobian 5e-5 ->
// 1.5e-6 with them bisected). 0 here; the curved mesher passes π/2
// (CurvedMeshOptions::shape_refine_spike_angle, meshing/curved/README.md, step 1).
struct ShapeRefineOptions {
  double max_mips = 10;
  double min_edge = 0;        // absolute length; <= 0: off
  double min_cone_angle = 0;  // 0: spikes are bisected too
  int max_added_faces = 60000;
  std::vector<std::array<int, 2>> feature_edges;  // input vertex pairs
  bool bisect_features = true;  // false: a face whose longest edge is a feature edge stays
};

struct ShapeRefineStats {
  int poor_faces_before = 0, poor_faces_after = 0;  // faces that qualify for a bisection
  int spike_faces = 0;  // poor long input faces left alone at a cone tip (min_cone_angle)
  int splits = 0, feature_splits = 0;  // bisections, of which on feature edges
  int refined_faces = 0;               // input faces refined
  bool budget_reached = false;
  double seconds = 0;
};

/// The input refined where its faces are poorly shaped and long (see above); the input itself
/// (identity parents) when none is. `refined_features` receives the feature edges as vertex pairs
/// of the refined surface (input vertices keep their ids). The input must be a closed, consistently
/// oriented, edge-manifold surface.
BeveledSurface refine_poor_shapes(const SurfaceMesh& input, const ShapeRefineOptions& options,
                                  ShapeRefineStats& stats,
                                  std::vector<std::array<int, 2>>& refined_features);

/// `outer` (a refinement of inner.mesh) as a refinement of inner's input: parents and
/// barycentric coordinates composed, counts of the input. Vertices keep outer's ids.
BeveledSurface compose(const BeveledSurface& inner, BeveledSurface outer);

}  // namespace curvefem::meshing::shell
