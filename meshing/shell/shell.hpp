#pragma once
// The bijective prismatic shell (thesis chapter 4; reference-notes §3.1–3.5, §4).
//
// Around a closed, oriented triangle surface (the input), every face f of the shell's middle
// surface carries a prism: base corners below, middle corners on the middle surface, top corners
// above, joined by the pillars of its three vertices. Built without simplification the middle
// surface is the input itself (with edges between two singular vertices split), and base/top
// are offsets along the QP extrusion directions, shrunk until every prism passes the exact 24-tet
// positivity test and no base or top triangle intersects the input.

#include <Eigen/Core>
#include <string>
#include <vector>

#include "meshing/core/progress.hpp"
#include "meshing/core/surface_mesh.hpp"
#include "meshing/shell/extrusion_direction.hpp"
#include "meshing/shell/shell_intersection.hpp"

namespace curvefem::meshing::shell {

/// The coarse shell's projection distortion bound (SimplifyOptions::section_cos): bichon's
/// distortion_bound, about 89.4°.
inline constexpr double k_section_cos = 0.01;
/// Where the starting shell leans further than that, the bound is this fraction of its own
/// cosine (SimplifyOptions::section_cos_relative).
inline constexpr double k_section_cos_relative = 0.5;

struct Shell {
  Eigen::MatrixXd base, mid, top;  // #V × 3 each
  Eigen::MatrixXi F;               // #F × 3, same orientation as the input
  std::vector<char> singular;      // #V: zero-length pillar (base = mid = top)
  std::vector<int> face_parent;    // #F: an input face under this prism (the one it was built on)
  std::vector<int>
      input_vertex;  // #V: the input vertex a middle vertex sits on, -1 for pinch points
  // The reference copy of the input (thesis §5.3): input vertices inside a coarse feature edge,
  // snapped onto it (empty: the reference copy is the input). The shell's invariants hold for
  // that copy, exactly; P projects onto it, and a point of it stands for the input point with
  // the same face and barycentric coordinates.
  std::vector<SnappedVertex> reference;
  // A shell built on a refinement of the input (the curved mesher's shape and thin refinements,
  // beveling) and then rewritten to the input's ids (restore_input_ids): the refined surface,
  // whose vertices are the input's and then `points`, with its faces' places in the input faces
  // and the snaps of *its* reference copy (surface ids). `reference` above then has the input
  // vertices' snaps only, an approximation of that copy (bisection points on and next to feature
  // chains move with it there but not in the input's faces); fibers_of crosses the refined
  // surface itself. Empty (no faces): built on the input.
  struct Refinement {
    Eigen::MatrixXd points;                // #added × 3
    Eigen::MatrixXi faces;                 // #refined F × 3
    std::vector<int> parent;               // input face of each refined face
    std::vector<Eigen::Matrix3d> bary;     // column k: corner k in the parent face
    std::vector<SnappedVertex> reference;  // snaps of the refined surface's reference copy
    bool empty() const { return faces.rows() == 0; }
  } refinement;
  // Locally injective only (local_sheets.hpp): the invariants hold against each prism's local
  // sheet of the input, which may pass through itself; verification and P check and use that.
  bool local_sheets = false;
};

struct ShellOptions {
  double max_thickness_rel = 0.02;  // cap on each half-pillar, relative to the longest bbox edge
  // > 0: also cap each vertex's half-pillar at this multiple of the mean length of its input
  // edges. A shell much thicker than the input's triangles are wide turns small differences
  // between neighbouring pillars into inverted prisms once coarsening starts; thickness growth
  // during simplification (SimplifyOptions::zoom) restores it where the coarse faces allow.
  double max_thickness_per_edge = 0;
  double singularity_tolerance = 1e-2;
  int smoothing_rounds = 3;
  // Build a locally injective shell (local_sheets.hpp) for an input that may self-intersect.
  bool local_sheets = false;
  int threads = 0;  // 0: oneTBB default
};

struct ShellStats {
  int input_faces = 0, input_vertices = 0;
  int singular_vertices = 0, pinch_splits = 0;
  int shrink_rounds_volume = 0, shrink_rounds_intersection = 0;
  double min_thickness_rel = 0, median_thickness_rel = 0, max_thickness_rel = 0;
  std::vector<std::pair<std::string, double>> stage_seconds;
};

// Throws InputError if the input is not a closed, consistently oriented manifold, MeshingError
// if a prism cannot be made positive or an edge between two singular vertices is folded flat
// (its two faces' normals opposite). Edges between singular vertices are split (repeatedly: a
// face with three singular corners becomes four faces), so every prism has at most one.
Shell build_shell(const SurfaceMesh& input, const ShellOptions& options, ShellStats& stats,
                  const ProgressFn& progress = {});

// The same with given per-vertex directions instead of the QP's (#V rows, unit or zero; singular
// vertices zero), e.g. those of a beveled surface (bevel.hpp). InputError on a size mismatch.
Shell build_shell(const SurfaceMesh& input, const ExtrusionDirections& directions,
                  const ShellOptions& options, ShellStats& stats, const ProgressFn& progress = {});

}  // namespace curvefem::meshing::shell
