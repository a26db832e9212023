// SCAF in 3D: deforming a closed surface without self-intersection, with a tetrahedral scaffold
// (thesis §3.2.3 and Figs. 3.9–3.10).
//
// The solid bounded by the surface is tetrahedralized once (the object; its rest shape is the
// input, optionally scaled by `grow`) and the space between the surface and a
// fixed box around it is tetrahedralized every iteration (the scaffold; its rest shape is its
// current shape). Both meshes share the surface vertices and together tile the box; so while every
// tet of both stays positively oriented, the object's map is injective and the surface cannot
// meet itself (local injectivity on a tiling of a fixed domain implies global bijectivity). Each
// iteration:
//   1. rebuild the scaffold between the box and the current surface (meshing/tetfill, Gmsh) when
//      the moved one has degraded (`rebuild_quality`; every iteration in the thesis); where Gmsh
//      fails (surfaces closer than its boundary recovery handles) the previous
//      scaffold, moved with the last step and still positive, is kept;
//   2. objective E = E_M + λ Σ_S (D(J_t) − 6) + w Σ_c ‖x_c − y_c‖² / L² (+ the surface ARAP term
//      of `arap_weight`), with E_M the
//      volume-weighted mean symmetric Dirichlet energy of the object (≥ 6, 6 for a rigid motion
//      of the rest shape), λ = scaffold_weight · E_M / |S|, y_c the positional targets, L the
//      box diagonal;
//   3. SLIM proxy Σ c_t ‖W_t (J_t(x) − R_t)‖²_F + the constraint term (+ ARAP's global step, its
//      rotations those of x_k): a sparse SPD system in the
//      free coordinates (box corners fixed), CHOLMOD supernodal Cholesky;
//   4. flip-free line search along d = x* − x: t ≤ 0.8 × the first root in (0, 1.25] of every
//      tet's volume (a cubic in t), t ≤ 1, then halving until Armijo holds on E.
// Stops when the relative decrease of E is below `tolerance`, after `max_iterations`, or when no
// step lowers E. The guarantee is checked independently of this code: `verify_scaf3d` (exact
// orientation of every tet and the tiling's boundary chains) and meshing/check's exact
// self-intersection count of the surface.
// Not done (thesis): local re-meshing of the scaffold instead of a rebuild; the mean conformalized
// flow that removes self-intersections of genus-0 inputs.
#pragma once

#include <Eigen/Core>
#include <functional>
#include <string>
#include <vector>

#include "meshing/core/surface_mesh.hpp"

namespace curvefem::meshing::param {

struct PositionTarget {
  int vertex = -1;         ///< surface vertex
  Eigen::Vector3d target;  ///< where it should go
};

struct Deform3dIteration {
  int iteration = 0;
  double energy = 0;        ///< E_M (≥ 6)
  double objective = 0;     ///< E at the accepted step
  double target_error = 0;  ///< max ‖x_c − y_c‖ / L over the targets
  double arap = 0;          ///< the ARAP term / w_A (relative; 0 at a rigid motion of the rest)
  double step = 0, max_step = 0;
  int backtracks = 0;
  double min_singular = 0, max_singular = 0;  ///< over object tets
  double min_volume_rel = 0;                  ///< min tet volume (object and scaffold) / L³
  int scaffold_tets = 0;
  /// Scaffold tets whose rest was the ε regular tet (Deform3dOptions::replace_slivers), and
  /// whether the step was taken with them (false: redone with every rest its current shape).
  int slivers = 0;
  bool slivers_kept = false;
  bool scaffold_rebuilt = false;  ///< false: kept (good enough, or Gmsh failed)
  /// The worst shape of a scaffold tet after the step: min over them of 6√2 V / ℓ_rms³ (1 for
  /// the regular tet, 0 when flat).
  double scaffold_min_quality = 0;
  /// The same of the last rebuilt scaffold when it was built (rebuild_quality's reference).
  double scaffold_reference_quality = 0;
  double seconds = 0, scaffold_s = 0, assemble_s = 0, solve_s = 0, line_search_s = 0;
};

struct Deform3dOptions {
  int max_iterations = 50;
  double tolerance = 1e-5;        ///< on the relative decrease of the objective E
  double scaffold_weight = 0.01;  ///< λ = scaffold_weight · E_M / |S|
  double target_weight = 1e4;     ///< w of the positional targets (per target, distances / L)
  /// w_A of the surface ARAP term toward the rest pose (Sorkine and Alexa 2007; thesis Fig. 3.9's
  /// way back): w_A Σ_i Σ_{j ∈ N(i)} ‖(x_i − x_j) − R_i (y_i − y_j)‖² / Σ_i Σ_j ‖y_i − y_j‖², over
  /// the surface's directed edges with uniform weights, R_i the rotation closest to the vertex's
  /// edge covariance. Rotation-invariant per vertex: a part that cannot return to its rest
  /// position keeps its rest shape. 0: off.
  double arap_weight = 0;
  /// The ARAP rest positions y (#V × 3); empty: the input surface scaled by `grow`.
  Eigen::MatrixXd arap_rest;
  double grow = 1.0;  ///< rest shape = the input scaled by this (no centre: E is rigid-invariant)
  /// box: the bounding box of the input and the targets, widened on every side by
  /// (box_scale − 1) / 2 × its longest extent
  double box_scale = 2.0;
  int box_divisions = 4;  ///< grid of each box side (quads split in two)
  double armijo = 1e-4;
  /// > 0: the scaffold is rebuilt only when the moved one has a tet whose shape 6√2 V / ℓ_rms³
  /// fell below this × that of the last rebuild's worst tet; otherwise the moved scaffold (a
  /// positive tiling, its rest its current shape as after a rebuild) is kept. 0: rebuilt every
  /// iteration, as in the thesis. Measured on 6 inputs (benchmarks/results/deform.md): at 0.5,
  /// 5 of 13 to 24 of 29 rebuilds skipped, whole runs 0.25–0.52× the time, final objectives
  /// within 0.25% (lower on spot and bunny).
  double rebuild_quality = 0.5;
  /// Degeneracy prevention (thesis §3.2.2, as in 2-D): a scaffold tet whose volume is below ε =
  /// l³ / 16 (l = the surface's shortest edge now; about half the volume of the regular tet of
  /// edge l) gets the regular tet of volume ε as its rest instead of its current shape, so the
  /// scaffold pushes back where two sheets of the surface come close. A step must then lower E
  /// (Armijo) without raising E_M; when none does, the iteration is redone with every rest its
  /// current shape. false: every rest is the current shape.
  bool replace_slivers = false;
  /// Called with each iteration's statistics and the surface vertices (#V × 3).
  std::function<void(const Deform3dIteration&, const Eigen::MatrixXd&)> on_iteration;
};

struct Deform3dResult {
  Eigen::MatrixXd V;  ///< deformed surface vertices (the input's faces)
  /// The final tiling: all vertices (surface first, then object Steiner points, box, scaffold
  /// Steiner points), the object's tets and the scaffold's, and the box (its vertices' rows and
  /// its outward faces).
  Eigen::MatrixXd X;
  Eigen::MatrixXi object_tets, scaffold_tets, box_faces;
  std::vector<Deform3dIteration> history;
  std::string stop_reason;  ///< "tolerance", "iterations", "line search"
  double seconds = 0;
  int scaffold_failures = 0;  ///< iterations whose scaffold Gmsh could not rebuild
  int scaffold_kept = 0;      ///< iterations that kept the moved scaffold (rebuild_quality)
};

/// Deforms the closed outward surface toward the targets (and/or the grown rest shape) without
/// ever letting a tet of the object or the scaffold invert. Throws InputError for a bad target
/// (vertex out of range, non-finite), MeshingError when the initial object or scaffold cannot be
/// tetrahedralized, SolverError when a factorisation fails.
Deform3dResult scaf3d_deform(const SurfaceMesh& surface, const std::vector<PositionTarget>& targets,
                             const Deform3dOptions& options = {});

/// Independent check of a result: exact orientation of every object and scaffold tet, each mesh's
/// boundary chain (object: the surface; scaffold: the box and the reversed surface), and the
/// volumes (object + scaffold = box). Uses meshing/tetfill's verifier (exact CGAL predicates).
struct Deform3dCheck {
  long long non_positive_tets = 0;
  long long boundary_mismatches = 0;  ///< missing, extra or badly used faces over both meshes
  double volume_error_rel = 0;        ///< |V_object + V_scaffold − V_box| / V_box
  bool ok() const { return non_positive_tets == 0 && boundary_mismatches == 0; }
};
Deform3dCheck verify_scaf3d(const SurfaceMesh& input, const Deform3dResult& result);

/// Positional targets from a text file: "vertex x y z" per line (0-based vertex), '#' comments.
/// InputError naming file:line for a malformed line or a vertex outside [0, num_vertices).
std::vector<PositionTarget> read_target_file(const std::string& path, int num_vertices);

}  // namespace curvefem::meshing::param
