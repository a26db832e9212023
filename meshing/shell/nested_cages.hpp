// Nested cages (thesis §4.5, Fig. 4.29): the shell is built around the input, its top surface is
// the first cage, a shell is built around that cage, and so on: increasingly coarse closed
// surfaces, each strictly outside the one before, with P of each shell mapping a cage
// bijectively onto the layer inside it (thesis §4.2.8: every point of the top surface lies on
// exactly one fiber, and every fiber crosses the shell's input exactly once).
//
// A simplified shell's top surface may intersect itself where two parts of the surface face each
// other (legs, handles). As in the thesis, the top pillars of the faces involved are shortened
// (kept fraction `shrink` per round, toward the middle surface) until the top surface has no
// self-intersecting pair, and every round is verified: the shell must stay positive, separated
// from its input and a section (verify_shell). The thesis refines the middle surface where a
// shrink would break the shell; that refinement is not implemented. Instead the layer is tried
// again with a less coarsened shell: simplified without thickness growth, then the same on a
// shell a quarter as thick, then not simplified (its middle surface is the layer inside, which
// shrinking cannot cross). Only when even that
// fails does the construction stop, with a MeshingError naming the layer and the pairs left.
// At a singular vertex of a layer (zero-length pillar) the next cage touches that layer. When the
// layer is a cage, such a vertex is a "pinch point" of the top surface the layer came from (no
// direction sees all its faces), usually where a coarse top surface folds into a narrow crease:
// before the next layer is built, the top pillars at and around each pinch point are shortened,
// round by round (the top surface then approaches the middle surface, a section of the layer
// inside), each change kept only if the changed prisms stay positive and off the layer inside
// and the top surface free of self-intersections, the whole shell verified at the end. Points
// left over make the layer try its next, less coarsened shell; the shell with the fewest is kept.
// At singular vertices of the input itself (and at pinch points of a cage that unpinching left)
// the shell's top pillar has zero length, and its top surface touches the layer inside. There
// the cage is filled (thesis §4.5, "pinching alternative"): it is the union of the top surface
// with a small regular tetrahedron centred on each such point (CGAL corefinement, exact, then
// rounded), smaller than the pillars and edges around it. The point is then strictly inside the
// cage; the cage's faces on a tetrahedron map to the point itself, so the map is not one to one
// on them (and the layer inside's points whose fibers end inside a tetrahedron have no place on
// the cage), as in the thesis, where every point of the filled region projects to the
// singularity. CageLayer::cage_face_parent carries the cage's faces to the top surface.
//
// Maps. cage_to_input carries points of cage k + 1, given as a face and barycentric coordinates
// (a point of the top surface is on the boundary of the shell, where locating a rounded position
// would be a coin toss), down through the shells k, …, 0: the fiber of (face, u, v) to the
// layer inside, whose point is again a face and barycentric coordinates of the cage below (of the
// input at the end). input_to_cage carries input positions up: each lies inside the next shell,
// is located exactly, and the top end of its fiber (h = 1) is on the next cage. Both compose P
// and P⁻¹; up(down(x)) = x up to rounding checks that the composition is one to one where it is
// sampled.
#pragma once

#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

#include "meshing/core/progress.hpp"
#include "meshing/core/surface_mesh.hpp"
#include "meshing/shell/projection.hpp"
#include "meshing/shell/shell.hpp"
#include "meshing/shell/simplify.hpp"
#include "meshing/shell/verify.hpp"

namespace curvefem::meshing::shell {

struct NestedCageOptions {
  int layers = 3;
  ShellOptions shell;  ///< each layer's shell (max_thickness_rel relative to that layer's bbox)
  bool simplify = true;
  double zoom_rel = 0.1;  ///< SimplifyOptions::zoom, relative to each layer's longest bbox edge
  int threads = 1;
  double shrink = 0.8;  ///< fraction of a top half-pillar kept per shrink round
  int max_shrink_rounds = 40;
  /// Shorten the top pillars around the cage's pinch points before the next layer is built on
  /// it (see CageLayer::top_pinch_points); false only to measure what it changes.
  bool unpinch = true;
  /// Fill the cage around zero-length top pillars (see above); false only to measure it.
  bool fill = true;
  /// Each tetrahedron's circumradius, as a fraction of the smallest of: half the top edges at
  /// the point, its neighbours' top pillars, the distance to the top faces away from it, and
  /// 0.4 × the distance to the nearest other filled point.
  double fill_size = 0.5;
};

struct CageLayer {
  /// The top surface of `shell` (its vertices, the shell's faces), or when points were filled
  /// its union with the fill tetrahedra (then cage_face_parent is not empty).
  SurfaceMesh cage;
  /// Per cage face when filled: the top surface's face (a face of shell.F) it lies in, and its
  /// corners' barycentric coordinates there (column k: corner k). A face on a tetrahedron has a
  /// face at the filled point as parent and every corner at that point. Empty: the identity.
  std::vector<int> cage_face_parent;
  std::vector<Eigen::Matrix3d> cage_corner_bary;
  std::vector<char> cage_face_on_fill;  ///< per cage face when filled: on a tetrahedron
  int filled_points = 0;                ///< zero-length top pillars filled
  int unfilled_points = 0;              ///< zero-length top pillars with no room for a tetrahedron
  double fill_size = 0;                 ///< the largest tetrahedron's circumradius
  SurfaceMesh surface;  ///< what the shell was built on: the layer inside (beveled if needed)
  /// surface's faces in the layer inside (bevel.hpp's BeveledSurface: identity when not beveled)
  std::vector<int> surface_face_parent;
  std::vector<Eigen::Matrix3d> surface_corner_bary;
  Shell shell;
  /// Which shell was kept: "simplified", "simplified without growth" (SimplifyOptions::zoom 0),
  /// "simplified, thinner" (no growth, a quarter of max_thickness_rel) or "not simplified", the
  /// first whose top surface could be freed of self-intersections.
  std::string attempt;
  int singular_vertices = 0;  ///< zero-length pillars: the cage touches the layer inside there
  int self_intersecting_pairs_before = 0;  ///< the top surface's pairs before shrinking
  int shrink_rounds = 0;
  int shrunk_pillars = 0;  ///< top half-pillars shortened at least once
  /// Vertices of the cage the next layer's shell would pinch (no extrusion direction), before
  /// and after their top pillars and their neighbours' were shortened (unpinch_rounds rounds);
  /// not computed for the last layer.
  int top_pinch_points_before = 0, top_pinch_points = 0, unpinch_rounds = 0;
  int unpinch_trials = 0;  ///< shortenings tried (each screened on its prisms), the attempt kept
  ShellVerification verification;  ///< the final shell against `surface`
  double seconds = 0;
};

struct NestedCages {
  SurfaceMesh input;
  std::vector<CageLayer> layers;  ///< layers[k].cage is cage k + 1; layers[0] is around the input
  /// One projection per layer (ShellProjection(layers[k].shell, layers[k].surface)).
  std::vector<std::unique_ptr<ShellProjection>> projections;
};

struct SeparationStats {
  int pairs_before = 0;            ///< self-intersecting pairs of that surface before shrinking
  int rounds = 0;                  ///< shrink rounds kept
  int shortened_pillars = 0;       ///< half-pillars shortened at least once
  ShellVerification verification;  ///< of the shell kept, when rounds > 0
};

/// The thesis' resolution of a shell's self-intersections (§4.5): the half-pillars on one side
/// (top or base) of the faces in self-intersecting pairs of that surface are shortened toward
/// the middle surface (kept fraction `shrink` per round), round by round, each change verified
/// against `surface`: each change is screened on the prisms it moves (positive, their top and
/// base triangles off `surface`), and a refused change is split, each half of the round's pairs
/// tried alone down to single pairs; the whole shell is then verified once (verify_shell:
/// positive, separated, a section), and if that fails, the rounds are redone with every round
/// verified whole and not split (the construction before the screen). "" when that surface ends
/// free of self-intersections, else why not (a round in which nothing could be shortened; the
/// shell keeps the changes made until then).
std::string separate_shell_side(Shell& shell, const SurfaceMesh& surface, bool top, double shrink,
                                int max_rounds, SeparationStats& stats);

/// MeshingError when a layer's top surface cannot be made free of self-intersections by
/// shrinking (the layer's number and the pairs left), InputError for a bad input.
NestedCages build_nested_cages(const SurfaceMesh& input, const NestedCageOptions& options,
                               const ProgressFn& progress = {});

/// A point of a triangle mesh: a face and barycentric coordinates in its vertex order.
struct MeshPoint {
  int face = -1;
  Eigen::Vector3d bary{0, 0, 0};
};

/// Points of cage k + 1 (layers[k].cage) to the input: #P × 3 positions, NaN rows where a step
/// could not map (counted in *failures). *on_fill (when given): per point, 1 when its way down
/// met a fill (a face of a filled cage on a tetrahedron), where the map is not one to one.
Eigen::MatrixXd cage_to_input(const NestedCages& cages, int k, const std::vector<MeshPoint>& points,
                              int* failures = nullptr, std::vector<char>* on_fill = nullptr);
/// Points of the input (#P × 3) up to cage k + 1: each point's fiber end on the top surface of
/// every shell in turn. Near a filled point that end may lie inside the fill, not on the cage.
Eigen::MatrixXd input_to_cage(const NestedCages& cages, int k, const Eigen::MatrixXd& points,
                              int* failures = nullptr);

}  // namespace curvefem::meshing::shell
