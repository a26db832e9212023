#pragma once
// An opt-in repair of a closed surface's tiniest edges (`curvefem check --merge-short-edges L -o
// OUT`): each edge shorter than a length is collapsed onto one of its two ends, which keeps its
// position, so the repaired surface's vertices are a subset of the input's and every input vertex
// has one repaired vertex (itself or the end it was merged into, at most that length away).
//
// Why: a needle whose short edge is far below ε is a floor under the curved mesh's elements
// (pipeline/input_floors.hpp): the shell's coarsening cannot collapse it (CGAL's femur.off: input
// vertices 2 and 73, 1e-4 apart at a crease tip, every collapse refused by the new prisms'
// positivity), so the boundary keeps the needle and the tet on it is the mesh's worst (curved
// MIPS 1.6e4, scaled Jacobian 4.5e-3 at K = 3). Merged first, the same mesh meets issue 21's
// quality goal (7.2e3, 1.8e-2). The price is the bijection: the curved mesh then maps to the
// repaired surface, and an input vertex merged away takes its end's place.
//
// A collapse is made only where it keeps the surface a closed 2-manifold (the link condition:
// the edge's two ends share exactly the two vertices opposite it) and turns no surviving face by
// more than `max_normal_turn_deg` nor makes it degenerate. Edges are taken shortest first, and of
// the two ends the one whose faces turn least is kept. The result is not checked for
// self-intersections here: `curvefem check` runs the full check on it.
#include <array>
#include <vector>

#include "meshing/core/surface_mesh.hpp"

namespace curvefem::check {

struct MergeShortEdgesOptions {
  double max_length = 0;              ///< absolute; edges strictly shorter are candidates
  double max_normal_turn_deg = 30.0;  ///< per surviving face of a collapse
};

struct MergedEdge {
  int removed = -1, kept = -1;  ///< input vertex ids
  double length = 0;
};

struct MergeShortEdgesResult {
  SurfaceMesh mesh;  ///< the repaired surface (vertices renumbered, input order kept)
  /// Per input vertex: its repaired vertex (itself or the one it was merged into).
  std::vector<int> vertex_map;
  /// Per repaired face: the input face it is (faces keep their input order and tags).
  std::vector<int> face_origin;
  std::vector<MergedEdge> merged;  ///< in the order made
  int candidates = 0;              ///< input edges shorter than max_length
  int refused = 0;                 ///< candidates left as they are (link condition or normals)
  double max_moved = 0;            ///< the longest merged edge
};

MergeShortEdgesResult merge_short_edges(const SurfaceMesh& input,
                                        const MergeShortEdgesOptions& options);

}  // namespace curvefem::check
