#pragma once
// Topological beveling (thesis §4.2.3 "Topological beveling", Fig. 4.9–4.11, §4.2.5 for
// singularities; reference-notes §3.3): the input's connectivity is refined around chosen
// vertices, without moving the surface, so that every prism of the shell built on the refined
// surface sees, with each of its pillars, every input face it can meet (the section condition I2).
//
// Pattern (a masked Doo–Sabin bevel, t = 0.2 by default). For a face (v0, v1, v2), every marked
// corner vi gets
//   - an edge point on each of its two edges at t from vi: (1 - t) vi + t vj (shared with the
//     face across that edge, which marks the same corner);
//   - an inner point (1 - t) vi + t/2 (vj + vk); at a singular corner two inner points,
//     (1 - t) vi + 2t/3 vj + t/3 vk and (1 - t) vi + t/3 vj + 2t/3 vk;
// and the face is rebuilt from corner triangles (vi, edge point, inner point), edge strips
// (two edge points and two inner points along each edge) and a centre polygon. Unmarked corners
// collapse back to the corner itself (degenerate triangles are dropped), so a face with no
// marked corner is kept as it is and a fully marked face becomes 13 triangles (15 or more with
// singular corners). Conformity: an edge carries the point near vi exactly when vi is marked,
// in both faces.
//
// Directions (the thesis: "copied from the closest vertex"): a point made for a non-singular
// corner vi gets vi's direction, so every refined vertex next to vi extrudes along the same
// pillar; a point of an edge (vi, vj) made for a singular corner vi gets the normalized sum of
// the two face normals at that edge (as build_shell's pinch splits; singular only if the sum
// vanishes), and each inner point of a singular corner copies the edge point on its side. Every
// refined face then lies in the one-ring used to compute each of its pillars, so a thin enough
// prism meets only faces its pillars see (thesis Theorem 4.6); the shell built on the refined
// surface is still verified independently (verify.hpp), never trusted.
//
// Conventions: vertices 0..#input V - 1 of the refined surface are the input's (same positions,
// same ids); new vertices are appended. Positions of new vertices are barycentric combinations
// of their parent face's corners, rounded to double (so a new point on an edge lies on it up to
// rounding). face_parent maps every refined face to the input face containing it, and
// corner_bary gives its corners' barycentric coordinates in that parent (input vertex order), so
// a point (refined face, barycentrics b) is (face_parent, corner_bary · b) on the input.

#include <Eigen/Core>
#include <utility>
#include <vector>

#include "meshing/core/progress.hpp"
#include "meshing/core/surface_mesh.hpp"
#include "meshing/shell/extrusion_direction.hpp"
#include "meshing/shell/shell.hpp"

namespace curvefem::meshing::shell {

struct BevelOptions {
  double t = 0.2;      // edge fraction of the new points (thesis: 0.2), in (0, 0.5)
  int max_rounds = 4;  // build_beveled_shell: bevel/rebuild rounds at most
};

struct BeveledSurface {
  SurfaceMesh mesh;                          // the refined surface (tags follow the parent face)
  ExtrusionDirections directions;            // one row per refined vertex (left empty by
                                             // build_beveled_shell when nothing is beveled)
  std::vector<int> face_parent;              // #refined F: the input face containing it
  std::vector<Eigen::Matrix3d> corner_bary;  // #refined F: column k = corner k in the parent
  int input_vertices = 0, input_faces = 0;
  int beveled_faces = 0;    // input faces refined (at least one marked corner)
  int marked_vertices = 0;  // input vertices beveled

  bool refined() const { return beveled_faces > 0; }
  // (refined face, barycentric coordinates in it) -> (input face, barycentric coordinates).
  std::pair<int, Eigen::Vector3d> to_input(int face, const Eigen::Vector3d& bary) const;
};

// The input unchanged, as a BeveledSurface (identity parents, the given directions).
BeveledSurface unbeveled_surface(const SurfaceMesh& input, const ExtrusionDirections& directions);

// Refines `input` around the vertices with marked[v] != 0 (#V entries). `directions` are the
// input's extrusion directions (extrusion_directions on the same V, F). The input must be an
// edge-manifold, consistently oriented, closed surface (InputError otherwise).
BeveledSurface bevel_surface(const SurfaceMesh& input, const ExtrusionDirections& directions,
                             const std::vector<char>& marked, const BevelOptions& options = {});

struct BevelStats {
  bool needed = false;  // the shell of the unrefined input failed the section check
  int rounds = 0;       // bevel + rebuild rounds done
  int marked_vertices = 0, beveled_faces = 0;
  int non_section_before = 0;  // prisms failing I2 on the unrefined input
  int non_section_after = 0;   // prisms failing I2 after the last round
  double seconds = 0;          // section checks and refinement (not the shell builds)
};

struct BeveledShell {
  Shell shell;             // built on surface.mesh: face_parent / input_vertex refer to it
  BeveledSurface surface;  // the input itself when no beveling was needed
  BevelStats stats;
};

// build_shell on the input; if some prism fails the section condition (non_section_prisms,
// verify.hpp), the corners of the input faces under the failing prisms are marked, the input is
// beveled around them and the shell rebuilt on the refined surface with the beveled directions,
// for up to max_rounds rounds (stopping early when no new corner gets marked, or keeping the
// previous shell when a rebuild throws MeshingError). When nothing fails the shell is the one
// build_shell returns, bit for bit. `stats` ends as the last build's, with the input counts of
// the unrefined input and the stage times summed over the builds (plus a "bevel" stage).
BeveledShell build_beveled_shell(const SurfaceMesh& input, const ShellOptions& options,
                                 ShellStats& stats, const BevelOptions& bevel = {},
                                 const ProgressFn& progress = {});

// Rewrites a shell built on surface.mesh (or coarsened from it) so it refers to the unrefined
// input: face_parent becomes the input face, input_vertex of a vertex added by beveling or
// refinement -1, and the reference snaps refer to input vertices (SnappedVertex: ends by position).
void restore_input_ids(Shell& shell, const BeveledSurface& surface);

}  // namespace curvefem::meshing::shell
