// SCAF: bijective 2D parameterization with a scaffold (thesis chapter 3, §3.2.1–3.2.2).
//
// Minimises the symmetric Dirichlet energy of the charts (area-weighted mean over chart
// triangles, rest shape = the 3D triangle; ≥ 4, = 4 for an isometry) while every triangle of the
// charts *and* of a scaffold filling a box around them stays positively oriented, which makes
// the map bijective (locally injective, boundaries non-overlapping; several charts never
// overlap each other). Each iteration:
//   1. rebuild the scaffold (scaffold.hpp) from the current UV positions; its rest shape is its
//      current shape ("isometric to the current iteration"), slivers of area < ε replaced by an
//      equilateral triangle of area ε, ε = l²/4 with l the shortest chart boundary edge;
//   2. objective E = E_M + λ Σ_S (D(J_f) − 4), λ = scaffold_weight · E_M / |S| (E_M at the start
//      of the iteration; thesis: 1/100);
//   3. SLIM proxy: Σ c_f ‖W_f (J_f(x) − R_f)‖²_F (c_f = A_f / A_M on charts, λ on the scaffold),
//      a sparse SPD system in the free UV coordinates (box boundary fixed), solved by CHOLMOD
//      (supernodal Cholesky, Eigen's CholmodSupport);
//   4. flip-free line search along d = x* − x: t ≤ 0.8 × the first root of every triangle's
//      signed area (a quadratic in t), t ≤ 1, then backtracking (halving) until Armijo holds on E
//      and E_M did not increase (so E_M is monotone). If no step qualifies, the iteration is
//      redone with no sliver replacement (then E_S(x_k) = 0, ∇E_S(x_k) = 0 and d is a descent
//      direction of E_M); if that fails too, the optimisation stops ("line search").
// Stops when the relative decrease of E_M is below `tolerance` or after `max_iterations`.
// Then, optionally (`newton_iterations` > 0), the SLIM result is the warm start of a projected
// Newton phase (thesis §3.3: "a few iterations minimizing the quadratic proxy and then switch to
// a traditional Newton method until numerical convergence", after Rabinovich et al. 2017): the
// same scaffold rebuild (no sliver replacement, so E_S(x_k) = 0), the exact gradient of E and its
// Hessian with each triangle's 4 × 4 Hessian in J projected onto the positive semi-definite
// cone (symmetric_dirichlet_hessian), the same CHOLMOD solve, flip-free bound and line search
// (from t = min(1, 0.8 × the first root)). It stops when the relative decrease of E_M is below
// `newton_tolerance`, when no step lowers E, or after `newton_iterations`.
#pragma once

#include <Eigen/Core>
#include <functional>
#include <string>
#include <vector>

#include "meshing/param/cut_mesh.hpp"
#include "meshing/param/scaffold.hpp"

namespace curvefem::meshing::param {

/// One iteration (iteration 0 = the initial map, before any step).
struct IterationStats {
  int iteration = 0;
  double energy = 0;     ///< E_M: area-weighted mean symmetric Dirichlet of the charts (≥ 4)
  double objective = 0;  ///< E_M + λ E_S at the accepted step (rest of the scaffold: x_k)
  double lambda = 0;     ///< scaffold weight λ of this iteration
  double step = 0;       ///< accepted line-search parameter t (0 for iteration 0)
  double max_step = 0;   ///< flip-free bound (0.8 × first root, ≤ 1)
  int backtracks = 0;
  int slivers = 0;            ///< scaffold triangles whose rest was the ε equilateral
  int fallbacks = 0;          ///< 1 if the iteration was redone without the sliver replacement
  double regularisation = 0;  ///< δ of the proximal term the factorisation needed (0: none)
  double min_singular = 0;    ///< over chart triangles, after the step
  double max_singular = 0;
  int scaffold_vertices = 0, scaffold_faces = 0;
  double seconds = 0;  ///< wall time of this iteration (scaffold + assembly + solve + search)
  double scaffold_s = 0, assemble_s = 0, solve_s = 0, line_search_s = 0;
  bool newton = false;       ///< a projected Newton iteration (else SLIM)
  double gradient_norm = 0;  ///< Newton: ‖∇E‖ over the free coordinates before the step
};

struct ScafOptions {
  int max_iterations = 50;
  double tolerance = 1e-6;  ///< stop when (E_M(k−1) − E_M(k)) / E_M(k−1) < tolerance
  /// Projected Newton iterations after SLIM (0: none). 10 by default: on the knight cut to a
  /// disk, SLIM's 50 iterations end 3.9% above the minimum and 10 Newton iterations below the
  /// 300-iteration SLIM reference (benchmarks/results/param.md).
  int newton_iterations = 10;
  double newton_tolerance = 1e-12;  ///< the Newton phase's stop on the relative decrease of E_M
  double scaffold_weight = 0.01;    ///< λ = scaffold_weight · E_M / |S|
  double armijo = 1e-4;
  ScaffoldOptions scaffold;
  /// Called after every iteration (and for iteration 0) with the chart UV positions (#U × 2) and
  /// that iteration's scaffold (for iteration 0: the first one).
  std::function<void(const IterationStats&, const Eigen::MatrixXd& uv, const Scaffold&)>
      on_iteration;
};

struct ScafResult {
  Eigen::MatrixXd uv;                   ///< #U × 2
  std::vector<IterationStats> history;  ///< iteration 0 .. n
  bool converged = false;
  std::string stop_reason;         ///< "tolerance", "iterations", "line search"
  int newton_iterations = 0;       ///< Newton iterations taken (accepted steps)
  std::string newton_stop_reason;  ///< "tolerance", "iterations", "line search"; "" without
  double seconds = 0;              ///< total, excluding on_iteration callbacks
  std::string solver = "cholmod-supernodal-llt";
};

/// Optimises the bijective map `uv0` (#U × 2, e.g. tutte_layout(cut)) of the charts of `cut`.
/// Throws InputError if uv0 has a non-positive chart triangle, MeshingError if its chart
/// boundaries overlap (the scaffold cannot be built), SolverError if a factorisation fails.
ScafResult scaf_optimize(const CutMesh& cut, const Eigen::MatrixXd& uv0,
                         const ScafOptions& options = {});

/// E_M of a map: area-weighted mean symmetric Dirichlet energy over the chart triangles.
double chart_energy(const CutMesh& cut, const Eigen::MatrixXd& uv);

}  // namespace curvefem::meshing::param
