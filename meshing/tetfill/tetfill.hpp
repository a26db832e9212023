// Boundary-preserving tetrahedralization of the inside of a closed triangle surface
// (DESIGN.md §1: "tetrahedralize inside the shell's bottom surface, boundary untouched"; also the
// dense baseline, where the dense input itself is filled and φ = identity).
//
// Input: V #V × 3, F #F × 3 (0-based), a closed, edge-manifold surface oriented outward
// (counter-clockwise seen from outside) and free of self-intersections. Several components are
// allowed: disjoint solids, and nested shells whose inner shell is oriented inward (a cavity);
// orientations must alternate with nesting depth (checked with winding numbers).
// Self-intersections are not checked here (meshing/check does that); gmsh's boundary recovery
// usually fails on them ("PLC Error"), but see verify_tetfill for what the check cannot see.
//
// Output guarantees (checked by verify_tetfill before fill_interior returns, else MeshingError):
//   - V.topRows(#V_in) == V_in bit for bit; interior (Steiner) vertices follow, none lies on the
//     boundary: the boundary faces of T are exactly F.
//   - T is #T × 4, every tet positively oriented: det(x1 - x0, x2 - x0, x3 - x0) > 0 (exact).
//   - the faces used by one tet are exactly the triangles of F with the same orientation (taken
//     outward from the tet); every other face is used by two tets with opposite orientations.
//   - Σ tet volumes equals the enclosed volume.
// Unreferenced input vertices are kept in V (rows < boundary_vertices) but used by no tet.
//
// Engine: Gmsh 4.8 3D Delaunay (Mesh.Algorithm3D = 1) on a discrete surface that is not remeshed,
// with gmsh's tet optimization (which only moves/swaps interior entities). gmsh is global state:
// calls are serialized through io::GmshSession.
#pragma once

#include <Eigen/Core>

namespace curvefem::meshing::tetfill {

struct TetFillOptions {
  /// Interior target size relative to the local boundary edge length (mean length of the edges at
  /// the nearest boundary vertex). 1 = gmsh's own extension of the boundary sizes.
  double size_factor = 1.0;
  bool optimize = true;  ///< gmsh tet optimization (Mesh.Optimize); boundary entities never move
  int threads = 1;       ///< gmsh General.NumThreads (the 3D Delaunay itself is serial in 4.8)
  /// Run gmsh in a forked child process. Gmsh 4.8's boundary recovery can fail an assertion
  /// (abort) on near-degenerate surfaces; isolated, that becomes a MeshingError the caller can
  /// handle instead of killing the process. The child runs gmsh on one thread.
  bool isolate = true;
  /// Report the result at debug level instead of info (for callers that fill many times).
  bool quiet = false;
};

struct TetFillResult {
  Eigen::MatrixXd V;          ///< #V × 3: input vertices first (bit-identical), then interior
  Eigen::MatrixXi T;          ///< #T × 4, positively oriented
  int boundary_vertices = 0;  ///< n: V.topRows(n) == input V exactly
  double seconds = 0;         ///< wall time of fill_interior (gmsh + read-back + verification)
  double gmsh_seconds = 0;    ///< of which gmsh mesh generation
};

/// Fills the inside of the closed outward surface (V, F).
/// Throws InputError for an invalid surface (index out of range, repeated index, open boundary
/// edge, non-manifold or inconsistently oriented edge, non-positive enclosed volume, non-finite
/// coordinate), naming the face or vertex. Throws MeshingError "tetfill: <stage> failed: ..." when
/// gmsh fails (boundary recovery, no tets) or its result does not keep the boundary exactly.
TetFillResult fill_interior(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F,
                            const TetFillOptions& options = {});

/// Independent check of a TetFillResult against its input (no gmsh; exact CGAL orient3d).
/// Assumes the input has no self-intersection: then positive tets whose boundary chain is F tile
/// the inside exactly once. (Two overlapping outward solids would pass with the overlap covered
/// twice; fill_interior rejects nested outward shells, meshing/check rejects overlaps.)
struct TetFillVerification {
  int tets = 0;
  int non_positive_tets = 0;        ///< exact orient3d ≤ 0, or an index out of range
  int missing_boundary_faces = 0;   ///< triangles of F that are not a boundary face of T (oriented)
  int extra_boundary_faces = 0;     ///< boundary faces of T that are not in F
  int bad_interior_faces = 0;       ///< faces used by > 2 tets or twice with the same orientation
  int moved_boundary_vertices = 0;  ///< rows < #V_in differing from the input (or missing)
  double enclosed_volume = 0;       ///< Σ over F (outward) of the signed cone volumes
  double tet_volume = 0;            ///< Σ over T of the tet volumes
  double volume_error_rel = 0;      ///< |tet_volume − enclosed_volume| / |enclosed_volume|
  /// All counts zero and the volumes agree to 1e-9 relative (floating sums; exactness is in the
  /// counts: positive tets whose boundary chain is F cover the inside exactly once).
  bool valid() const {
    return tets > 0 && non_positive_tets == 0 && missing_boundary_faces == 0 &&
           extra_boundary_faces == 0 && bad_interior_faces == 0 && moved_boundary_vertices == 0 &&
           volume_error_rel <= 1e-9;
  }
};

TetFillVerification verify_tetfill(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F,
                                   const TetFillResult& result);

}  // namespace curvefem::meshing::tetfill
