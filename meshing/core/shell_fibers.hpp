#pragma once
// The fibers of a coarse shell at the middle surface: everything the pull-back P_T(f, u, v) at
// h = 0 of a shell (thesis §4.4, meshing/shell/projection.hpp) needs, without the shell code, so
// the BoundaryMap φ is evaluable in both directions from a saved `mesh` directory (DESIGN.md §2,
// "BoundaryMap φ"; issue 23).
//
// A prism f has base/mid/top corners at the vertices of faces.row(f). Faces are stored rotated so
// that the smallest vertex id comes first (the rotation the shell projection and the boundary
// triangles of φ use: (u, v) of boundary triangle f are barycentric coordinates in this order);
// orientation is the shell's. The fiber of (f, u, v) is the polyline through the rising facets of
// the canonical 3-tet split of both half-prisms (meshing/core/prism_split.hpp); a vertex with
// base = mid = top is a pinch point (a zero-length pillar).
//
// The fibers cross the *reference copy* of the input: the input itself, except the vertices listed
// in `reference_vertices`, which sit at `reference_positions` (feature chains: input vertices
// snapped onto straight coarse feature edges, thesis §5.3). A crossing with reference face t at
// barycentric coordinates b stands for the input point of face t at the same b.
//
// `candidate_faces[candidate_offsets[f] .. candidate_offsets[f + 1])`: input faces, increasing,
// whose (reference) triangles may meet prism f — a superset of those its fibers cross, computed
// when the shell is saved (meshing/shell/fibers_of.hpp, exact box queries on the input), so
// evaluation (fiber_projection.hpp) is a local search.
#include <Eigen/Core>
#include <span>
#include <vector>

namespace curvefem {

struct ShellFibers {
  Eigen::MatrixXd base, mid, top;       // #shell vertices × 3: the layers
  Eigen::MatrixXi faces;                // #prisms × 3, smallest vertex id first
  std::vector<int> reference_vertices;  // input vertices moved in the reference copy, increasing
  Eigen::MatrixXd reference_positions;  // #reference_vertices × 3: where they are there
  std::vector<int> candidate_offsets;   // #prisms + 1 (empty when there are no prisms)
  std::vector<int> candidate_faces;
  // Built on a refinement of the input (the curved mesher's shape and thin refinements,
  // beveling): the fibers cross the refined surface, whose vertices are the input's and then
  // `surface_points` (ids #input V + i) and whose faces are `surface_faces`; candidate faces and
  // reference vertices refer to it. Refined face t lies in input face surface_parent[t], its
  // corner k at barycentric coordinates surface_bary(t, 3k .. 3k + 2) there. Empty: the input.
  Eigen::MatrixXd surface_points;  // #added × 3
  Eigen::MatrixXi surface_faces;   // #refined F × 3
  std::vector<int> surface_parent;
  Eigen::MatrixXd surface_bary;  // #refined F × 9

  bool refined() const { return surface_faces.rows() > 0; }

  int num_prisms() const { return static_cast<int>(faces.rows()); }
  int num_vertices() const { return static_cast<int>(mid.rows()); }
  /// The input faces prism f's fibers may cross (increasing).
  std::span<const int> candidates(int f) const {
    return {candidate_faces.data() + candidate_offsets[f],
            candidate_faces.data() + candidate_offsets[f + 1]};
  }
  /// Is shell vertex v a pinch point (base = mid = top)?
  bool pinched(int v) const { return base.row(v) == mid.row(v) && top.row(v) == mid.row(v); }
};

/// Throws InputError naming the first structural defect: layer sizes, face ids, a face not rotated
/// to its smallest id, candidate offsets, the refinement's sizes, and (when input_vertices /
/// input_faces ≥ 0) reference vertex ids and candidate face ids outside the (refined) input.
void validate_structure(const ShellFibers& fibers, int input_vertices = -1, int input_faces = -1);

/// Bit-for-bit equality of every member (a read file against the written data).
bool identical(const ShellFibers& a, const ShellFibers& b);

}  // namespace curvefem
