// Displacement maps baked through the shell's projection (thesis §4.4, "Displacement mapping",
// Fig. 4.26): the coarse middle surface plus one height per sample point reconstructs the dense
// input, and the correspondence is P's, so it is bijective wherever the coarse surface is a
// section (Phong / normal projection is not: it folds on thin parts and sharp bends).
//
// Samples. Each middle-surface face f, rotated to its smallest vertex id (projection.hpp), is
// sampled at the (L+1)(L+2)/2 points (u, v) = (i/L, j/L), i + j ≤ L, of a level-L grid, in the
// order i = 0..L, then j = 0..L−i. The value stored at a sample is the prism coordinate h ∈ [-1, 1]
// of the input point P_T(f, u, v) on that sample's fiber: the map is scalar, a height along the
// fiber (the pillar direction interpolated over the prism), and the point is rebuilt from the
// shell's base, middle and top vertices alone by ShellProjection::point(f, u, v, h).
// Samples on an edge or a corner belong to several faces; the reconstruction takes each shared
// point from the face of smallest id holding it (the fibers of neighbouring prisms on their
// common lateral facet are the same, so both values agree up to rounding).
//
// The file (write_displacement_map / read_displacement_map, text): a line
// "curvefem-displacement-map 1", a line "level L faces N", then N lines of (L+1)(L+2)/2 heights
// written with 17 significant digits. The shell it belongs to is written beside it (shell.vtu /
// cage.obj of `curvefem shell --displacement-map`).
#pragma once

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "meshing/core/surface_mesh.hpp"
#include "meshing/shell/projection.hpp"
#include "meshing/shell/shell.hpp"

namespace curvefem::meshing::shell {

struct DisplacementMap {
  int level = 1;
  int faces = 0;
  std::vector<double> h;  ///< faces × samples_per_face(level), face-major, order of the header
  int failures = 0;       ///< samples whose fiber missed the input (NaN in h)
};

inline int samples_per_face(int level) { return (level + 1) * (level + 2) / 2; }

/// The prism coordinate h of the input point on the fiber of (face, u, v) (rotated order, as
/// PrismPoint): P_T's crossing, placed on the fiber polyline. nullopt where the fiber misses.
std::optional<double> input_height(const ShellProjection& onto_input, int face, double u, double v);

/// Bakes the map of `onto_input` (ShellProjection(shell, input)) at `level` ≥ 1; parallel over
/// faces. A sample whose fiber misses the input is NaN and counted.
DisplacementMap bake_displacement_map(const ShellProjection& onto_input, int level);

/// The level-L subdivision of the shell's middle surface with every vertex at its height: the
/// dense surface rebuilt from shell + map (no input needed). Vertices: the middle vertices
/// first (ids kept), then edge points, then face-interior points; faces keep the middle
/// surface's orientation, L² per coarse face, face_parent[k] = the coarse face. A NaN height
/// leaves the point on the middle surface (h = 0).
struct Reconstruction {
  SurfaceMesh mesh;
  std::vector<int> face_parent;
};
Reconstruction reconstruct(const Shell& shell, const DisplacementMap& map);

/// The same subdivision displaced the usual way, for comparison: each point moves along the
/// interpolated vertex normal of the middle surface (area-weighted face normals) to the nearest
/// crossing with the input within ± `reach` (Phong-style normal projection, thesis Fig. 4.26
/// top). `missed` counts points with no crossing (left on the middle surface).
Reconstruction reconstruct_along_normals(const Shell& shell, const SurfaceMesh& input, int level,
                                         double reach, int* missed);

/// Checks each rebuilt vertex against its sample by another path than the bake's fiber walk:
/// exact point location (ShellProjection::locate) of the vertex gives a fiber, whose point on the
/// middle surface (h = 0) must be the sample's. Distinct samples have distinct fibers, so with
/// every vertex on the input (checked apart, e.g. check::distances_to_surface) this verifies that
/// the samples map one to one onto input points, in P's correspondence.
struct FiberCheck {
  int not_located = 0;    ///< rebuilt vertices in no prism
  double max_offset = 0;  ///< max distance between the two middle-surface points
};
FiberCheck check_on_fibers(const ShellProjection& projection, const DisplacementMap& map,
                           const Reconstruction& rebuilt);

void write_displacement_map(const std::string& path, const DisplacementMap& map);
/// InputError naming the file and line on a malformed file.
DisplacementMap read_displacement_map(const std::string& path);

}  // namespace curvefem::meshing::shell
