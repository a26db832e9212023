// Geometric textures (thesis §4.4, Fig. 4.27): a tile — a closed triangle mesh in the unit prism —
// copied into every prism of the shell through the shell's volumetric parametrization.
//
// Tile coordinates (a, b, t): (a, b) barycentric in the reference triangle (a, b ≥ 0, a + b ≤ 1),
// the prism's face taken in its rotated order (projection.hpp), and t ∈ [0, 1] from the base of
// the shell (t = 0) through the middle surface (t = ½) to the top (t = 1): the point of prism
// coordinates (face, a, b, h = 2t − 1), ShellProjection::point.
// Why the copies do not meet: that map is affine on each tet of the prism's canonical split
// (consecutive rising facets differ in one corner on one pillar, so interpolating along the fiber
// between them is the tet's barycentric map), hence a piecewise-linear bijection of the unit
// prism onto the prism when its tets are positive, and the prisms of a shell conform on their
// lateral facets. The tile is first split along the planes of the reference split (two per half
// plus the middle, for type A or B faces: split_tile_at_tets), so every piece lies in one tet and
// its image is the flat triangle of its mapped corners: the textured surface is the exact image
// of the tile. So a tile free of self-intersections gives copies that meet neither themselves nor
// each other wherever the shell's prisms are positive and do not overlap. Overlaps show where the
// top (base) surface meets itself; separate_for_tile shortens the half-pillars there first.
// A prism pinched at a singular vertex (zero-length pillar) has flat tets and gets no copy.
// `curvefem shell --texture` does both and checks the result with exact predicates. The input is
// not a constraint: it crosses the fibers at heights of its own, and a tile reaching below it meets
// it (reported).
#pragma once

#include <string>
#include <vector>

#include "meshing/core/surface_mesh.hpp"
#include "meshing/shell/nested_cages.hpp"
#include "meshing/shell/projection.hpp"
#include "meshing/shell/shell.hpp"

namespace curvefem::meshing::shell {

/// A built-in tile, in the upper half of the prism: "knob" (a ball at the triangle's centroid,
/// t ∈ [0.6, 0.9]), "ring" (a torus around the centroid at t = 0.75), "spike" (a cone on a
/// disc at t = 0.55 around the centroid, apex at t = 0.95). InputError for an unknown name (the
/// message lists the names).
SurfaceMesh builtin_tile(const std::string& name);
/// The built-in tile names.
std::vector<std::string> builtin_tile_names();

/// InputError naming the first vertex outside the unit prism (a, b ≥ 0, a + b ≤ 1, 0 ≤ t ≤ 1).
void check_tile(const SurfaceMesh& tile, const std::string& where);

/// The tile with its triangles split along the planes of the reference prism's canonical split
/// for a face of type A or B (prism_split.hpp): each piece lies in one tet, where the shell's
/// map is affine, so the mapped pieces are the exact image of the tile.
SurfaceMesh split_tile_at_tets(const SurfaceMesh& tile, bool type_a);

struct TexturedSurface {
  SurfaceMesh mesh;  ///< one copy of the (split) tile per prism (tags: the prism's face)
  /// Prisms pinched at a singular vertex (a zero-length pillar) get no copy: their canonical
  /// split has flat tets, which would flatten the pieces of the tile in them (degenerate faces
  /// meeting the neighbouring copies). Their number.
  int skipped_pinched = 0;
};

/// Where the shell's top (base) surface meets itself, the upper (lower) halves of prisms overlap
/// and copies lying there can meet. For each half the tile reaches (t > ½, t < ½), that surface
/// is freed of self-intersections by shortening its half-pillars (separate_shell_side, as for
/// nested cages, each change verified against `surface`). `shell` is changed in place.
struct TileSeparation {
  bool top = false, base = false;  ///< which halves the tile reaches
  SeparationStats top_stats, base_stats;
  std::string top_failure, base_failure;  ///< "" when that surface ended free of pairs
};
TileSeparation separate_for_tile(Shell& shell, const SurfaceMesh& surface, const SurfaceMesh& tile);

/// Copies `tile` into every prism of onto_input's shell but the pinched ones (parallel over
/// prisms).
TexturedSurface apply_geometric_texture(const ShellProjection& onto_input, const SurfaceMesh& tile);

}  // namespace curvefem::meshing::shell
